"""The Cutter from Python: the paper's Figure 4, provenance of each batch, world-space cuts, the
material surface, embedding a real scan, and agreement with the CLI on the same input."""

import json
import subprocess

import numpy as np
import pytest

import tetcut
from conftest import figure4_planes, soup, square, tet_volumes


def figure4_cube():
    return tetcut.make_grid((0, 0, 0), (1, 1, 1), (4, 4, 4), 5)


def test_figure4_cuts_the_cube_into_289_sticks():
    V, T = figure4_cube()
    assert T.shape == (320, 4)
    cutter = tetcut.Cutter(V, T)
    report = cutter.cut(*figure4_planes())
    assert report.triangles == 64 and len(report.degenerate) == 0
    result = cutter.result()
    assert result.num_pieces == 289
    np.testing.assert_allclose(result.piece_volumes, np.full(289, 1 / 289), rtol=1e-12)
    assert result.piece_volumes.sum() == pytest.approx(1.0, rel=1e-13)
    # Each copy holds material, and the copies' material adds up to the cube.
    assert (result.tet_material_volume > 0).all()
    assert result.tet_material_volume.sum() == pytest.approx(1.0, rel=1e-13)
    # Pieces by volume, largest first; every copy is in one.
    assert set(np.unique(result.tet_piece)) == set(range(289))
    # The material surface is closed, consistently oriented, and encloses the cube.
    stats = tetcut.measure_surface(result.surface.vertices, result.surface.triangles)
    assert stats.balanced
    assert stats.enclosed_volume == pytest.approx(1.0, rel=1e-12)


def test_each_batch_reports_where_new_nodes_and_copies_came_from():
    V, T = figure4_cube()
    cutter = tetcut.Cutter(V, T)
    first = cutter.cut(*square(0, 0.3))
    assert first.first_new_node == 125 and first.first_new_tet == 320
    assert len(first.new_node_source) == cutter.num_nodes - 125
    assert len(first.new_tet_source) == cutter.num_tets - 320
    assert (first.new_node_source < 125).all() and (first.new_tet_source < 320).all()
    np.testing.assert_array_equal(first.touched, np.unique(first.touched))
    assert first.tets_touched == len(first.touched) > 0
    # A node split off copies its source's position; a copy copies its source's tet.
    nodes, parent = cutter.tet_nodes, cutter.tet_parent
    assert nodes.shape == (cutter.num_tets, 4) and nodes.dtype == np.int32
    np.testing.assert_array_equal(parent[320:], parent[first.new_tet_source])
    np.testing.assert_array_equal(cutter.node_parent[125:], first.new_node_source)
    for tet in first.touched[:5]:
        copies = cutter.copies_of(int(tet))
        assert len(copies) >= 1 and (parent[copies] == tet).all()
    # A second batch starts its numbering where the first ended.
    nodes_before, tets_before = cutter.num_nodes, cutter.num_tets
    second = cutter.cut(*square(1, 0.6))
    assert second.first_new_node == nodes_before and second.first_new_tet == tets_before
    assert cutter.num_cut_triangles == 4
    assert cutter.result().num_pieces == 4
    # Fractions the simulator would use, one by one and all at once, agree bit for bit.
    fractions = cutter.result().material_fractions
    assert [cutter.material_fraction(c) for c in range(cutter.num_tets)] == list(fractions)
    with pytest.raises(IndexError):
        cutter.material_fraction(cutter.num_tets)


def test_batches_and_one_batch_give_the_same_pieces():
    V, T = figure4_cube()
    planes = figure4_planes()
    at_once = tetcut.Cutter(V, T)
    at_once.cut(*planes)
    progressive = tetcut.Cutter(V, T)
    PV, PF = planes
    for k in range(0, len(PF), 8):
        progressive.cut(PV, np.ascontiguousarray(PF[k:k + 8]))
    a, b = at_once.result(), progressive.result()
    assert a.num_pieces == b.num_pieces == 289
    np.testing.assert_allclose(np.sort(a.piece_volumes), np.sort(b.piece_volumes), rtol=1e-12)


