"""examples/python/cut_and_simulate.py runs, cuts the block in two while it hangs, and writes a
ParaView series whose frames tetcut and meshio both read."""

import os
import pathlib
import subprocess
import sys

import meshio
import numpy as np

import tetcut

EXAMPLE = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python" / "cut_and_simulate.py"


def test_the_example_cuts_simulates_and_writes_a_series(tmp_path):
    out = tmp_path / "series"
    run = subprocess.run([sys.executable, EXAMPLE, out, "--steps", "90"], check=True, capture_output=True, text=True,
                         env=dict(os.environ))
    assert "into 2 pieces" in run.stdout
    meshes = tetcut.read_series(out / "mesh.pvd")
    surfaces = tetcut.read_series(out / "surface.pvd")
    assert len(meshes) == len(surfaces) == 31
    assert [t for t, _ in meshes] == sorted(t for t, _ in meshes)
    first, last = meshio.read(meshes[0][1]), meshio.read(meshes[-1][1])
    V0, _ = tetcut.from_meshio(first)
    V1, T1 = tetcut.from_meshio(last)
    piece = last.cell_data["piece"][0].astype(int)
    assert set(piece) == {0, 1}
    # The piece below the blade fell; the one above still hangs from the top.
    low = [p for p in (0, 1) if V1[T1[piece == p]].mean(axis=(0, 1))[2] < 0.4]
    assert len(low) == 1
    assert V1[np.unique(T1[piece == low[0]]), 2].max() < V0[:, 2].max() * 0.45 - 0.05
    SV, SF = tetcut.read_surface(surfaces[-1][1])
    assert tetcut.measure_surface(SV, SF).balanced


def test_the_readme_five_line_example_prints_289(capsys):
    readme = (pathlib.Path(__file__).resolve().parents[2] / "README.md").read_text()
    start = readme.index("    import numpy as np, tetcut\n")
    block = readme[start:readme.index("\n\n", start)]
    lines = [line[4:] for line in block.splitlines()]
    assert len(lines) == 5
    exec(compile("\n".join(lines), "README.md", "exec"), {})
    assert capsys.readouterr().out.strip() == "289"
