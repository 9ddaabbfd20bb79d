#!/usr/bin/env bash
# tetcut sim: a scene runs and writes its frames and series; the example scenes load and start;
# a bad scene gets a message naming the file and the key, and nothing is written.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

expect_exit 0 "$TETCUT" sim --help
expect_stdout "--frames"

cat > drop.json <<'JSON'
{
  "mesh": {"grid": {"box": [0, 0, 0.1, 1, 1, 1.1], "cells": [2, 2, 2]}},
  "material": {"youngs_modulus": 1e5, "density": 100},
  "time": {"dt": 0.01, "duration": 0.2, "output_every": 0.05},
  "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}],
  "cuts": [{"time": 0.02, "plane": {"centre": [0.5, 0.5, 0.5], "normal": [1, 0, 0.1], "size": 3}}]
}
JSON
expect_exit 0 "$TETCUT" sim drop.json -o out
expect_stdout "frames           5"
expect_stdout "cuts             1"
for f in 0 1 2 3 4; do
  [[ -s out/mesh_000$f.vtu && -s out/surface_000$f.vtp ]] || fail "frame $f is missing"
done
grep -q 'file="surface_0004.vtp"' out/surface.pvd || fail "the surface series lacks its last frame"
json_check out/summary.json 'j["frames"] == 5 and j["steps"] == 20 and j["pieces"] == 2 and j["unconverged_steps"] == 0'
# The pieces' volumes in the material add up to the block's; the cut (in world space, once the
# block has fallen about 3 mm) splits it as the plane x = 0.5 - 0.1 (z - 0.5) nearly does, 0.51
# and 0.49 across z in [0.1, 1.1].
json_check out/summary.json 'len(j["piece_volumes"]) == 2 and abs(sum(j["piece_volumes"]) - 1) < 1e-12 and abs(j["piece_volumes"][1] - 0.49) < 1e-3'
# Stage times per step, the residual left, the final box.
json_check out/summary.json 'all(j["ms_per_step"][k] >= 0 for k in ("cut", "surface", "remesh", "step", "total", "median", "p99", "max"))'
json_check out/summary.json 'j["ms_per_step"]["step"] > 0 and j["ms_per_step"]["total"] >= j["ms_per_step"]["step"] and j["ms_per_step"]["max"] >= j["ms_per_step"]["median"]'
json_check out/summary.json 'j["max_residual"] <= 1e-7 and len(j["final_box"]) == 6 and j["final_box"][2] > -0.05 and j["mean_cg_iterations"] > 0'

# --check-intersections: per frame and the maximum in summary.json, and a line of the report.
# The fresh cut is no intersection; landing, the halves' cut faces press into each other (pieces
# are not kept apart yet), which it counts.
expect_exit 0 "$TETCUT" sim drop.json -o checked --check-intersections
expect_stdout "intersections    at most"
json_check checked/summary.json 'len(j["intersecting_pairs"]) == 5 and j["intersecting_pairs"][:3] == [0, 0, 0]'
json_check checked/summary.json 'j["max_intersecting_pairs"] == max(j["intersecting_pairs"]) > 0'
expect_stdout "ms per step"
# The real-time mode: a fixed budget, and the residual it left reported.
sed 's/"obstacles"/"solver": {"mode": "real_time", "max_cg_iterations": 2}, "obstacles"/' drop.json > budget.json
expect_exit 0 "$TETCUT" sim budget.json -o budget
json_check budget/summary.json 'j["mean_newton_iterations"] == 1 and j["mean_cg_iterations"] <= 2 and j["max_residual"] > 0'
# The frames are meshes and surfaces other tools read.
"$PYTHON" - out <<'PY'
import sys, meshio
m = meshio.read(sys.argv[1] + "/mesh_0004.vtu")
assert len(m.points) > 27 and "piece" in m.cell_data
PY
# meshio has no PolyData reader: decode the .vtp's arrays (UInt64 header + data, base64) directly.
"$PYTHON" - out/surface_0004.vtp <<'PY'
import base64, struct, sys, xml.etree.ElementTree as ET
piece = ET.parse(sys.argv[1]).getroot().find("PolyData/Piece")
points, polys = int(piece.get("NumberOfPoints")), int(piece.get("NumberOfPolys"))
def array(name):
    node = [a for a in piece.iter("DataArray") if a.get("Name") == name][0]
    text = node.text.strip()
    size = struct.unpack("<Q", base64.b64decode(text[:12]))[0]
    data = base64.b64decode(text[12:])
    assert len(data) == size
    return data
