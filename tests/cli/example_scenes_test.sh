#!/usr/bin/env bash
# The example scenes give the results they gave before the simulator was made fast (golden data
# from commit 8e25780 in tests/data/golden/example_scenes.json): the same pieces, tets and nodes,
# spring gaps within 1e-3 relative, and the final bounding box within 1e-3 of its diagonal.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

for scene in fig8-slinky fig3-progressive-tet fig5-cookie-cutter lip-incision; do
  expect_exit 0 "$TETCUT" sim "$EXAMPLES/$scene.json" -o "$scene"
  "$PYTHON" - "$DATA/golden/example_scenes.json" "$scene" <<'PY' || fail "$scene differs from its golden results"
import json, math, sys
golden = json.load(open(sys.argv[1]))["scenes"][sys.argv[2]]
now = json.load(open(sys.argv[2] + "/summary.json"))
for key in ("pieces", "tets", "nodes", "steps"):
    assert now[key] == golden[key], (key, now[key], golden[key])
for key in ("spring_gap_when_attached", "spring_gap_final"):
    assert abs(now[key] - golden[key]) <= 1e-3 * abs(golden[key]) + 1e-12, (key, now[key], golden[key])
box, expected = now["final_box"], golden["final_box"]
diagonal = math.dist(expected[:3], expected[3:])
worst = max(abs(a - b) for a, b in zip(box, expected))
assert worst <= 1e-3 * diagonal, ("final box", box, expected, worst / diagonal)
print(sys.argv[2], "final box within", worst / diagonal, "of its diagonal")
PY
done
