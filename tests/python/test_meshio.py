"""Interop with meshio (Debian's python3-meshio): each side reads what the other writes."""

import meshio
import numpy as np
import pytest

import tetcut


def test_to_meshio_then_meshio_writes_what_tetcut_reads(tmp_path):
    V, T = tetcut.make_bcc((0, 0, 0), (1, 1, 1), 0.5)
    mesh = tetcut.to_meshio(V, T, cell_data={"index": np.arange(len(T), dtype=np.float64)})
    assert mesh.cells[0].type == "tetra"
    meshio.write(tmp_path / "by_meshio.vtu", mesh)
    V2, T2 = tetcut.read_tet_mesh(tmp_path / "by_meshio.vtu")
    np.testing.assert_array_equal(T2, T)
    np.testing.assert_array_equal(V2, V)


def test_from_meshio_reads_what_tetcut_writes(tmp_path):
    V, T = tetcut.make_grid((0, 0, 0), (2, 1, 1), (2, 1, 1))
    cutter = tetcut.Cutter(V, T)
    result = cutter.result()
    tetcut.write_tet_mesh(tmp_path / "by_tetcut.vtu", result.vertices, result.tets)
    V2, T2 = tetcut.from_meshio(meshio.read(tmp_path / "by_tetcut.vtu"))
    assert V2.dtype == np.float64 and T2.dtype == np.int32 and T2.flags.c_contiguous
    np.testing.assert_array_equal(T2, result.tets)
    # Straight into the library again.
    assert tetcut.measure_quality(V2, T2).volume == pytest.approx(2.0, rel=1e-14)
    # A surface: its triangles.
    s = result.surface
    tetcut.write_surface(tmp_path / "surface.obj", s.vertices, s.triangles)
    SV, SF = tetcut.from_meshio(meshio.read(tmp_path / "surface.obj"))
    np.testing.assert_array_equal(SF, s.triangles)
    surface_mesh = tetcut.to_meshio(s.vertices, s.triangles)
    assert surface_mesh.cells[0].type == "triangle"


def test_meshes_without_the_cells_asked_for_are_refused():
    only_lines = meshio.Mesh(np.zeros((2, 3)), [("line", np.array([[0, 1]]))])
    with pytest.raises(ValueError, match="no triangle cells"):
        tetcut.from_meshio(only_lines)
    with pytest.raises(ValueError, match="cell_type"):
        tetcut.from_meshio(only_lines, cell_type="hexahedron")
    with pytest.raises(ValueError, match="shape"):
        tetcut.to_meshio(np.zeros((4, 3)), np.zeros((2, 5), dtype=np.int32))
    dangling = meshio.Mesh(np.zeros((3, 3)), [("triangle", np.array([[0, 1, 5]]))])
    with pytest.raises(ValueError, match="points it does not have"):
        tetcut.from_meshio(dangling)
