#!/usr/bin/env python3
"""Cut a hanging block with a scalpel while it is simulated, from Python, and write a ParaView
series (open OUT/mesh.pvd or OUT/surface.pvd in ParaView and press play).

    PYTHONPATH=build/release/python python3 examples/python/cut_and_simulate.py out/python [--steps N]

A BCC block hangs from its top edge; after it has settled a little, a blade sweeps across it in
world space, each pose mapped into the material through the motion at that moment (as a surgeon's
blade follows the tissue); the simulator takes each cut batch as it comes, and the freed lower part
falls away.
"""

import argparse
import pathlib

import numpy as np

import tetcut
from tetcut import sim


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=pathlib.Path, help="output folder (created)")
    parser.add_argument("--steps", type=int, default=90, help="time steps of 1/60 s (default 90)")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    V, T = tetcut.make_bcc((0, 0, 0), (1, 0.4, 1), 0.1)
    cutter = tetcut.Cutter(V, T)
    simulator = sim.Simulator(V, T, sim.Material(youngs_modulus=2e5, poissons_ratio=0.35, density=1000, mass_damping=1))
    top = V[:, 2].max()
    for node in np.flatnonzero(V[:, 2] > top - 1e-9):
        simulator.pin(int(node))
    options = sim.StepOptions(dt=1 / 60)

    meshes, surfaces = [], []
    blade_start, blade_end = 20, 50  # the blade crosses the block between these steps
    previous = None
    for step in range(args.steps + 1):
        if blade_start <= step <= blade_end:
            # The blade's edge, through the block's thickness, at mid-height, moving along x.
            x = -0.2 + 1.4 * (step - blade_start) / (blade_end - blade_start)
            world = np.array([[x, -0.2, 0.45], [x, 0.6, 0.45]])
            # Followed in the material: the pose mapped to rest space through the motion now, and
            # the strip since the last pose cut there, so that consecutive strips meet exactly.
            cutter.set_current(simulator.positions)
            pose = cutter.to_rest(world)
            if previous is not None:
                back = np.ascontiguousarray(np.stack([previous[0], pose[0]]))
                tip = np.ascontiguousarray(np.stack([previous[1], pose[1]]))
                batch = cutter.cut(*tetcut.swept_blade(back, tip))
                if batch.tets_touched:
                    simulator.remesh(cutter, batch)
            previous = pose
        if step % 3 == 0:
            frame = step // 3
            result = cutter.result()
            X = simulator.positions
            mesh_file, surface_file = f"mesh_{frame:04d}.vtu", f"surface_{frame:04d}.vtp"
            tetcut.write_tet_mesh(args.out / mesh_file, X, result.tets,
                                  cell_fields={"piece": result.tet_piece.astype(np.float64),
                                               "material_fraction": result.material_fractions})
            s = result.surface
            tetcut.write_surface(args.out / surface_file, s.positions(result.tets, X), s.triangles)
            meshes.append((step * options.dt, mesh_file))
            surfaces.append((step * options.dt, surface_file))
        if step < args.steps:
            simulator.step(options)

    tetcut.write_series(args.out / "mesh.pvd", meshes)
    tetcut.write_series(args.out / "surface.pvd", surfaces)
    result = cutter.result()
    print(f"{len(T)} tets cut into {result.num_pieces} pieces ({len(result.tets)} tet copies); "
          f"piece volumes {np.round(result.piece_volumes, 4).tolist()} (sum {result.piece_volumes.sum():.6f}, "
          f"block {0.4:.6f}); {len(meshes)} frames in {args.out}")


if __name__ == "__main__":
    main()
