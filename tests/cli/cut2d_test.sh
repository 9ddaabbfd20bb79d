#!/usr/bin/env bash
# tetcut cut2d: a planar mesh cut by polyline files in every format, the report, the outputs read
# back, and clear errors that change and write nothing.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

expect_exit 0 "$TETCUT" cut2d --help
expect_stdout "--boundary"

# A 2 x 2 square of four counter-clockwise triangles in the plane y = 0.5 (an x-z cloth, seen
# from -y: the (x, z) orientation is clockwise, so the tool swaps the axes).
printf 'v 0 0.5 0\nv 2 0.5 0\nv 2 0.5 2\nv 0 0.5 2\nv 1 0.5 1\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n' > cloth.obj
# A cut across at z = 0.5 (OBJ l), one at x = 1.5 from the top down to the first (legacy VTK), and
# a small closed square inside one triangle (plain points, closed by repeating the first).
printf 'v -1 0.5 0.5\nv 3 0.5 0.5\nl 1 2\n' > across.obj
printf '# vtk DataFile Version 4.2\nt\nASCII\nDATASET POLYDATA\nPOINTS 2 double\n1.5 0.5 3\n1.5 0.5 0.5\nLINES 1 3\n2 0 1\n' > down.vtk
printf '# a loop\n0.875 0.5 1.625\n1.125 0.5 1.625\n1.125 0.5 1.875\n0.875 0.5 1.875\n0.875 0.5 1.625\n' > loop.xyz
expect_exit 0 "$TETCUT" cut2d cloth.obj across.obj down.vtk loop.xyz -o material.vtp --copies copies.obj --boundary boundary.obj --json
cp out.txt report.json
json_check report.json 'j["pieces"] == 4 and j["triangles_in"] == 4 and j["segments"] == 6'
json_check report.json 'sorted(j["piece_areas"]) == [0.0625, 0.75, 1.0, 2.1875] and j["area"] == 4.0'
json_check report.json 'len(j["batches"]) == 3 and j["batches"][0]["triangles_touched"] == 3 and j["batches"][2]["triangles_touched"] == 1'
json_check report.json 'j["triangle_copies"] > 4 and j["nodes"] > 5'
# The material reads back with the mesh's area, lying in the mesh's plane.
expect_exit 0 "$TETCUT" info --json material.vtp
cp out.txt material.json
json_check material.json 'abs(j["area"] - 4) < 1e-12 and j["bbox"]["min"][1] == 0.5 and j["bbox"]["max"][1] == 0.5'
expect_exit 0 "$TETCUT" info --json copies.obj
cp out.txt copies.json
json_check copies.json "j['triangles'] == $("$PYTHON" -c "import json; print(json.load(open('report.json'))['triangle_copies'])")"
grep -q '^l ' boundary.obj || fail "the boundary has no segments"
expect_exit 0 "$TETCUT" cut2d cloth.obj across.obj
expect_stdout "2 piece(s)"

# Bad input: each names the file (and line), exits 2, and writes nothing.
rm -f material.vtp
printf 'v 0 0 0\nv 1 0 nan\nl 1 2\n' > nan.obj
expect_exit 2 "$TETCUT" cut2d cloth.obj across.obj nan.obj -o material.vtp
expect_stderr "nan.obj:2"
[[ ! -e material.vtp ]] || fail "a failed cut wrote its output"
printf 'v 0 0 0\nl 1 3\n' > range.obj
expect_exit 2 "$TETCUT" cut2d cloth.obj range.obj
expect_stderr "range.obj:2"
printf '0 0\n' > single.txt
expect_exit 2 "$TETCUT" cut2d cloth.obj single.txt
expect_stderr "single point"
printf '# nothing\n' > empty.txt
expect_exit 2 "$TETCUT" cut2d cloth.obj empty.txt
expect_stderr "no polyline"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 1\nf 1 2 3\n' > bent.obj
expect_exit 2 "$TETCUT" cut2d bent.obj across.obj
expect_stderr "coordinate plane"
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 4 3\n' > mixed.obj
expect_exit 2 "$TETCUT" cut2d mixed.obj across.obj
expect_stderr "mixed.obj"
expect_stderr "triangle 1"
expect_exit 2 "$TETCUT" cut2d cloth.obj across.obj -o across.obj
expect_stderr "overwrite"
echo "cut2d: ok"
