"""The simulator and the live session from Python: materials, pins and moves, obstacles, springs
and anchors, steps and static solves, a cut while simulating, and a session replayed by the CLI."""

import json
import subprocess
import threading

import numpy as np
import pytest

import tetcut
from tetcut import sim
from conftest import square

DENSITY = 1000.0


def block(cells=3):
    return tetcut.make_grid((0, 0, 0), (1, 1, 1), (cells, cells, cells), 5)


def hanging(cells=3, **material):
    V, T = block(cells)
    s = sim.Simulator(V, T, sim.Material(youngs_modulus=1e5, density=DENSITY, **material))
    top = np.flatnonzero(V[:, 2] > 0.999)
    for node in top:
        s.pin(int(node))
    return V, T, s, top


def test_materials_and_masses():
    V, T = block()
    for model in (sim.Model.corotated, sim.Model.stable_neo_hookean):
        s = sim.Simulator(V, T, sim.Material(model=model, youngs_modulus=2e5, poissons_ratio=0.4, density=DENSITY))
        assert s.num_nodes == len(V) and s.num_tets == len(T)
        assert s.masses.sum() == pytest.approx(DENSITY, rel=1e-12)
        assert s.elastic_energy() == pytest.approx(0, abs=1e-9)
        np.testing.assert_allclose(s.elastic_gradient(), 0, atol=1e-9)
    # Half the material, half the mass.
    half = sim.Simulator(V, T, sim.Material(density=DENSITY), np.full(len(T), 0.5))
    assert half.masses.sum() == pytest.approx(DENSITY / 2, rel=1e-12)
    with pytest.raises(tetcut.Error, match="Poisson"):
        sim.Material(poissons_ratio=0.5)
    with pytest.raises(tetcut.Error):
        sim.Simulator(V, T, sim.Material(), np.ones(3))


def test_a_hanging_block_sags_and_comes_to_rest_held_at_its_top():
    V, T, s, top = hanging()
    options = sim.StepOptions(dt=0.01)
    assert options.gravity.tolist() == [0, 0, -9.81]
    for _ in range(30):
        report = s.step(options)
        assert report.converged and report.newton_iterations >= 1
        # Pinned, not pressed into anything: no contact or spring term goes into the matrix.
        assert report.constraint_matrix_seconds == 0 and report.assemble_seconds > 0
    X = s.positions
    np.testing.assert_array_equal(X[top], V[top])  # pinned
    assert X[:, 2].min() < -1e-4  # sagged
    static = s.solve_static(options)
    assert static.converged
    np.testing.assert_allclose(s.velocities, 0)
    # At equilibrium the elastic forces carry the weight of the free nodes.
    free = np.setdiff1d(np.arange(len(V)), top)
    weight = s.masses[free].sum() * 9.81
    assert -s.elastic_gradient()[free, 2].sum() == pytest.approx(weight, rel=1e-4)


def test_the_real_time_budget_reports_its_residual():
    V, T, s, _ = hanging()
    options = sim.StepOptions.real_time(1 / 30)
    assert options.max_newton_iterations == 1 and options.max_cg_iterations == 30
    assert options.first_guess == sim.FirstGuess.prediction
    reports = [s.step(options) for _ in range(10)]
    options.first_guess = sim.FirstGuess.start  # Newton from where each step starts
    reports += [s.step(options) for _ in range(10)]
    assert all(r.newton_iterations - r.rescue_iterations <= 1 for r in reports)
    assert all(np.isfinite(r.residual) for r in reports)


def test_a_block_falls_onto_a_plane_and_stops_there():
    V, T = block(2)
    s = sim.Simulator(V + [0, 0, 0.2], T, sim.Material(youngs_modulus=1e5, density=DENSITY, mass_damping=2))
    surface = tetcut.Cutter(V, T).surface()
    s.set_contact_points(surface.vertex_tet, surface.vertex_weights)
    s.add_obstacle(sim.Obstacle.plane((0, 0, 0), (0, 0, 1)))
    assert s.contact_stiffness > 0
    momentum = []
    for _ in range(200):
        s.step(sim.StepOptions(dt=0.01))
        momentum.append(s.momentum()[2])
    assert momentum[10] < 0  # fell
    assert s.positions[:, 2].min() > -0.02  # held by the plane, within the penalty's give
    # It bounces on the penalty and the damping takes the bounce out.
    assert max(abs(p) for p in momentum[-20:]) < abs(min(momentum)) / 10
    d, direction = sim.Obstacle.sphere((0, 0, 0), 1).distance((0, 0, 2))
    assert d == pytest.approx(1) and direction.tolist() == [0, 0, 1]


