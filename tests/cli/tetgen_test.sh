#!/usr/bin/env bash
# Meshes written by the real TetGen program (.node/.ele and its legacy .vtk) read correctly.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

# Our cube's boundary, as an OFF file TetGen can read, meshed with quality and volume bounds.
"$TETCUT" grid --cells 2 2 2 --box 0 0 0 2 1 1 -o cube.vtu > /dev/null
"$TETCUT" convert cube.vtu cube.off > /dev/null
"$TETGEN" -pq1.414a0.01kQ cube.off > /dev/null
[[ -s cube.1.node && -s cube.1.ele && -s cube.1.vtk ]] || fail "tetgen produced no mesh"
tets=$(head -1 cube.1.ele | awk '{print $1}')
nodes=$(head -1 cube.1.node | awk '{print $1}')
for f in cube.1.ele cube.1.node cube.1.vtk; do
  expect_exit 0 "$TETCUT" info --json "$f"
  cp out.txt info.json
  json_check info.json "j['tets'] == $tets and j['nodes'] == $nodes"
  # TetGen puts Steiner points on the box faces by interpolation, so the volume is 2 up to rounding.
  json_check info.json 'abs(j["volume"] - 2) < 1e-12 and j["bbox"]["max"] == [2, 1, 1]'
  json_check info.json 'j["boundary_faces"] > 0 and j["min_tet_volume"] > 0'
done
# And TetGen's mesh converts to our formats and back unchanged in size.
expect_exit 0 "$TETCUT" convert cube.1.ele again.msh
expect_exit 0 "$TETCUT" info --json again.msh
cp out.txt again.json
json_check again.json "j['tets'] == $tets"
echo "tetgen_test: $tets tets from tetgen read back"