def test_a_cut_placed_on_the_deformed_mesh_follows_its_motion():
    V, T = figure4_cube()
    offset = np.array([2.0, -1.0, 0.5])
    world = tetcut.Cutter(V, T)
    world.set_current(V + offset)
    np.testing.assert_array_equal(world.current(), V + offset)
    np.testing.assert_allclose(world.to_rest(np.array([[2.25, -0.5, 1.0]])), [[0.25, 0.5, 0.5]], atol=1e-12)
    SV, SF = square(0, 0.25)
    report = world.cut_deformed(SV + offset, SF)
    assert len(report.skipped_inverted) == 0
    rest = tetcut.Cutter(V, T)
    rest.cut(SV, SF)
    np.testing.assert_allclose(world.result().piece_volumes, rest.result().piece_volumes, rtol=1e-12)
    np.testing.assert_allclose(world.result().piece_volumes, [0.75, 0.25], rtol=1e-12)
    # Or with the positions given with the batch.
    again = tetcut.Cutter(V, T)
    again.cut_deformed(SV + offset, SF, V + offset)
    assert again.result().num_pieces == 2


def cube_cut_in_half(axis):
    """Figure 4's cube cut by the plane x[axis] = 0.5: the result, and which copies are the upper half's."""
    V, T = figure4_cube()
    cutter = tetcut.Cutter(V, T)
    cutter.cut(*square(axis, 0.5))
    result = cutter.result()
    upper_piece = result.tet_piece[np.argmax(result.vertices[result.tets].mean(axis=1)[:, axis])]
    return result, result.tet_piece == upper_piece


def test_the_surface_follows_the_nodes():
    result, top = cube_cut_in_half(2)
    s = result.surface
    assert s.vertex_weights.shape == (len(s.vertices), 4)
    np.testing.assert_allclose(s.vertex_weights.sum(axis=1), 1, atol=1e-14)
    np.testing.assert_allclose(s.positions(result.tets, result.vertices), s.vertices, atol=1e-12)
    # Lift the top piece: its surface goes with it.
    X = result.vertices.copy()
    lifted = np.unique(result.tets[top])
    X[lifted, 2] += 1
    moved = s.positions(result.tets, X)
    on_top = np.isin(s.vertex_tet, np.flatnonzero(top))
    np.testing.assert_allclose(moved[on_top, 2] - s.vertices[on_top, 2], 1, atol=1e-12)
    np.testing.assert_allclose(moved[~on_top], s.vertices[~on_top], atol=1e-12)
    # Sources: the cut triangles (ids 0, 1) and the cube's faces (negative).
    assert set(s.triangle_source[s.triangle_source >= 0]) <= {0, 1}
    assert (s.triangle_source < 0).any()


def test_a_blade_sweeps_a_strip_that_cuts():
    A = np.array([[0.5, -1, -1], [0.5, -1, 2]])  # two poses of the blade's back end...
    B = np.array([[0.5, 2, -1], [0.5, 2, 2]])    # ...and of its tip
    SV, SF = tetcut.swept_blade(A, B)
    assert SF.shape == (2, 3)
    V, T = figure4_cube()
    cutter = tetcut.Cutter(V, T)
    cutter.cut(SV, SF)
    assert cutter.result().num_pieces == 2
    with pytest.raises(ValueError, match="one row per blade pose"):
        tetcut.swept_blade(A, B[:1].copy())


def test_bad_cuts_change_nothing():
    V, T = figure4_cube()
    cutter = tetcut.Cutter(V, T)
    SV, SF = square(0, 0.5)
    SV[1, 1] = np.inf
    with pytest.raises(tetcut.Error, match="finite") as caught:
        cutter.cut(SV, SF)
    assert caught.value.kind == "invalid_input"
    assert cutter.num_nodes == 125 and cutter.num_tets == 320 and cutter.num_cut_triangles == 0
    with pytest.raises(ValueError, match=r"F\[1, 2\] is 7"):
        cutter.cut(*square(0, 0.5)[:1], np.array([[0, 1, 2], [0, 2, 7]], dtype=np.int32))
    # An empty cut is no cut.
    empty = cutter.cut(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32))
    assert empty.triangles == 0 and cutter.result().num_pieces == 1