def slide(mu):
    V, T = block(2)
    s = sim.Simulator(V, T, sim.Material(youngs_modulus=1e6, density=DENSITY))
    surface = tetcut.Cutter(V, T).surface()
    s.set_contact_points(surface.vertex_tet, surface.vertex_weights)
    ground = sim.Obstacle.plane((0, 0, 0), (0, 0, 1))
    ground.friction = mu
    s.add_obstacle(ground)
    for _ in range(20):
        s.step(sim.StepOptions(dt=0.005))
    v = s.velocities.copy()
    v[:, 0] = 1
    s.velocities = v
    start = s.positions[:, 0].mean()
    for _ in range(60):
        s.step(sim.StepOptions(dt=0.005))
    return s.positions[:, 0].mean() - start


def test_friction_against_an_obstacle_stops_a_sliding_block():
    assert slide(0.5) < 0.5 * slide(0.0)
    with pytest.raises(tetcut.Error):
        s = sim.Simulator(*block(1), sim.Material())
        bad = sim.Obstacle.plane((0, 0, 0), (0, 0, 1))
        bad.friction = -1
        s.add_obstacle(bad)


def test_moves_springs_and_anchors():
    V, T = block(2)
    s = sim.Simulator(V, T, sim.Material(youngs_modulus=1e4, density=DENSITY))
    corner = int(np.argmin(V.sum(axis=1)))
    s.move_to(corner, (-0.1, -0.1, -0.1))
    s.step(sim.StepOptions(dt=0.01, gravity=(0, 0, 0)))
    np.testing.assert_allclose(s.positions[corner], [-0.1, -0.1, -0.1])
    s.release(corner)
    # A spring from one tet's centre to another's pulls them together.
    centre = np.full(4, 0.25)
    s.add_spring(0, centre, len(T) - 1, centre, 1e4)
    assert s.num_springs == 1
    gap = np.linalg.norm(s.position(0, centre) - s.position(len(T) - 1, centre))
    for _ in range(5):
        s.step(sim.StepOptions(dt=0.01, gravity=(0, 0, 0)))
    assert np.linalg.norm(s.position(0, centre) - s.position(len(T) - 1, centre)) < gap
    s.clear_springs()
    assert s.num_springs == 0
    # An anchor (a hook) pulls its point toward the target.
    target = s.position(3, centre) + [0, 0, 0.5]
    s.set_anchors(np.array([3], dtype=np.int32), centre[None, :].copy(), target[None, :].copy(), np.array([1e4]))
    z0 = s.position(3, centre)[2]
    for _ in range(5):
        s.step(sim.StepOptions(dt=0.01, gravity=(0, 0, 0)))
    assert s.position(3, centre)[2] > z0 + 0.01
    with pytest.raises(ValueError, match="one row per anchor"):
        s.set_anchors(np.array([3], dtype=np.int32), centre[None, :].copy(), np.zeros((2, 3)), np.array([1.0]))
    with pytest.raises(ValueError, match="no tet copy"):
        s.add_spring(len(T), centre, 0, centre, 1.0)
    with pytest.raises(IndexError):
        s.pin(len(V))
    with pytest.raises(ValueError, match="finite"):
        s.move_to(0, (np.nan, 0, 0))


def test_cut_while_simulating():
    V, T = block(4)
    cutter = tetcut.Cutter(V, T)
    s = sim.Simulator(V, T, sim.Material(youngs_modulus=1e5, density=DENSITY))
    for node in np.flatnonzero(V[:, 2] > 0.999):
        s.pin(int(node))
    options = sim.StepOptions(dt=0.01)
    for _ in range(5):
        s.step(options)
    # A horizontal cut through the middle, placed where the block hangs now (world space).
    X = s.positions
    level = 0.5 + np.median(X[:, 2] - V[:, 2])
    PV, PF = square(2, level)
    batch = cutter.cut_deformed(PV, PF, X)
    assert batch.tets_touched > 0
    s.remesh(cutter, batch)
    assert s.num_nodes == cutter.num_nodes and s.num_tets == cutter.num_tets
    for _ in range(20):
        s.step(options)
    result = cutter.result()
    assert result.num_pieces == 2
    np.testing.assert_allclose(result.piece_volumes.sum(), 1, rtol=1e-12)
    # The lower piece falls away; the upper one stays hung.
    rest = result.vertices
    lower = np.unique(result.tets[result.tet_piece == result.tet_piece[np.argmin(rest[result.tets].mean(axis=1)[:, 2])]])
    assert s.positions[lower, 2].max() < rest[lower, 2].max() - 0.05


