"""tetcut.sim: backward Euler FEM on (cut) tet meshes (the C++ tetcut::sim).

    material = tetcut.sim.Material(youngs_modulus=1e5, poissons_ratio=0.3, density=1000)
    sim = tetcut.sim.Simulator(result.vertices, result.tets, material, result.material_fractions)
    sim.pin(0)
    report = sim.step(tetcut.sim.StepOptions(dt=0.01))
"""

from ._tetcut.sim import FirstGuess, Material, Model, Obstacle, Simulator, StepOptions, StepReport, SurfaceContactOptions  # noqa: F401
