"""Files, generators and measures over numpy arrays, and the errors for what is not a mesh."""

import numpy as np
import pytest

import tetcut
from conftest import tet_volumes


def test_make_grid_gives_arrays_of_the_documented_types():
    V, T = tetcut.make_grid((0, 0, 0), (1, 2, 3), (2, 3, 4), 5)
    assert V.dtype == np.float64 and V.shape == (3 * 4 * 5, 3) and V.flags.c_contiguous
    assert T.dtype == np.int32 and T.shape == (2 * 3 * 4 * 5, 4)
    assert tet_volumes(V, T).sum() == pytest.approx(6.0, rel=1e-14)
    assert (tet_volumes(V, T) > 0).all()
    _, T6 = tetcut.make_grid([0, 0, 0], [1, 1, 1], [2, 2, 2], tets_per_cube=6)
    assert T6.shape == (48, 4)


def test_make_bcc_fills_its_box():
    V, T = tetcut.make_bcc((0, 0, 0), (1, 1, 1), 0.25)
    q = tetcut.measure_quality(V, T)
    assert q.volume == pytest.approx(np.prod(q.bbox_max - q.bbox_min), rel=1e-12)
    # BCC tets have dihedral angles of 60 and 90 degrees; the boundary pyramids, 45 and 120.
    assert q.min_dihedral_degrees == pytest.approx(45) and q.max_dihedral_degrees == pytest.approx(120)
    assert q.num_unused_nodes == 0
    assert q.min_volume > 0 and q.min_altitude > 0


@pytest.mark.parametrize("extension", [".mesh", ".msh", ".vtu", ".vtk", ".node"])
def test_tet_meshes_round_trip_through_every_format(tmp_path, extension):
    V, T = tetcut.make_bcc((0, 0, 0), (1, 1, 1), 0.5)
    path = tmp_path / f"lattice{extension}"
    tetcut.write_tet_mesh(path, V, T)
    V2, T2 = tetcut.read_tet_mesh(path)
    np.testing.assert_array_equal(T2, T)
    np.testing.assert_allclose(V2, V, rtol=0, atol=1e-12)


def test_cell_fields_and_labels_reach_the_file(tmp_path):
    V, T = tetcut.make_grid((0, 0, 0), (1, 1, 1), (1, 1, 1))
    path = tmp_path / "fields.vtu"
    tetcut.write_tet_mesh(path, V, T, cell_fields={"height": V[T].mean(axis=1)[:, 2].copy()}, labels=np.arange(5, dtype=np.int32))
    text = path.read_text(errors="replace")
    assert 'Name="height"' in text
    with pytest.raises(ValueError, match="one value per tet"):
        tetcut.write_tet_mesh(path, V, T, cell_fields={"short": np.zeros(3)})


@pytest.mark.parametrize("extension", [".obj", ".off", ".ply", ".stl", ".vtp"])
def test_surfaces_round_trip(tmp_path, extension):
    V, T = tetcut.make_grid((0, 0, 0), (1, 1, 1), (2, 2, 2))
    cutter = tetcut.Cutter(V, T)
    s = cutter.surface()
    path = tmp_path / f"box{extension}"
    tetcut.write_surface(path, s.vertices, s.triangles)
    V2, F2 = tetcut.read_surface(path)
    assert F2.shape == s.triangles.shape
    stats = tetcut.measure_surface(V2, F2)
    assert stats.area == pytest.approx(6.0, rel=1e-6)
    assert stats.enclosed_volume == pytest.approx(1.0, rel=1e-6)


def test_a_real_scan_read_straight_from_its_archive(cgal_archive):
    V, F = tetcut.read_surface(cgal_archive, "data/meshes/bunny00.off")
    assert V.shape[1] == 3 and F.shape[1] == 3 and len(F) > 1000
    check = tetcut.check_surface(V, F)
    assert check.triangles == len(F)


def test_malformed_files_name_the_file_and_line(tmp_path):
    path = tmp_path / "broken.off"
    path.write_text("OFF\n3 1 0\n0 0 0\n1 0 x\n0 1 0\n3 0 1 2\n")
    with pytest.raises(tetcut.Error) as caught:
        tetcut.read_surface(path)
    assert caught.value.kind == "invalid_input"
    assert caught.value.file == str(path)
    assert caught.value.line == 4
    assert str(path) in str(caught.value)
    with pytest.raises(tetcut.Error) as missing:
        tetcut.read_tet_mesh(tmp_path / "absent.mesh")
    assert missing.value.kind == "io"
    (tmp_path / "mesh.xyz").write_text("1 2 3\n")
    with pytest.raises(tetcut.Error) as unknown:
        tetcut.read_tet_mesh(tmp_path / "mesh.xyz")
    assert unknown.value.kind == "invalid_argument"


def test_writing_a_bad_mesh_overwrites_nothing(tmp_path):
    V, T = tetcut.make_grid((0, 0, 0), (1, 1, 1), (1, 1, 1))
    path = tmp_path / "keep.mesh"
    tetcut.write_tet_mesh(path, V, T)
    before = path.read_bytes()
    bad = V.copy()
    bad[0, 0] = np.nan
    with pytest.raises(tetcut.Error, match="finite"):
        tetcut.write_tet_mesh(path, bad, T)
    assert path.read_bytes() == before


def test_wrong_dtypes_shapes_and_layouts_are_clear_errors():
    V, T = tetcut.make_grid((0, 0, 0), (1, 1, 1), (1, 1, 1))
    with pytest.raises(TypeError, match=r"V must be a float64 array of shape \(n, 3\), not float32"):
        tetcut.measure_quality(V.astype(np.float32), T)
    with pytest.raises(TypeError, match=r"T must be a int32 array of shape \(n, 4\), not int64"):
        tetcut.measure_quality(V, T.astype(np.int64))
    with pytest.raises(TypeError, match="numpy"):
        tetcut.measure_quality(V.tolist(), T)
    with pytest.raises(ValueError, match=r"not \(8, 2\)"):
        tetcut.measure_quality(np.ascontiguousarray(V[:, :2]), T)
    with pytest.raises(ValueError, match="C-contiguous"):
        tetcut.measure_quality(np.asfortranarray(V), T)
    with pytest.raises(ValueError, match="C-contiguous"):
        tetcut.measure_quality(np.repeat(V, 2, axis=0)[::2], T)
    bad = T.copy()
    bad[2, 1] = 99
    with pytest.raises(ValueError, match=r"T\[2, 1\] is 99"):
        tetcut.measure_quality(V, bad)
    with pytest.raises(ValueError, match="three numbers"):
        tetcut.make_grid((0, 0), (1, 1, 1), (1, 1, 1))
    with pytest.raises(tetcut.Error):
        tetcut.make_bcc((0, 0, 0), (1, 1, 1), -1.0)


def test_nans_and_inverted_tets_are_refused():
    V, T = tetcut.make_grid((0, 0, 0), (1, 1, 1), (1, 1, 1))
    bad = V.copy()
    bad[3, 2] = np.nan
    with pytest.raises(tetcut.Error) as caught:
        tetcut.Cutter(bad, T)
    assert caught.value.kind == "invalid_input"
    inverted = T.copy()
    inverted[0, [0, 1]] = inverted[0, [1, 0]]
    with pytest.raises(tetcut.Error, match="volume"):
        tetcut.Cutter(V, inverted)