def test_long_calls_let_other_threads_run():
    # One long call (a static solve of a 20k-tet block from rest, some 150 ms), so that the count is
    # what this thread did while the call ran. Up to five such calls, each on a block at rest,
    # stopping at the first this thread counted through: with the GIL released a call lets it run,
    # but on a loaded machine (CI runs two tests at once, and the solve's own threads take both
    # cores) one call may pass without it getting a slice; held, every count is 0.
    options = sim.StepOptions(dt=0.01)
    options.tolerance = 1e-10
    for _ in range(5):
        V, T, s, _ = hanging(cells=16)
        counter = [0]
        during = {}

        def steps():
            before = counter[0]
            s.solve_static(options)
            during["count"] = counter[0] - before

        worker = threading.Thread(target=steps)
        worker.start()
        while worker.is_alive():
            counter[0] += 1
        worker.join()
        if during["count"] > 0:
            break
    # The GIL was released in the solve: this thread counted while it ran.
    assert during["count"] > 0  # held, it would be 0


SCENE = {
    "mesh": {"grid": {"box": [0, 0, 0, 1, 1, 1], "cells": [4, 4, 4], "tets_per_cube": 5}},
    "material": {"youngs_modulus": 1e5, "density": 100},
    "time": {"dt": 0.01, "duration": 0.3},
    "pin": [{"box": [-1, -1, 0.999, 2, 2, 2]}],
}


def test_a_session_cut_live_then_replayed_by_the_cli(tmp_path, cli):
    scene = tetcut.parse_scene(json.dumps(SCENE), str(tmp_path / "block.json"))
    session = tetcut.Session(scene)
    for _ in range(3):
        session.advance()
    # A stroke across the block at mid-height, a pose a step.
    for k in range(8):
        session.blade((-0.2 + 0.2 * k, -0.1, 0.53), (-0.2 + 0.2 * k, 1.1, 0.53))
        step = session.advance()
        assert step.seconds["step"] > 0
    session.lift_blade()
    assert session.cuts_applied == 7 and session.topology_changes >= 1
    hook = session.grab((0.5, 0.0, 0.8))
    assert hook == 0 and session.num_hooks == 1
    session.move_hook(hook, (0.5, -0.2, 0.8))
    session.advance()
    session.release(hook)
    session.pin((0.5, 0.5, 0.9), 0.2)
    session.unpin((0.5, 0.5, 0.9), 0.2)
    while session.time < 0.3 - 1e-9:
        session.advance()
    result = session.result()
    assert result.num_pieces == 2
    X = session.positions()
    assert X.shape == (len(result.vertices), 3)
    np.testing.assert_allclose(session.surface_positions(), session.surface().positions(session.tet_nodes(), X), atol=1e-12)
    # Bad events are refused and change nothing.
    with pytest.raises(tetcut.Error):
        session.release(7)
    with pytest.raises(ValueError, match="finite"):
        session.blade((np.nan, 0, 0), (1, 0, 0))
    # Replayed by tetcut sim: the same pieces and the same positions, bit for bit.
    tetcut.write_recording(tmp_path / "take.json", scene, session)
    subprocess.run([cli, "sim", tmp_path / "take.json", "-o", tmp_path / "replay"], check=True, capture_output=True)
    summary = json.loads((tmp_path / "replay" / "summary.json").read_text())
    assert summary["pieces"] == 2 and summary["steps"] == session.steps
    final = sorted((tmp_path / "replay").glob("mesh_*.vtu"))[-1]
    FV, FT = tetcut.read_tet_mesh(final)
    np.testing.assert_array_equal(FT, session.tet_nodes())
    np.testing.assert_array_equal(FV, X)


