#!/usr/bin/env bash
# tetcut view: the page's default names and contents, what it accepts, and clear errors. What the
# page shows is checked in a browser by viewer/test/e2e.mjs (ctest: viewer.e2e).
set -euo pipefail
source "$(dirname "$0")/lib.sh"

expect_exit 0 "$TETCUT" view --help
expect_stdout "--mesh"

cat > drop.json <<'JSON'
{"mesh": {"grid": {"box": [0, 0, 0.1, 1, 1, 1.1], "cells": [2, 2, 2]}},
 "time": {"dt": 0.01, "duration": 0.1, "output_every": 0.05}}
JSON
expect_exit 0 "$TETCUT" sim drop.json -o sim
expect_exit 0 "$TETCUT" view sim
expect_stdout "sim/view.html (3 frames, with tet edges"
grep -qF "<title>sim - tetcut</title>" sim/view.html || fail "a directory's page is not titled by its name"
# One page, nothing fetched: three.js and the data are inline.
"$PYTHON" - sim/view.html <<'PY'
import base64, json, re, struct, sys
html = open(sys.argv[1]).read()
assert "<script src" not in html and "http://" not in html.split("tetcut-data")[0], "the page loads something"
data = json.loads(re.search(r'<script id="tetcut-data" type="application/json">(.*?)</script>', html, re.S).group(1))
frames = data["frames"]
assert [f["time"] for f in frames] == [0, 0.05, 0.1], [f["time"] for f in frames]
# Topology is stored once; positions every frame, as 16-bit steps within the frame's box (2x2x2
# cubes of 6 tets: 27 nodes).
assert frames[0]["surface"]["triangles"] and frames[1]["surface"]["triangles"] is None
assert frames[0]["mesh"]["edges"] and frames[2]["mesh"]["edges"] is None
p = frames[2]["mesh"]["positions"]
q = base64.b64decode(p["q"])
nodes = len(q) // 6
assert nodes == 27, nodes
zs = [p["min"][2] + k * p["step"][2] for k in struct.unpack("<%dH" % (3 * nodes), q)[2::3]]
assert abs(min(zs) - p["min"][2]) < 1e-12 and min(zs) < 0.1 - 1e-3, "the last frame does not hold the fallen positions"
assert frames[0]["surface"]["pieces"] == 1
# Within half a step of what the frame's mesh file holds (read by meshio, independently).
import meshio
points = meshio.read(sys.argv[1].replace("view.html", "mesh_0002.vtu")).points
decoded = struct.unpack("<%dH" % (3 * nodes), q)
for n in range(nodes):
    for c in range(3):
        error = abs(p["min"][c] + decoded[3 * n + c] * p["step"][c] - points[n][c])
        assert error <= 0.5 * p["step"][c] * (1 + 1e-9), (n, c, error)
PY

# A surface file, with a mesh's edges; a mesh file alone; the default names.
expect_exit 0 "$TETCUT" grid --cells 2 2 2 -o cube.vtu
printf 'v -1 -1 0.4\nv 2 -1 0.4\nv 2 2 0.4\nv -1 2 0.4\nf 1 2 3\nf 1 3 4\n' > z.obj
expect_exit 0 "$TETCUT" cut cube.vtu z.obj --out-mesh cut.vtu --out-surface cut.obj
expect_exit 0 "$TETCUT" view cut.obj --mesh cut.vtu --title "two halves"
expect_stdout "cut.html (1 frame, with tet edges"
grep -qF "<title>two halves - tetcut</title>" cut.html || fail "the title is not the one given"
expect_exit 0 "$TETCUT" view cut.vtu -o mesh_page.html
[[ -s mesh_page.html ]] || fail "no page for a mesh file"

# A cloth scene's frames, with the edges of its triangle copies where they are; and the material
# tetcut cut2d writes, with its copies.
cat > cloth.json <<'JSON'
{"cloth": {"mesh": {"grid": {"cells": 4, "size": 1, "plane": "xz"}}},
 "pin": [{"box": [-1, -1, 0.99, 2, 1, 1.01]}],
 "time": {"dt": 0.01, "duration": 0.1, "output_every": 0.05},
 "cuts": [{"time": 0, "blade": {"poses": [[-1, -1, 0.4375, -1, 1, 0.4375], [2, -1, 0.4375, 2, 1, 0.4375]]}}]}
JSON
expect_exit 0 "$TETCUT" sim cloth.json -o cloth
expect_exit 0 "$TETCUT" view cloth
expect_stdout "cloth/view.html (3 frames, with triangle-copy edges"
"$PYTHON" - cloth/view.html cloth/summary.json <<'PY'
import base64, json, re, sys
html = open(sys.argv[1]).read()
summary = json.load(open(sys.argv[2]))
data = json.loads(re.search(r'<script id="tetcut-data" type="application/json">(.*?)</script>', html, re.S).group(1))
assert data["mesh_kind"] == "triangles", data["mesh_kind"]
frames = data["frames"]
assert len(frames) == 3
# One point per node; edges stored when the copies change: frame 0 is the uncut grid (its 56
# edges), frame 1 has the copies the blade made (more edges, over the doubled nodes), frame 2 the same.
nodes = len(base64.b64decode(frames[2]["mesh"]["positions"]["q"])) // 6
assert nodes == summary["nodes"] == 35, nodes
edges = [len(base64.b64decode(f["mesh"]["edges"])) // 8 if f["mesh"]["edges"] else None for f in frames]
assert edges[0] == 56 and edges[1] > 56 and edges[2] is None, edges
assert frames[0]["surface"]["pieces"] == 1 and frames[2]["surface"]["pieces"] == 2
PY
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 0\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n' > square.obj
printf 'v -1 0.3 0\nv 2 0.6 0\nl 1 2\n' > across.obj
expect_exit 0 "$TETCUT" cut2d square.obj across.obj -o material.vtp --copies copies.obj
expect_exit 0 "$TETCUT" view material.vtp --mesh copies.obj
expect_stdout "material.html (1 frame, with triangle-copy edges"

# Errors name the file and leave nothing behind.
expect_exit 2 "$TETCUT" view missing_dir
expect_stderr "missing_dir: no such file or directory"
mkdir empty
expect_exit 2 "$TETCUT" view empty
expect_stderr "no surface.pvd here"
expect_exit 2 "$TETCUT" view cut.obj -o page.htm
expect_stderr "must be a .html file"
cp -r sim broken
printf '<?xml version="1.0"?>\n<VTKFile type="Collection">\n<Collection>\n<DataSet timestep="soon" file="surface_0000.vtp"/>\n</Collection>\n</VTKFile>\n' > broken/surface.pvd
rm broken/view.html
expect_exit 2 "$TETCUT" view broken
expect_stderr "surface.pvd:4: DataSet timestep 'soon' is not a finite number"
[[ ! -e broken/view.html ]] || fail "a page was written for a broken series"
head -c 200 sim/mesh.pvd > broken/mesh.pvd
cp sim/surface.pvd broken/surface.pvd
expect_exit 2 "$TETCUT" view broken
expect_stderr "mesh.pvd"
echo "view CLI: all checks passed"
