#!/usr/bin/env bash
# Side by side: TetGen (tetgen -pq1.414, a quality Delaunay mesh that conforms to the surface) and
# tetcut embed (a BCC lattice with the surface embedded) on the same closed scans from Debian's
# libcgal-demo. Prints a Markdown table: time, tet count, smallest dihedral angle and smallest
# altitude of the simulation mesh (the explicit time step scales with the smallest altitude).
#
#   bench/tetgen_compare.sh [TETCUT] [CUBES]     (defaults: build/release/bin/tetcut, 24)
set -euo pipefail
TETCUT=$(realpath "${1:-build/release/bin/tetcut}")
CUBES=${2:-24}
ARCHIVE=/usr/share/doc/libcgal-dev/data.tar.gz
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
scans="femur knot1 bunny00 armadillo"
members=""
for s in $scans; do members="$members data/meshes/$s.off"; done
tar xzf "$ARCHIVE" $members

now() { date +%s.%N; }
elapsed() { /usr/bin/python3 -c "import sys; print(float(sys.argv[2]) - float(sys.argv[1]))" "$1" "$(now)"; }
# field FILE KEY: one key of `tetcut info --json FILE`.
field() { "$TETCUT" info --json "$1" | /usr/bin/python3 -c "import json,sys; print(json.load(sys.stdin)['$2'])"; }
row() {  # row SCAN TOOL SECONDS MESH
  printf '| %s | %s | %.2f | %s | %.2f | %.3g |\n' "$1" "$2" "$3" "$(field "$4" tets)" \
    "$(field "$4" min_dihedral_degrees)" "$(field "$4" min_altitude)"
}

echo "| Surface | Mesher | Seconds | Tets | Min dihedral (deg) | Min altitude |"
echo "| --- | --- | --- | --- | --- | --- |"
for s in $scans; do
  cp "data/meshes/$s.off" "$s.off"
  start=$(now)
  if tetgen -pq1.414Q "$s.off" > tetgen.log 2>&1; then
    row "$s" "tetgen -pq1.414" "$(elapsed "$start")" "$s.1.ele"
  else
    echo "| $s | tetgen -pq1.414 | failed: $(tail -1 tetgen.log) | | | |"
  fi
  start=$(now)
  "$TETCUT" embed "$s.off" --cells "$CUBES" --out-mesh "$s.vtu" > embed.log
  row "$s" "tetcut embed --cells $CUBES" "$(elapsed "$start")" "$s.vtu"
done