def test_a_scene_file_with_an_error_names_it(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"mesh": {"grid": {"box": [0, 0, 0, 1, 1, 1], "cells": [0, 1, 1]}}}')
    with pytest.raises(tetcut.Error) as caught:
        tetcut.load_scene(path)
    assert caught.value.file == str(path)


def test_state_setters_obstacle_boxes_and_the_rest_of_the_api():
    V, T = block(2)
    cutter = tetcut.Cutter(V, T)
    IV, IT = cutter.input_mesh()
    np.testing.assert_array_equal(IV, V)
    np.testing.assert_array_equal(IT, T)
    with pytest.raises(IndexError):
        cutter.copies_of(len(T))
    surface = cutter.surface()
    assert surface.triangle_tet.shape == (len(surface.triangles),)
    s = sim.Simulator(V, T, sim.Material())
    s.positions = V + [0, 0, 1]
    s.velocities = np.tile([1.0, 0, 0], (len(V), 1))
    np.testing.assert_allclose(s.momentum(), [s.masses.sum(), 0, 0])
    s.contact_stiffness = 123.0
    assert s.contact_stiffness == 123.0
    s.set_contact_points(surface.vertex_tet, surface.vertex_weights)
    s.add_obstacle(sim.Obstacle.box((-1, -1, -1), (2, 2, 0)))  # a table top at z = 0, far below
    d, _ = sim.Obstacle.box((0, 0, 0), (1, 1, 1)).distance((0.5, 0.5, 2))
    assert d == pytest.approx(1)
    s.step(sim.StepOptions(dt=0.01, gravity=(0, 0, 0)))
    assert s.positions[:, 0].mean() > V[:, 0].mean()  # coasting along x
    with pytest.raises(ValueError, match="positions must be a float64 array of shape"):
        s.positions = V[:, :2].copy()
    with pytest.raises(tetcut.Error, match="wrong size"):
        s.positions = V[:3].copy()


def test_surface_contact_keeps_a_falling_block_on_another():
    # Two unit blocks, the upper 0.1 above the lower, which stands on the ground: with surface
    # contact the upper one comes to rest on top; without, it falls through to the ground.
    a = tetcut.make_grid([0, 0, 0], [1, 1, 1], [3, 3, 3])
    b = tetcut.make_grid([0.05, 0.02, 1.1], [1.05, 1.02, 2.1], [3, 3, 3])
    V = np.vstack([a[0], b[0]])
    T = np.vstack([a[1], b[1] + len(a[0])]).astype(np.int32)
    cutter = tetcut.Cutter(V, T)
    surface = cutter.surface()

    def lowest_of_upper(contact):
        sim = tetcut.sim.Simulator(V, T, tetcut.sim.Material(youngs_modulus=1e6, mass_damping=4))
        if contact:
            sim.set_contact_surface(surface, tetcut.sim.SurfaceContactOptions(friction=0.2))
            assert sim.surface_contact()["enabled"]
            assert sim.surface_contact()["joined_copy_pairs"] == 0
        sim.set_contact_points(surface.vertex_tet, surface.vertex_weights)
        sim.add_obstacle(tetcut.sim.Obstacle.plane([0, 0, -0.1], [0, 0, 1]))
        for _ in range(100):
            report = sim.step(tetcut.sim.StepOptions(dt=0.01))
        if contact:
            seconds = sim.surface_contact()["seconds"]
            assert set(seconds) == {"rebuild", "ccd", "active", "guards", "joins"}
            assert seconds["rebuild"] > 0 and seconds["active"] > 0
        upper = V[:, 2] > 1.05
        return sim.positions[upper, 2].min(), report

    with_contact, report = lowest_of_upper(True)
    assert with_contact > 0.85
    assert report.contact_pairs > 0
    without, _ = lowest_of_upper(False)
    assert without < 0
    with pytest.raises(tetcut.Error):
        tetcut.sim.Simulator(V, T, tetcut.sim.Material()).set_contact_surface(surface, tetcut.sim.SurfaceContactOptions(thickness=-1))
    assert tetcut.sim.SurfaceContactOptions(cushion=1).cushion == 1
    with pytest.raises(tetcut.Error):
        tetcut.sim.Simulator(V, T, tetcut.sim.Material()).set_contact_surface(surface, tetcut.sim.SurfaceContactOptions(cushion=-1))
