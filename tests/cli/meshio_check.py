"""Cross-checks tetcut's files against meshio, an independent reader and writer.

Part 1: meshio reads what tetcut writes (.vtu, .msh 2.2 and 4.1, .mesh, .vtk) and finds the grid
we asked for: the analytic node set, 5 tets per cube, positive volumes adding up to the box.
Part 2: meshio writes a mesh built here (binary+zlib and ascii .vtu, binary and ascii legacy .vtk,
Gmsh 2.2 and 4.1, Medit, TetGen, and surfaces as OBJ, OFF, binary PLY, binary and ASCII STL),
and `tetcut info --json` must report the same counts, volume, bounding box and area.
Usage: meshio_check.py TETCUT WORKDIR
"""
import itertools
import json
import subprocess
import sys
import warnings

import meshio
import numpy as np

warnings.filterwarnings("ignore")
tetcut, work = sys.argv[1], sys.argv[2]


def run(*args):
    return subprocess.run([tetcut, *args], check=True, capture_output=True, text=True).stdout


def info(path):
    return json.loads(run("info", "--json", path))


def tet_volumes(points, tets):
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6


# Part 1 -------------------------------------------------------------------------------------
nx, ny, nz = 3, 2, 2
box_max = (1.5, 0.5, 0.75)  # dyadic, so the analytic node coordinates are exact doubles
run("grid", "--cells", str(nx), str(ny), str(nz), "--box", "0", "0", "0", *map(str, box_max), "-o", f"{work}/g.vtu")
expected_nodes = {(i * box_max[0] / nx, j * box_max[1] / ny, k * box_max[2] / nz)
                  for i in range(nx + 1) for j in range(ny + 1) for k in range(nz + 1)}
outputs = ["g.vtu"]
for name, extra in [("g41.msh", []), ("g22.msh", ["--msh-version", "22"]), ("g.mesh", []), ("g.vtk", [])]:
    run("convert", f"{work}/g.vtu", f"{work}/{name}", *extra)
    outputs.append(name)
for name in outputs:
    mesh = meshio.read(f"{work}/{name}")
    tets = np.concatenate([block.data for block in mesh.cells if block.type == "tetra"])
    assert len(tets) == 5 * nx * ny * nz, (name, len(tets))
    nodes = {tuple(p) for p in mesh.points[:, :3].tolist()}
    assert nodes == expected_nodes, (name, "node coordinates differ from the analytic grid")
    volumes = tet_volumes(mesh.points[:, :3], tets)
    assert (volumes > 0).all(), (name, "non-positive tet")
    assert abs(volumes.sum() - np.prod(box_max)) < 1e-14, (name, volumes.sum())
    print(f"meshio read tetcut's {name}: {len(mesh.points)} nodes, {len(tets)} tets")

# Part 2 -------------------------------------------------------------------------------------
# A 2x2x2 grid of cubes, each split into 6 tets along its main diagonal, with a non-dyadic box.
n = 2
size = np.array([1.3, 0.7, 1.1])
index = {}
points = []
for i, j, k in itertools.product(range(n + 1), repeat=3):
    index[i, j, k] = len(points)
    points.append(np.array([i, j, k]) * size / n)
points = np.array(points)
tets = []
for i, j, k in itertools.product(range(n), repeat=3):
    corner = lambda c: index[i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)]
    for a, b in itertools.permutations([1, 2, 4], 2):
        tet = [corner(0), corner(a), corner(a | b), corner(7)]
        if tet_volumes(points, np.array([tet]))[0] < 0:
            tet[2], tet[3] = tet[3], tet[2]
        tets.append(tet)
tets = np.array(tets)
volume = tet_volumes(points, tets).sum()
mesh = meshio.Mesh(points, [("tetra", tets)])
variants = [
    ("m_zlib.vtu", dict(file_format="vtu", binary=True, compression="zlib")),
    ("m_raw.vtu", dict(file_format="vtu", binary=True, compression=None)),
    ("m_ascii.vtu", dict(file_format="vtu", binary=False)),
    ("m_bin.vtk", dict(file_format="vtk", binary=True)),
    ("m_ascii.vtk", dict(file_format="vtk", binary=False)),
    ("m22.msh", dict(file_format="gmsh22", binary=False)),
    ("m41.msh", dict(file_format="gmsh", binary=False)),
    ("m.mesh", dict(file_format="medit")),
    ("m.node", dict(file_format="tetgen")),
]
for name, options in variants:
    meshio.write(f"{work}/{name}", mesh, **options)
    got = info(f"{work}/{name}")
    assert got["tets"] == len(tets) and got["nodes"] == len(points), (name, got)
    assert abs(got["volume"] - volume) < 1e-12, (name, got["volume"], volume)
    assert got["bbox"]["max"] == size.tolist() and got["bbox"]["min"] == [0, 0, 0], (name, got["bbox"])
    print(f"tetcut read meshio's {name}: {got['nodes']} nodes, {got['tets']} tets, volume {got['volume']:.15g}")

# The boundary of that mesh as surfaces.
faces = {}
for tet in tets:
    for f in ([1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]):
        tri = tet[f]
        faces.setdefault(tuple(sorted(tri)), []).append(tri)
skin = np.array([v[0] for v in faces.values() if len(v) == 1])
area = 2 * (size[0] * size[1] + size[1] * size[2] + size[0] * size[2])
surface = meshio.Mesh(points, [("triangle", skin)])
for name, options in [("s.obj", dict(file_format="obj")), ("s.off", dict(file_format="off")),
                      ("s.ply", dict(file_format="ply", binary=True)), ("s_bin.stl", dict(file_format="stl", binary=True)),
                      ("s_ascii.stl", dict(file_format="stl", binary=False))]:
    meshio.write(f"{work}/{name}", surface, **options)
    got = info(f"{work}/{name}")
    assert got["triangles"] == len(skin), (name, got)
    # Binary STL stores single-precision floats.
    tolerance = 1e-6 if name == "s_bin.stl" else 1e-12
    assert abs(got["area"] - area) < tolerance * area and got["balanced"], (name, got)
    assert abs(got["enclosed_volume"] - volume) < tolerance, (name, got)
    print(f"tetcut read meshio's {name}: {got['triangles']} triangles, balanced, area {got['area']:.12g}")
print("meshio cross-check passed")
