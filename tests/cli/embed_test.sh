#!/usr/bin/env bash
# tetcut embed: a closed surface carved out of a lattice, an open one with a choice of material,
# the report's keys, and clear errors on bad surfaces and options.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

expect_exit 0 "$TETCUT" embed --help
expect_stdout "--keep"

# A closed box [0.1, 0.9]^3 as an OBJ (outward), embedded in a lattice of 8 cubes along its side.
cat > box.obj <<'OBJ'
v 0.1 0.1 0.1
v 0.9 0.1 0.1
v 0.1 0.9 0.1
v 0.9 0.9 0.1
v 0.1 0.1 0.9
v 0.9 0.1 0.9
v 0.1 0.9 0.9
v 0.9 0.9 0.9
f 1 3 2
f 2 3 4
f 5 6 7
f 6 8 7
f 1 2 5
f 2 6 5
f 3 7 4
f 4 7 8
f 1 5 3
f 3 5 7
f 2 4 6
f 4 8 6
OBJ
expect_exit 0 "$TETCUT" embed box.obj --cells 8 --out-mesh box.vtu --out-surface box_surface.obj --report box.json
expect_stdout "pieces           1"
expect_stdout "peak memory"
json_check box.json 'j["pieces"] == 1 and abs(j["volume"] - 0.512) < 1e-12 and j["surface"]["balanced"]'
json_check box.json 'abs(j["surface"]["area"] - 6 * 0.64) < 1e-12 and j["tets_out"] < j["tets_in"]'
json_check box.json 'set(j["timings"]) == {"read", "lattice", "check", "insert", "classify", "copies", "pieces", "surface", "write"}'
json_check box.json 'j["peak_memory_bytes"] > 0 and j["embed"]["keep"] == "inside" and j["embed"]["surface_balanced"]'
json_check box.json 'abs(j["lattice_spacing"] - 0.1) < 1e-12 and j["embed"]["tets_with_material"] == j["tets_out"]'
# The written mesh holds only copies with material; the surface reads back closed.
expect_exit 0 "$TETCUT" info --json box_surface.obj
json_check out.txt 'j["balanced"] and abs(j["enclosed_volume"] - 0.512) < 1e-12'
"$PYTHON" - box.vtu <<'PY'
import sys, meshio, numpy
m = meshio.read(sys.argv[1])
fraction = numpy.concatenate(m.cell_data["material_fraction"])
assert (fraction > 0).all() and abs(numpy.concatenate(m.cell_data["material_volume"]).sum() - 0.512) < 1e-12
PY

# The same box with one triangle turned over: not closed, and the message says why.
sed 's/^f 1 3 2$/f 1 2 3/' box.obj > flipped.obj
expect_exit 2 "$TETCUT" embed flipped.obj --cells 4 --out-mesh never.vtu
expect_stderr "flipped.obj"
expect_stderr "not closed: 3 edges"
expect_stderr "disagree on orientation"
[[ ! -e never.vtu ]] || fail "a failed embedding wrote its output"

# Open: the box without its top. Inside is refused; the largest piece or a point's piece works.
grep -v '^f [56] ' box.obj > open.obj
expect_exit 2 "$TETCUT" embed open.obj --cells 4
expect_stderr "edges are used more often in one direction"
expect_exit 0 "$TETCUT" embed open.obj --cells 8 --keep largest --report open.json
json_check open.json 'j["pieces"] == 1 and j["embed"]["keep"] == "largest" and not j["embed"]["surface_balanced"]'
expect_exit 0 "$TETCUT" embed open.obj --cells 8 --keep point 0.5 0.5 0.5 --report point.json
json_check point.json 'j["pieces"] == 1 and j["embed"]["keep"] == "point"'
expect_exit 2 "$TETCUT" embed open.obj --cells 8 --keep point 0.5 0.5 0.1
expect_stderr "lies on the cut surface"

# Into a given mesh.
expect_exit 0 "$TETCUT" grid --cells 4 4 4 -o cube.vtu
expect_exit 0 "$TETCUT" embed box.obj --mesh cube.vtu --report given.json
json_check given.json 'j["tets_in"] == 320 and abs(j["volume"] - 0.512) < 1e-12 and j["mesh"] == "cube.vtu"'

# Bad options and inputs.
expect_exit 2 "$TETCUT" embed box.obj --keep sideways
expect_stderr "unknown choice 'sideways'"
expect_exit 2 "$TETCUT" embed box.obj --keep point 1 2
expect_stderr "needs three coordinates"
expect_exit 2 "$TETCUT" embed box.obj --spacing 0.1 --cells 4
expect_exit 2 "$TETCUT" embed box.obj --spacing -1
expect_stderr "positive"
expect_exit 2 "$TETCUT" embed box.obj --cells 0
expect_stderr "at least 1"
printf 'v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n' > nan.obj
expect_exit 2 "$TETCUT" embed nan.obj
expect_stderr "nan.obj"
expect_exit 2 "$TETCUT" embed box.obj --out-mesh box.obj
expect_stderr "overwrite the input"
echo "embed CLI: all checks passed"