def test_embedding_a_real_scan(cgal_archive):
    SV, SF = tetcut.read_surface(cgal_archive, "data/meshes/femur.off")
    spacing = tetcut.spacing_for_cubes(SV, SF, 12)
    V, T = tetcut.embedding_lattice(SV, SF, spacing)
    cutter, report = tetcut.embed(V, T, SV, SF)
    assert report.check.balanced and report.tets_in == len(T)
    assert 0 < report.tets_with_material < len(T)
    result = cutter.result()
    # The kept material is what the scan encloses, and its surface is closed.
    enclosed = tetcut.measure_surface(SV, SF).enclosed_volume
    assert result.piece_volumes.sum() == pytest.approx(enclosed, rel=1e-9)
    assert tetcut.measure_surface(result.surface.vertices, result.surface.triangles).balanced
    # Keep cutting the embedded model: a plane across the shaft.
    centre = SV.mean(axis=0)
    PV, PF = square(2, centre[2], lo=-10, hi=10)
    cutter.cut(PV, PF)
    assert cutter.result().num_pieces >= 2
    with pytest.raises(ValueError, match="keep must be"):
        tetcut.embed(V, T, SV, SF, keep="outside")
    with pytest.raises(tetcut.Error):
        tetcut.embed(V, T, SV, SF, keep="point", point=(1e6, 0, 0))


def test_the_same_cut_as_the_cli(tmp_path, cli):
    V, T = figure4_cube()
    tetcut.write_tet_mesh(tmp_path / "cube.vtu", V, T)
    first, second = soup(square(0, 0.3), square(1, 0.55)), square(2, 0.8)
    tetcut.write_surface(tmp_path / "first.obj", *first)
    tetcut.write_surface(tmp_path / "second.obj", *second)
    subprocess.run([cli, "cut", tmp_path / "cube.vtu", tmp_path / "first.obj", tmp_path / "second.obj",
                    "--out-mesh", tmp_path / "cut.vtu", "--report", tmp_path / "report.json"], check=True, capture_output=True)
    report = json.loads((tmp_path / "report.json").read_text())
    cutter = tetcut.Cutter(V, T)
    cutter.cut(*first)
    cutter.cut(*second)
    result = cutter.result()
    assert report["pieces"] == result.num_pieces == 8
    assert report["tets_out"] == len(result.tets) and report["nodes_out"] == len(result.vertices)
    np.testing.assert_allclose(report["piece_volumes"], result.piece_volumes, rtol=1e-12)
    CV, CT = tetcut.read_tet_mesh(tmp_path / "cut.vtu")
    np.testing.assert_array_equal(CT, result.tets)
    np.testing.assert_allclose(CV, result.vertices, atol=1e-15)
    assert tet_volumes(CV, CT).sum() == pytest.approx(tet_volumes(result.vertices, result.tets).sum(), rel=1e-14)


def test_counting_where_the_surface_passes_through_itself():
    result, right = cube_cut_in_half(0)
    s = result.surface
    assert tetcut.count_surface_intersections(s, result.tets, s.positions(result.tets, result.vertices)).intersecting_pairs == 0
    X = result.vertices.copy()
    X[np.unique(result.tets[right]), 0] -= 0.2  # the right half into the left
    found = tetcut.count_surface_intersections(s, result.tets, s.positions(result.tets, X))
    assert found.intersecting_pairs > 0 and found.examples.shape[1] == 2
    # Pressed 1e-3 into each other and slid as far: within an allowance of 2e-3, the sides of a
    # cut pressed together; with none, crossings.
    X = result.vertices.copy()
    X[np.unique(result.tets[right])] += [-1e-3, -1e-3, 1e-3]
    pressed = s.positions(result.tets, X)
    assert tetcut.count_surface_intersections(s, result.tets, pressed, opened=2e-3).intersecting_pairs == 0
    assert tetcut.count_surface_intersections(s, result.tets, pressed).intersecting_pairs > 0
    # Slid 0.4 along the cut as well: faces apart in the material now cross by 1e-3, counted unless
    # they lie within `slid` of each other there.
    X[np.unique(result.tets[right]), 2] += 0.4
    slid = s.positions(result.tets, X)
    assert tetcut.count_surface_intersections(s, result.tets, slid, opened=2e-3).intersecting_pairs > 0
    assert tetcut.count_surface_intersections(s, result.tets, slid, opened=2e-3, slid=2.0).intersecting_pairs == 0


def test_a_session_keeps_its_scene_alive():
    import gc
    session = tetcut.Session(tetcut.parse_scene(
        '{"mesh": {"grid": {"box": [0, 0, 0, 1, 1, 1], "cells": [2, 2, 2]}}, "time": {"dt": 0.01, "duration": 0.05}}', "scene.json"))
    gc.collect()
    for _ in range(5):
        session.advance()
    assert session.steps == 5
