#!/usr/bin/env bash
# tetcut cut: outputs, the JSON report, warnings, and clear errors on bad input.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

expect_exit 0 "$TETCUT" cut --help
expect_stdout "--out-mesh"

expect_exit 0 "$TETCUT" grid --cells 4 4 4 -o cube.vtu
# z = 0.3 and x = 0.6 as two-triangle squares, in two batches (the second cuts the first's pieces).
printf 'v -1 -1 0.3\nv 2 -1 0.3\nv 2 2 0.3\nv -1 2 0.3\nf 1 2 3\nf 1 3 4\n' > z.obj
printf 'ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0.6 -1 -1\n0.6 2 -1\n0.6 2 2\n0.6 -1 2\n3 0 1 2\n3 0 2 3\n' > x.ply
expect_exit 0 "$TETCUT" cut cube.vtu z.obj x.ply --out-mesh cut.vtu --out-surface cut.obj --report report.json
expect_stdout "pieces           4"
json_check report.json 'j["nodes_in"] == 125 and j["tets_in"] == 320 and j["pieces"] == 4'
json_check report.json 'j["tets_out"] > 320 and j["nodes_out"] > 125'
json_check report.json 'all(abs(a - b) < 1e-12 for a, b in zip(j["piece_volumes"], [0.42, 0.28, 0.18, 0.12]))'
json_check report.json 'abs(j["volume"] - 1) < 1e-12 and j["surface"]["balanced"] and abs(j["surface"]["area"] - 10) < 1e-12'
json_check report.json 'set(j["timings"]) == {"read", "cut", "surface", "write"} and all(t >= 0 for t in j["timings"].values())'
# The outputs read back: the mesh with the reported counts, the surface closed with the same area.
expect_exit 0 "$TETCUT" info --json cut.vtu
cp out.txt mesh.json
python_report() { "$PYTHON" -c "import json; print(json.load(open('report.json'))[\"$1\"])"; }
# Copies are whole tets overlapping in rest space, so their plain volume exceeds the material's.
json_check mesh.json "j['tets'] == $(python_report tets_out) and j['nodes'] == $(python_report nodes_out) and j['volume'] > 1"
expect_exit 0 "$TETCUT" info --json cut.obj
cp out.txt surface.json
json_check surface.json 'j["balanced"] and abs(j["area"] - 10) < 1e-12 and abs(j["enclosed_volume"] - 1) < 1e-12'
# Per-copy fields for viewers, read by an independent reader.
"$PYTHON" - cut.vtu <<'PY'
import sys, meshio, numpy
m = meshio.read(sys.argv[1])
data = {name: numpy.concatenate(values) for name, values in m.cell_data.items()}
assert set(data) >= {"original_tet", "piece", "material_volume", "material_fraction"}, data.keys()
assert data["piece"].min() == 0 and data["piece"].max() == 3
assert data["original_tet"].min() == 0 and data["original_tet"].max() == 319
assert abs(data["material_volume"].sum() - 1) < 1e-12
assert ((data["material_fraction"] > 0) & (data["material_fraction"] <= 1 + 1e-12)).all()
PY
# Medit and Gmsh outputs carry the piece as a label.
expect_exit 0 "$TETCUT" cut cube.vtu z.obj --out-mesh cut.mesh
expect_exit 0 "$TETCUT" cut cube.vtu z.obj --out-mesh cut.msh --msh-version 22
awk '/^Tetrahedra/{getline; n=$1; for(i=0;i<n;i++){getline; print $5}}' cut.mesh | sort -u | tr '\n' ' ' | grep -q "^0 1 $" \
  || fail "Medit references are not the pieces 0 and 1"
expect_exit 0 "$TETCUT" info cut.msh