assert points > 0 and polys > 0
xyz = struct.unpack("<%dd" % (3 * points), array("Points"))
connectivity = struct.unpack("<%dq" % (3 * polys), array("connectivity"))
offsets = struct.unpack("<%dq" % polys, array("offsets"))
assert max(connectivity) < points and min(connectivity) >= 0 and offsets[-1] == 3 * polys
assert min(xyz[2::3]) > -0.05, "the surface went through the ground"
PY
# --frames stops early.
expect_exit 0 "$TETCUT" sim drop.json -o short --frames 2
json_check short/summary.json 'j["frames"] == 3 and j["steps"] == 10'

# (Every example scene runs its first frames, into pictures and an animation, in render_test.sh.)

# A cloth scene: a hanging square cut across by a blade in world space before it moves, so exactly
# where a rest-space cut at z = 7/16 would: 8 triangles split, pieces of 9/16 and 7/16; the lower
# one falls. Its frames are the triangle copies and the material, as surfaces.
cat > cloth.json <<'JSON'
{"cloth": {"mesh": {"grid": {"cells": 4, "size": 1, "plane": "xz"}}, "material": {"stretch_stiffness": 2000, "mass_damping": 1}},
 "pin": [{"box": [-1, -1, 0.99, 2, 1, 1.01]}],
 "time": {"dt": 0.01, "duration": 0.2, "output_every": 0.05},
 "cuts": [{"time": 0, "blade": {"poses": [[-1, -1, 0.4375, -1, 1, 0.4375], [2, -1, 0.4375, 2, 1, 0.4375]]}}]}
JSON
expect_exit 0 "$TETCUT" sim cloth.json -o cloth
expect_stdout "cloth            40 triangle copies of 32 triangles, 35 nodes, 2 pieces"
for f in 0 1 2 3 4; do
  [[ -s cloth/mesh_000$f.vtp && -s cloth/surface_000$f.vtp ]] || fail "cloth frame $f is missing"
done
grep -q 'file="mesh_0004.vtp"' cloth/mesh.pvd || fail "the cloth's mesh series lacks its last frame"
json_check cloth/summary.json 'j["cloth"] and j["frames"] == 5 and j["steps"] == 20 and j["cuts_applied"] == 1'
json_check cloth/summary.json 'j["triangles_in"] == 32 and j["triangle_copies"] == 40 and j["nodes"] == 35 and j["pieces"] == 2'
json_check cloth/summary.json 'abs(j["piece_areas"][0] - 0.5625) < 1e-12 and abs(j["piece_areas"][1] - 0.4375) < 1e-12'
json_check cloth/summary.json 'all(j["ms_per_step"][k] >= 0 for k in ("cut", "surface", "remesh", "step", "total", "median", "p99", "max"))'
json_check cloth/summary.json 'j["unconverged_steps"] == 0 and j["final_box"][2] < -0.1 and j["final_box"][5] == 1'
expect_exit 0 "$TETCUT" info --json cloth/mesh_0004.vtp
json_check out.txt 'j["triangles"] == 40'
# What a cloth scene has not is refused by name; --check-intersections is for tets; nothing is written.
sed 's/"pin"/"obstacles": [], "pin"/' cloth.json > bad_cloth.json
expect_exit 2 "$TETCUT" sim bad_cloth.json -o bad_cloth
expect_stderr "obstacles: not in a cloth scene"
[[ ! -e bad_cloth ]] || fail "a rejected cloth scene created its output directory"
expect_exit 2 "$TETCUT" sim cloth.json -o cloth_checked --check-intersections
expect_stderr "cloth scene"
[[ ! -e cloth_checked ]] || fail "a refused run created its output directory"

# Bad scenes: the file and the key are named, nothing is written.
sed 's/"density": 100/"densty": 100/' drop.json > typo.json
expect_exit 2 "$TETCUT" sim typo.json -o typo_out
expect_stderr "typo.json"
expect_stderr "material: unknown key 'densty'"
[[ ! -e typo_out ]] || fail "a rejected scene created its output directory"
printf '{"mesh": {"file": "missing.vtu"}, "time": {"duration": 1}}' > missing.json
expect_exit 2 "$TETCUT" sim missing.json -o never
expect_stderr "missing.vtu"
echo "sim CLI: all checks passed"
