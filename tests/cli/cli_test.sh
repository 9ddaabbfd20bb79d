#!/usr/bin/env bash
# The command-line tool: help, exit codes, error messages, and what each subcommand writes.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

# --help works everywhere and exits 0.
expect_exit 0 "$TETCUT" --help
for command in grid bcc info convert cut demo; do
  expect_exit 0 "$TETCUT" "$command" --help
  expect_stdout "Usage"
done

# Usage errors exit 2 with a message.
expect_exit 2 "$TETCUT"
expect_exit 2 "$TETCUT" grid --cells 2 2 -o x.vtu
expect_stderr "error"
expect_exit 2 "$TETCUT" grid --cells 2 2 2 --tets-per-cube 4 -o x.vtu
expect_exit 2 "$TETCUT" bcc --box 0 0 0 1 1 1 --spacing -1 -o x.vtu
expect_exit 2 "$TETCUT" grid --cells 2 2 2 -o x.txt
expect_stderr "x.txt"
[[ ! -e x.vtu && ! -e x.txt ]] || fail "a failed command left an output"

# serve: bad arguments are refused before anything listens (the server itself: tests/server).
expect_exit 0 "$TETCUT" serve --help
expect_stdout "--record"
expect_exit 2 "$TETCUT" serve missing_scene.json --port 0
expect_stderr "missing_scene.json: cannot open the scene file"
expect_exit 2 "$TETCUT" serve --host not-an-address --port 0
expect_stderr "not an IP address: 'not-an-address'"
expect_exit 2 "$TETCUT" serve --record take.txt --port 0
expect_stderr "take.txt: the recording is a scene file"
expect_exit 2 "$TETCUT" serve --port 70000

# grid and bcc write meshes that info reads back with the expected numbers.
expect_exit 0 "$TETCUT" grid --cells 4 4 4 -o cube.vtu
expect_exit 0 "$TETCUT" info --json cube.vtu
cp out.txt cube.json
json_check cube.json 'j["tets"] == 320 and j["nodes"] == 125 and abs(j["volume"] - 1) < 1e-12'
json_check cube.json 'j["boundary_faces"] == 192 and abs(j["min_dihedral_degrees"] - 54.7356) < 1e-3'
expect_exit 0 "$TETCUT" grid --cells 2 3 4 --box -1 -1 -1 1 2 3 --tets-per-cube 6 -o six.msh --msh-version 22
head -2 six.msh | grep -q "2.2 0 8" || fail "--msh-version 22 not honoured"
expect_exit 0 "$TETCUT" info --json six.msh
cp out.txt six.json
json_check six.json 'j["tets"] == 144 and abs(j["volume"] - 24) < 1e-12 and j["bbox"]["min"] == [-1, -1, -1]'
expect_exit 0 "$TETCUT" bcc --box 0 0 0 1 1 1 --spacing 0.25 -o bcc.mesh
expect_exit 0 "$TETCUT" info --json bcc.mesh
cp out.txt bcc.json
json_check bcc.json 'j["tets"] == 12 * 64 and abs(j["volume"] - 1) < 1e-12'
expect_exit 0 "$TETCUT" info bcc.mesh
expect_stdout "dihedral angles"

# convert between every pair of tet formats keeps the mesh.
for ext in mesh msh node vtu vtk; do
  expect_exit 0 "$TETCUT" convert cube.vtu "c.$ext"
  expect_exit 0 "$TETCUT" info --json "c.$ext"
  cp out.txt c.json
  json_check c.json 'j["tets"] == 320 and j["nodes"] == 125 and abs(j["volume"] - 1) < 1e-12'
done
# A tet mesh converted to a surface format gives its closed boundary.
expect_exit 0 "$TETCUT" convert cube.vtu skin.ply --binary
expect_exit 0 "$TETCUT" info --json skin.ply
cp out.txt skin.json
json_check skin.json 'j["balanced"] and j["two_manifold"] and j["triangles"] == 192 and abs(j["area"] - 6) < 1e-12 and abs(j["enclosed_volume"] - 1) < 1e-12'
expect_exit 0 "$TETCUT" convert skin.ply skin.stl
expect_exit 0 "$TETCUT" convert skin.stl skin.off
expect_exit 0 "$TETCUT" info skin.off
expect_stdout "balanced         yes"

# Bad input: message names file and line, exit 2, and the output is not created.
printf 'MeshVersionFormatted 2\nDimension 3\nVertices\n2\n0 0 0 0\n1 nan 0 0\n' > bad.mesh
expect_exit 2 "$TETCUT" convert bad.mesh out.vtu
expect_stderr "bad.mesh:6:"
expect_stderr "not a finite number"
[[ ! -e out.vtu ]] || fail "convert left an output after failing"
expect_exit 2 "$TETCUT" info missing.vtu
expect_stderr "missing.vtu"
expect_exit 2 "$TETCUT" info notes.txt
expect_stderr "unknown file type"

# The input is never overwritten, and a failed conversion keeps an existing output intact.
cp cube.vtu keep.vtu
before=$(md5sum keep.vtu)
expect_exit 2 "$TETCUT" convert keep.vtu keep.vtu
expect_stderr "overwrite the input"
echo "old contents" > existing.vtu
expect_exit 2 "$TETCUT" convert bad.mesh existing.vtu
[[ $(cat existing.vtu) == "old contents" ]] || fail "a failed conversion changed the existing output"
[[ $(md5sum keep.vtu) == "$before" ]] || fail "input changed"
ls | grep -q '\.tmp' && fail "temporary files left behind"

# A surface cannot become a tet mesh.
expect_exit 2 "$TETCUT" convert skin.ply skin.vtu

# The default job runs without input: the paper's Figures 4 and 2.
expect_exit 0 "$TETCUT" demo -o demo
for f in figure4.vtu figure4_surface.obj figure4_report.json figure2.vtu figure2_surface.obj figure2_report.json; do
  [[ -s demo/$f ]] || fail "demo output $f missing"
done
json_check demo/figure4_report.json 'j["tets_in"] == 320 and j["pieces"] == 289 and j["surface"]["balanced"]'
json_check demo/figure2_report.json 'j["tets_in"] == 1 and j["pieces"] > 1000 and abs(j["volume"] - 1 / 6) < 1e-12' 
echo "cli_test: all checks passed"