# Zero-area triangles are skipped with a warning; a cut that misses the mesh is reported.
printf 'v 0 0 0\nv 1 1 1\nv 0.5 0.5 0.5\nv -1 -1 0.6\nv 2 -1 0.6\nv -1 2 0.6\nf 1 2 3\nf 4 5 6\n' > flat.obj
expect_exit 0 "$TETCUT" cut cube.vtu flat.obj
expect_stderr "skipped 1 zero-area triangle"
printf 'v 5 5 5\nv 6 5 5\nv 5 6 5\nf 1 2 3\n' > far.obj
expect_exit 0 "$TETCUT" cut cube.vtu far.obj
expect_stderr "does not reach into the mesh"
expect_stdout "pieces           1"

# World space: the cube sheared by x' = x + 0.5 z, cut by the world plane x' = 0.6, which is the
# rest plane x + 0.5 z = 0.6: pieces 0.65 and 0.35; the deformed surface is the sheared cube's skin
# (four unit faces, two of area sqrt(1.25)) and both sides of a unit square.
"$PYTHON" - <<'PY'
import meshio
m = meshio.read("cube.vtu")
p = m.points.copy()
p[:, 0] += 0.5 * p[:, 2]
meshio.write("sheared.vtu", meshio.Mesh(p, m.cells))
q = m.points.copy()
q[:, 0] *= -1  # a mirror image: every tet inverted
meshio.write("mirrored.vtu", meshio.Mesh(q, m.cells))
PY
printf 'v 0.6 -1 -1\nv 0.6 3 -1\nv 0.6 3 3\nv 0.6 -1 3\nf 1 2 3\nf 1 3 4\n' > x06.obj
expect_exit 0 "$TETCUT" cut cube.vtu x06.obj --deform sheared.vtu --out-surface deformed.obj --write-deformed --report world.json
expect_stdout "placed on the deformed mesh"
json_check world.json 'j["world_space"] and j["pieces"] == 2 and abs(j["piece_volumes"][1] - 0.35) < 1e-12'
expect_exit 0 "$TETCUT" info --json deformed.obj
cp out.txt deformed.json
json_check deformed.json 'j["balanced"] and abs(j["area"] - (4 + 2 * 1.25 ** 0.5 + 2)) < 1e-12'
# Inverted tets are not cut there, with a warning; a deformed file of another mesh is an error.
printf 'v -0.4 -1 -1\nv -0.4 3 -1\nv -0.4 3 3\nv -0.4 -1 3\nf 1 2 3\nf 1 3 4\n' > xm04.obj
expect_exit 0 "$TETCUT" cut cube.vtu xm04.obj --deform mirrored.vtu --report mirrored.json
expect_stderr "inverted or flat"
json_check mirrored.json 'j["pieces"] == 1 and j["inverted_tets_skipped"] > 0'
expect_exit 0 "$TETCUT" grid --cells 2 2 2 -o small.vtu
expect_exit 2 "$TETCUT" cut cube.vtu x06.obj --deform small.vtu
expect_stderr "small.vtu"
expect_stderr "the deformed mesh has 27 nodes"

# Bad input: a clear message naming the file, exit 2, and no output written.
printf '# nothing here\n' > empty.obj
expect_exit 2 "$TETCUT" cut cube.vtu empty.obj --out-mesh never.vtu --report never.json
expect_stderr "empty.obj"
expect_stderr "no triangles"
printf 'v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n' > nan.obj
expect_exit 2 "$TETCUT" cut cube.vtu nan.obj --out-mesh never.vtu
expect_stderr "nan.obj:2:"
expect_exit 2 "$TETCUT" cut missing.vtu z.obj
expect_stderr "missing.vtu"
expect_exit 2 "$TETCUT" cut cube.vtu z.obj --out-mesh cut.txt
expect_stderr "cut.txt"
expect_exit 2 "$TETCUT" cut cube.vtu z.obj --out-surface cut.vtu
expect_exit 2 "$TETCUT" cut cube.vtu z.obj --out-mesh cube.vtu
expect_stderr "overwrite the input"
expect_exit 2 "$TETCUT" cut cube.vtu
[[ ! -e never.vtu && ! -e never.json && ! -e cut.txt ]] || fail "a failed cut left an output"
ls | grep -q '\.tmp' && fail "temporary files left behind"
echo "cut_test: all checks passed"
