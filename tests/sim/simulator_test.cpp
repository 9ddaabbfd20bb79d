// The integrator on analytic cases: the patch test, a clamped cantilever against Euler-Bernoulli,
// free fall, and a cube cut in two falling apart.

#include <gtest/gtest.h>

#include <tetcut/blade.hpp>
#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/sim.hpp>

#include <tbb/task_arena.h>

#include <cmath>
#include <limits>

namespace tetcut::sim {
namespace {

class Integrator : public ::testing::TestWithParam<Model> {};

// Every tet's corners as contact points.
std::vector<EmbeddedPoint> corner_points(const TetMesh& mesh) {
  std::vector<EmbeddedPoint> points;
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    for (int k = 0; k < 4; ++k) {
      EmbeddedPoint p{t, Eigen::Vector4d::Zero()};
      p.weights[k] = 1;
      points.push_back(p);
    }
  }
  return points;
}

TEST_P(Integrator, PatchTestAffineDeformationHasNoInteriorForces) {
  const TetMesh grid = make_grid(Box{}, {3, 3, 3}, 6);
  Material material;
  material.model = GetParam();
  Simulator sim(grid, material);
  Mat3 A;
  A << 1.1, 0.05, -0.02, 0.03, 0.95, 0.04, -0.01, 0.02, 1.03;
  const Vec3 shift(0.3, -0.2, 0.1);
  Points x = grid.rest();
  for (Index v = 0; v < x.rows(); ++v) x.row(v) = (A * grid.rest().row(v).transpose() + shift).transpose();
  sim.set_positions(x);
  // Constant stress: the energy is the density at A times the volume.
  const Lame p = model_parameters(GetParam(), lame_parameters(material.youngs_modulus, material.poissons_ratio));
  EXPECT_NEAR(sim.elastic_energy(), energy_density(GetParam(), p, A), 1e-10 * p.mu);
  // Interior nodes feel no force; boundary nodes carry the traction P n (non-zero).
  const Points g = sim.elastic_gradient();
  double interior = 0, boundary = 0;
  for (Index v = 0; v < x.rows(); ++v) {
    const Vec3 X = grid.rest().row(v).transpose();
    const bool inside = (X.array() > 1e-9).all() && (X.array() < 1 - 1e-9).all();
    (inside ? interior : boundary) = std::max(inside ? interior : boundary, g.row(v).norm());
  }
  EXPECT_LT(interior, 1e-9 * boundary);
  EXPECT_GT(boundary, 0);
  // Sum of all forces vanishes (translation invariance).
  EXPECT_LT(g.colwise().sum().norm(), 1e-9 * boundary);
}

TEST_P(Integrator, CantileverDeflectsAsEulerBernoulli) {
  // A beam 1 long, 0.1 x 0.1 in section, clamped at x = 0, under its own weight: the tip deflects
  // q L^4 / (8 E I) with q = rho g A and I = a^4 / 12. Small deflection (1e-3 of the length), nu
  // = 0 so that the beam theory's assumptions hold; fine enough in section for linear tets.
  const double length = 1, a = 0.1;
  const int across = 8;
  const TetMesh beam = make_grid(Box{Vec3(0, 0, 0), Vec3(length, a, a)}, {10 * across, across, across}, 6);
  Material material;
  material.model = GetParam();
  material.youngs_modulus = 1.5e9;
  material.poissons_ratio = 0;
  material.density = 1000;
  Simulator sim(beam, material);
  for (Index v = 0; v < beam.num_nodes(); ++v) {
    if (beam.rest()(v, 0) == 0) sim.pin(v);
  }
  StepOptions options;
  options.tolerance = 1e-9;
  const StepReport report = sim.solve_static(options);
  EXPECT_TRUE(report.converged);
  const double q = material.density * 9.81 * a * a, inertia = std::pow(a, 4) / 12;
  const double expected = q * std::pow(length, 4) / (8 * material.youngs_modulus * inertia);
  // Tip deflection: mean over the tip's nodes.
  double tip = 0;
  int count = 0;
  for (Index v = 0; v < beam.num_nodes(); ++v) {
    if (beam.rest()(v, 0) != length) continue;
    tip += sim.positions()(v, 2) - beam.rest()(v, 2);
    ++count;
  }
  tip /= count;
  EXPECT_NEAR(-tip, expected, 0.05 * expected) << "tip " << -tip << " vs " << expected;
  RecordProperty("tip_over_euler_bernoulli", std::to_string(-tip / expected));
}

TEST_P(Integrator, FreeFallGainsGravitysImpulse) {
  const TetMesh cube = make_grid(Box{}, {2, 2, 2}, 5);
  Material material;
  material.model = GetParam();
  Simulator sim(cube, material);
  StepOptions options;
  options.dt = 0.01;
  for (int s = 0; s < 10; ++s) EXPECT_TRUE(sim.step(options).converged);
  const double mass = sim.masses().sum();
  EXPECT_NEAR(mass, material.density * 1.0, 1e-9 * mass);
  const Vec3 expected = mass * options.gravity * 0.1;
  EXPECT_LT((sim.momentum() - expected).norm(), 1e-8 * expected.norm());
  // Rigid fall: no deformation.
  EXPECT_LT(sim.elastic_energy(), 1e-12 * material.youngs_modulus);
}

TEST_P(Integrator, CubeCutInTwoFallsApart) {
  // A cube cut by the plane x = 0.43: two pieces sharing no node. Thrown apart sideways while
  // falling, their momentum changes by gravity's impulse only and they separate.
  const TetMesh cube = figures::figure4_cube();
  Cutter cutter(cube);
  cutter.cut(figures::axis_square(0, 0.43, -1, 2));
  const CutResult cut = cutter.result();
  ASSERT_EQ(cut.mesh.num_pieces(), 2);
  std::vector<Index> piece_of_node(static_cast<std::size_t>(cut.mesh.mesh.num_nodes()), -1);
  for (Index c = 0; c < cut.mesh.mesh.num_tets(); ++c) {
    for (int k = 0; k < 4; ++k) {
      Index& piece = piece_of_node[cut.mesh.mesh.tets()(c, k)];
      if (piece < 0) piece = cut.mesh.tet_piece[c];
      ASSERT_EQ(piece, cut.mesh.tet_piece[c]) << "a node is shared by both pieces";
    }
  }
  const std::vector<double> fraction = cut.mesh.material_fractions();
  Material material;
  material.model = GetParam();
  Simulator sim(cut.mesh.mesh, material, fraction);
  // Piece 0 is the larger, right one (x > 0.43): push it right and piece 1 left.
  Points v = Points::Zero(sim.num_nodes(), 3);
  for (Index n = 0; n < sim.num_nodes(); ++n) v(n, 0) = piece_of_node[n] == 0 ? 1 : -1;
  sim.set_velocities(v);
  const Vec3 start_momentum = sim.momentum();
  const auto centroid_gap = [&] {
    Vec3 moment[2] = {Vec3::Zero(), Vec3::Zero()};
    double mass[2] = {0, 0};
    for (Index n = 0; n < sim.num_nodes(); ++n) {
      moment[piece_of_node[n]] += sim.masses()[n] * sim.positions().row(n).transpose();
      mass[piece_of_node[n]] += sim.masses()[n];
    }
    return (moment[0] / mass[0] - moment[1] / mass[1])[0];
  };
  const double gap_before = centroid_gap();
  StepOptions options;
  options.dt = 0.01;
  for (int s = 0; s < 20; ++s) ASSERT_TRUE(sim.step(options).converged);
  const Vec3 expected = start_momentum + sim.masses().sum() * options.gravity * 0.2;
  EXPECT_LT((sim.momentum() - expected).norm(), 1e-8 * expected.norm());
  // Each piece moved 0.2 sideways as a rigid body: the centroids are 0.4 further apart, and
  // nothing deformed.
  EXPECT_NEAR(centroid_gap() - gap_before, 0.4, 1e-6);
  EXPECT_LT(sim.elastic_energy(), 1e-9 * material.youngs_modulus);
}

TEST(Obstacle, SignedDistanceAndDirection) {
  Vec3 n;
  EXPECT_DOUBLE_EQ(Obstacle::plane(Vec3(0, 0, 1), Vec3(0, 0, 2)).distance(Vec3(5, 5, 0.5), &n), -0.5);
  EXPECT_EQ(n, Vec3(0, 0, 1));
  EXPECT_DOUBLE_EQ(Obstacle::sphere(Vec3(1, 0, 0), 0.5).distance(Vec3(1, 0.2, 0), &n), -0.3);
  EXPECT_LT((n - Vec3(0, 1, 0)).norm(), 1e-15);
  const Obstacle box = Obstacle::box(Vec3(0, 0, 0), Vec3(1, 2, 3));
  EXPECT_NEAR(box.distance(Vec3(0.5, 1.9, 1.5), &n), -0.1, 1e-15);
  EXPECT_LT((n - Vec3(0, 1, 0)).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(box.distance(Vec3(4, 2, 3), &n), 3);
  EXPECT_EQ(n, Vec3(1, 0, 0));
}

TEST_P(Integrator, CubeComesToRestOnTheGround) {
  // Dropped from 0.05 above the ground, its corners' contact keeps it above the plane up to the
  // penalty's compliance, and damping brings it to rest.
  const TetMesh cube = make_grid(Box{Vec3(0, 0, 0.05), Vec3(0.2, 0.2, 0.25)}, {2, 2, 2}, 5);
  Material material;
  material.model = GetParam();
  material.youngs_modulus = 1e6;
  material.mass_damping = 2;
  Simulator sim(cube, material);
  const std::vector<EmbeddedPoint> points = corner_points(cube);
  sim.set_contact_points(points);
  sim.add_obstacle(Obstacle::plane(Vec3::Zero(), Vec3(0, 0, 1)));
  StepOptions options;
  options.dt = 0.01;
  for (int s = 0; s < 150; ++s) ASSERT_TRUE(sim.step(options).converged) << "step " << s;
  double lowest = 1e300;
  for (const EmbeddedPoint& p : points) lowest = std::min(lowest, sim.position(p)[2]);
  // Weight m g shared by the bottom points, each pushed by k d: d <= m g / k.
  const double weight = sim.masses().sum() * 9.81;
  EXPECT_LT(lowest, 0.0) << "resting on the ground means a little penetration";
  EXPECT_GT(lowest, -weight / sim.contact_stiffness());
  EXPECT_LT(sim.velocities().cwiseAbs().maxCoeff(), 1e-3);
}

// The report's share of assembly spent adding constraint terms into the Newton matrix: none while
// nothing touches (no term), some once the block's points press into the ground (a term each),
// and never more than the assembly it is part of. No time is asserted, only where it is counted.
TEST(StepReport, ConstraintMatrixTimeCountsOnlyWhileTermsExist) {
  const TetMesh cube = make_grid(Box{Vec3(0, 0, 0.05), Vec3(0.2, 0.2, 0.25)}, {2, 2, 2}, 5);
  Material material;
  material.youngs_modulus = 1e6;
  Simulator sim(cube, material);
  sim.set_contact_points(corner_points(cube));
  sim.add_obstacle(Obstacle::plane(Vec3::Zero(), Vec3(0, 0, 1)));
  StepOptions options;
  options.dt = 0.01;
  const StepReport falling = sim.step(options);
  EXPECT_EQ(falling.constraint_matrix_seconds, 0.0) << "0.05 above the ground: no point touches";
  bool pressed = false;
  for (int s = 0; s < 60 && !pressed; ++s) {
    const StepReport report = sim.step(options);
    EXPECT_LE(report.constraint_matrix_seconds, report.assemble_seconds);
    pressed = report.constraint_matrix_seconds > 0;
  }
  EXPECT_TRUE(pressed) << "the block lands within 0.6 s and its points press into the ground";
}

// A block resting on the ground is pushed sideways at v0: with friction mu it slides
// v0^2 / (2 mu g) and stops (Coulomb); without, it keeps going.
double slide_on_the_ground(Model model, double mu, Vec3* final_velocity) {
  const TetMesh block = make_grid(Box{Vec3(0, 0, 0), Vec3(0.2, 0.2, 0.1)}, {2, 2, 1}, 5);
  Material material;
  material.model = model;
  material.youngs_modulus = 1e6;
  Simulator sim(block, material);
  const std::vector<EmbeddedPoint> points = corner_points(block);
  sim.set_contact_points(points);
  sim.add_obstacle(Obstacle::plane(Vec3::Zero(), Vec3(0, 0, 1)).with_friction(mu));
  StepOptions options;
  options.dt = 0.005;
  // Settle onto the ground first, so that the normal force carries the weight.
  for (int s = 0; s < 40; ++s) sim.step(options);
  const auto centre_x = [&] { return sim.positions().col(0).mean(); };
  const double start = centre_x();
  Points v = sim.velocities();
  v.col(0).setConstant(1.0);
  sim.set_velocities(v);
  for (int s = 0; s < 80; ++s) EXPECT_TRUE(sim.step(options).converged) << "step " << s;  // 0.4 s
  *final_velocity = Vec3(sim.velocities().col(0).mean(), sim.velocities().col(1).mean(), sim.velocities().col(2).mean());
  return centre_x() - start;
}

TEST_P(Integrator, FrictionOnTheGroundStopsASlidingBlockAsCoulombSays) {
  Vec3 velocity;
  const double mu = 0.5, stopping = 1.0 / (2 * mu * 9.81);  // 0.102 m, after 0.204 s
  const double slid = slide_on_the_ground(GetParam(), mu, &velocity);
  EXPECT_NEAR(slid, stopping, 0.1 * stopping);
  EXPECT_LT(velocity.norm(), 0.02);  // at rest
  const double free = slide_on_the_ground(GetParam(), 0, &velocity);
  EXPECT_GT(free, 0.35);  // 0.4 m at 1 m/s, less what the settling left
  EXPECT_NEAR(velocity.x(), 1.0, 0.05);
}

TEST_P(Integrator, SpringsKeepAnIncisionClosed) {
  // A block cut from the top down to half its height by x = 0.51; its top corners are pulled apart
  // sideways. Without springs the incision opens; with springs between its two sides it stays shut.
  const TetMesh block = make_grid(Box{}, {4, 4, 4}, 6);
  Cutter cutter(block);
  TriangleSurface incision;
  incision.vertices.resize(4, 3);
  incision.vertices << 0.51, -1, 0.5, 0.51, 2, 0.5, 0.51, 2, 2, 0.51, -1, 2;
  incision.triangles.resize(2, 3);
  incision.triangles << 0, 1, 2, 0, 2, 3;
  cutter.cut(incision);
  const CutResult cut = cutter.result();
  ASSERT_EQ(cut.mesh.num_pieces(), 1);
  const auto pairs = incision_pairs(cut.surface, 0, 2);
  ASSERT_GT(pairs.size(), 10u);
  const auto widest_gap = [&](bool springs) {
    std::vector<double> fraction(static_cast<std::size_t>(cut.mesh.mesh.num_tets()), 1.0);
    Material material;
    material.model = GetParam();
    Simulator sim(cut.mesh.mesh, material, fraction);
    for (Index n = 0; n < sim.num_nodes(); ++n) {
      const Vec3 X = cut.mesh.mesh.rest().row(n).transpose();
      if (X[2] == 0) sim.pin(n);
      if (X[2] == 1 && (X[0] == 0 || X[0] == 1)) sim.move_to(n, X + Vec3(X[0] == 0 ? -0.1 : 0.1, 0, 0));
    }
    if (springs) {
      for (const auto& [p, q] : pairs) sim.add_spring(p, q, 100 * sim.contact_stiffness());
    }
    StepOptions options;
    options.gravity = Vec3::Zero();
    EXPECT_TRUE(sim.solve_static(options).converged);
    double gap = 0;
    for (const auto& [p, q] : pairs) gap = std::max(gap, (sim.position(p) - sim.position(q)).norm());
    return gap;
  };
  const double open = widest_gap(false), closed = widest_gap(true);
  EXPECT_GT(open, 0.05);
  EXPECT_LT(closed, 0.01 * open);
}

TEST_P(Integrator, CuttingWhileFallingCarriesTheStateOver) {
  // A falling cube is cut in two mid-flight (in world space, where it is now): the new nodes
  // start where and as fast as the nodes they were split from, so nothing jumps, and the pieces
  // keep falling together.
  const TetMesh cube = figures::figure4_cube();
  Cutter cutter(cube);
  Material material;
  material.model = GetParam();
  Simulator sim(cube, material);
  StepOptions options;
  options.dt = 0.01;
  // Positions are compared at 1e-9 below: each step must be settled that finely (the default
  // tolerance settles them to about 1e-7 of the mesh size).
  options.tolerance = 1e-11;
  for (int s = 0; s < 10; ++s) ASSERT_TRUE(sim.step(options).converged);
  const Vec3 momentum_before = sim.momentum();
  const double drop = sim.positions()(0, 2) - cube.rest()(0, 2);
  cutter.set_current(sim.positions());
  const CutBatchReport batch = cutter.cut_deformed(figures::axis_square(0, 0.43, -1, 2));
  ASSERT_GT(batch.new_node_source.size(), 0u);
  const CutResult cut = cutter.result();
  const std::vector<double> fraction = cut.mesh.material_fractions();
  sim.remesh(cut.mesh.mesh, fraction, batch.first_new_node, batch.new_node_source);
  ASSERT_EQ(sim.num_nodes(), cut.mesh.mesh.num_nodes());
  // Every node sits where the uncut cube's node it copies sits: the cube fell rigidly.
  for (Index n = 0; n < sim.num_nodes(); ++n) {
    const Vec3 expected = cube.rest().row(cut.mesh.node_parent[n]).transpose() + Vec3(0, 0, drop);
    EXPECT_LT((sim.positions().row(n).transpose() - expected).norm(), 1e-9) << "node " << n;
  }
  // The copies hold the same material as before (fractions), so the mass is the same and the
  // momentum carries over up to the mass moved into the copies of cut tets (kept exactly: the
  // material of each cut tet is split, not duplicated).
  EXPECT_NEAR(sim.masses().sum(), material.density, 1e-9 * material.density);
  EXPECT_LT((sim.momentum() - momentum_before).norm(), 1e-9 * momentum_before.norm());
  for (int s = 0; s < 10; ++s) ASSERT_TRUE(sim.step(options).converged);
  EXPECT_LT(sim.elastic_energy(), 1e-9 * material.youngs_modulus);
}

TEST_P(Integrator, StiffnessDampingTakesEnergyOut) {
  // A bar hanging from its top, released slightly stretched, oscillates. With a time step far
  // below its period the integrator's own dissipation is small, so without damping the energy
  // stays; Rayleigh stiffness damping (modal damping ratio beta omega / 2) takes a good part out.
  const TetMesh bar = make_grid(Box{Vec3(0, 0, 0), Vec3(0.2, 0.2, 1)}, {1, 1, 5}, 5);
  const auto energies = [&](double beta) {
    Material material;
    material.model = GetParam();
    material.stiffness_damping = beta;
    Simulator sim(bar, material);
    for (Index n = 0; n < bar.num_nodes(); ++n) {
      if (bar.rest()(n, 2) == 1) sim.pin(n);
    }
    Points stretched = bar.rest();
    stretched.col(2) = (stretched.col(2).array() - 1) * 1.01 + 1;
    sim.set_positions(stretched);
    const double start = sim.elastic_energy();
    StepOptions options;
    options.gravity = Vec3::Zero();
    options.dt = 2e-4;
    for (int s = 0; s < 200; ++s) EXPECT_TRUE(sim.step(options).converged);
    return std::pair(start, sim.kinetic_energy() + sim.elastic_energy());
  };
  const auto [start, undamped] = energies(0);
  const auto [start_again, damped] = energies(0.05);
  EXPECT_GT(start, 0);
  EXPECT_GT(undamped, 0.9 * start);
  EXPECT_LT(damped, 0.8 * start);
}

TEST_P(Integrator, RemeshFromTheCutterMatchesRemeshFromTheResult) {
  // A block hanging from its top is cut by a blade, a strip per step, and simulated twice: once
  // remeshed from each batch's full result (a new TetMesh), once straight from the cutter. Same
  // elements and masses (the same bits), so the same motion.
  const TetMesh block = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}, 0.25);
  Cutter from_result(block), from_cutter(block);
  Material material;
  material.model = GetParam();
  Simulator a(block, material), b(block, material);
  for (Index n = 0; n < block.num_nodes(); ++n) {
    if (block.rest()(n, 2) == 1) {
      a.pin(n);
      b.pin(n);
    }
  }
  StepOptions options;
  options.dt = 0.01;
  options.reuse_hessian = 1;  // the full-mesh remesh cannot reuse a matrix: compare like with like
  for (int frame = 0; frame < 8; ++frame) {
    const double x0 = -0.1 + 0.15 * frame, x1 = x0 + 0.15;
    const std::vector<BladePose> poses{{Vec3(x0, 0.45, -0.2), Vec3(x0, 0.45, 0.6)}, {Vec3(x1, 0.45, -0.2), Vec3(x1, 0.45, 0.6)}};
    const TriangleSurface strip = swept_blade(poses);
    const CutBatchReport batch_a = from_result.cut(strip);
    const CutBatchReport batch_b = from_cutter.cut(strip);
    const CutResult result = from_result.result();
    std::vector<double> fraction = result.mesh.material_fractions();
    for (double& f : fraction) f = std::min(f, 1.0);
    a.remesh(result.mesh.mesh, fraction, batch_a.first_new_node, batch_a.new_node_source);
    b.remesh(from_cutter, batch_b);
    ASSERT_EQ(a.num_tets(), b.num_tets());
    ASSERT_EQ(a.num_nodes(), b.num_nodes());
    for (Index n = 0; n < a.num_nodes(); ++n) ASSERT_EQ(a.masses()[n], b.masses()[n]) << "node " << n;
    ASSERT_TRUE(a.step(options).converged);
    ASSERT_TRUE(b.step(options).converged);
    // The SVDs' warm starts differ (a cut copy starts from its source's in b), within the
    // Hessian's tolerance: the steps agree far below the Newton tolerance.
    EXPECT_LT((a.positions() - b.positions()).cwiseAbs().maxCoeff(), 1e-9) << "frame " << frame;
  }
  EXPECT_GT(a.num_tets(), block.num_tets());
}

INSTANTIATE_TEST_SUITE_P(BothModels, Integrator, ::testing::Values(Model::kCorotated, Model::kStableNeoHookean));

// A block 1 x 1 x 2 hanging from its top (BCC), the benchmark in small.
TetMesh hanging_block() { return make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 2)}, 0.25); }
void pin_top(const TetMesh& mesh, Simulator* sim) {
  const double top = mesh.rest().col(2).maxCoeff();
  for (Index n = 0; n < mesh.num_nodes(); ++n) {
    if (mesh.rest()(n, 2) == top) sim->pin(n);
  }
}

TEST_P(Integrator, TheSameBitsOnOneThreadAndOnTwo) {
  // Assembly, solves and sums run in fixed chunks and colours: a run cut in mid-swing ends in
  // the same positions, bit for bit, whatever the threads.
  const TetMesh block = hanging_block();
  const auto run = [&](int threads) {
    Points x;
    tbb::task_arena(threads).execute([&] {
      Cutter cutter(block);
      Material material;
      material.model = GetParam();
      Simulator sim(block, material);
      pin_top(block, &sim);
      StepOptions options;
      options.dt = 0.01;
      for (int s = 0; s < 20; ++s) {
        if (s == 8) {
          cutter.set_current(sim.positions());
          sim.remesh(cutter, cutter.cut_deformed(figures::axis_square(2, 1.03, -1, 2)));
        }
        sim.step(options);
      }
      x = sim.positions();
    });
    return x;
  };
  const Points one = run(1), two = run(2);
  ASSERT_EQ(one.rows(), two.rows());
  EXPECT_TRUE(one == two) << "largest difference " << (one - two).cwiseAbs().maxCoeff();
}

TEST_P(Integrator, ACutMeshStepsAsStablyAsTheUncutOne) {
  // No new time step restriction: copies are whole tets (a sliver of material keeps its tet's
  // shape and 1% of its mass), so the dt the uncut block takes, the cut one takes too. Cuts
  // through the block (the lower part falls), an incision, and one just off a lattice plane
  // (copies holding slivers).
  const TetMesh block = hanging_block();
  const auto run = [&](bool cut) {
    Cutter cutter(block);
    if (cut) {
      cutter.cut(figures::axis_square(2, 1.0 + 1e-3, -1, 2));   // through, next to a node layer
      cutter.cut(figures::axis_square(0, 0.52, 1.2, 2.5));      // an incision from the top
      cutter.cut(figures::axis_square(1, 0.5 + 1e-4, -1, 0.7));  // slivers near the bottom
    }
    const CutResult r = cutter.result();
    std::vector<double> fraction = r.mesh.material_fractions();
    for (double& f : fraction) f = std::min(f, 1.0);
    Material material;
    material.model = GetParam();
    Simulator sim(r.mesh.mesh, material, fraction);
    pin_top(r.mesh.mesh, &sim);
    StepOptions options;
    options.dt = 1.0 / 30;  // a large step for this block
    int newton = 0;
    for (int s = 0; s < 30; ++s) {
      const StepReport report = sim.step(options);
      EXPECT_TRUE(report.converged) << (cut ? "cut" : "uncut") << ", step " << s;
      EXPECT_TRUE(std::isfinite(report.energy));
      newton += report.newton_iterations;
    }
    EXPECT_TRUE(sim.positions().allFinite());
    return std::pair(newton, r.mesh.num_pieces());
  };
  const auto [uncut_newton, uncut_pieces] = run(false);
  const auto [cut_newton, cut_pieces] = run(true);
  EXPECT_EQ(uncut_pieces, 1);
  EXPECT_GE(cut_pieces, 2);
  EXPECT_LE(cut_newton, 2 * uncut_newton) << "Newton iterations: " << cut_newton << " cut, " << uncut_newton << " uncut";
}

TEST_P(Integrator, RealTimeBudgetReportsWhatItLeft) {
  // A stiff block at a large step: the Newton system needs many CG iterations. A budget of a few
  // leaves a residual above the tolerance, and says so; more iterations leave less; the
  // converged step leaves at most the tolerance. What the budget costs: the tip's sag.
  const TetMesh block = hanging_block();
  const auto run = [&](const StepOptions& options, double* residual) {
    Material material;
    material.model = GetParam();
    material.youngs_modulus = 1e6;
    Simulator sim(block, material);
    pin_top(block, &sim);
    *residual = 0;
    for (int s = 0; s < 10; ++s) {
      const StepReport report = sim.step(options);
      if (options.max_cg_iterations > 0) {
        EXPECT_LE(report.cg_iterations, options.max_newton_iterations * options.max_cg_iterations);
        EXPECT_LE(report.newton_iterations, options.max_newton_iterations);
      }
      if (report.converged) {
        EXPECT_LE(report.residual, options.tolerance);
      }
      *residual = std::max(*residual, report.residual);
    }
    return sim.positions().col(2).minCoeff();
  };
  StepOptions converged;
  converged.dt = 0.02;
  double converged_residual, small_residual, large_residual;
  const double converged_tip = run(converged, &converged_residual);
  const double small_tip = run(StepOptions::real_time(0.02, 1, 3), &small_residual);
  const double large_tip = run(StepOptions::real_time(0.02, 1, 40), &large_residual);
  EXPECT_LE(converged_residual, converged.tolerance);
  EXPECT_GT(small_residual, converged.tolerance);
  EXPECT_LT(large_residual, small_residual);
  const double sag = block.rest().col(2).minCoeff() - converged_tip;
  EXPECT_GT(sag, 0);
  // Measured here: 3 iterations a step miss the sag by about three quarters after 10 steps, 40 by
  // well under a percent.
  EXPECT_LT(std::abs(large_tip - converged_tip), 0.01 * sag);
  EXPECT_GT(std::abs(small_tip - converged_tip), std::abs(large_tip - converged_tip));
}

TEST_P(Integrator, RealTimeStepsInSinglePrecisionMatchDouble) {
  // A block big enough that the real-time mode stores its Newton matrix in single precision
  // (past 8 MB): the same motion as with the matrix in double, to the budget's own accuracy.
  const TetMesh block = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 2)}, 0.072);
  ASSERT_GT(block.num_tets(), 60000);
  const auto run = [&](bool single) {
    Material material;
    material.model = GetParam();
    Simulator sim(block, material);
    pin_top(block, &sim);
    StepOptions options = StepOptions::real_time(0.01);
    options.single_precision_matrix = single;
    for (int s = 0; s < 6; ++s) sim.step(options);
    return sim.positions();
  };
  const Points single = run(true), twice = run(false);
  const double size = (block.rest().colwise().maxCoeff() - block.rest().colwise().minCoeff()).norm();
  EXPECT_LT((single - twice).cwiseAbs().maxCoeff(), 1e-6 * size);
  EXPECT_GT((single - twice).cwiseAbs().maxCoeff(), 0.0);  // single precision was used
}

TEST_P(Integrator, AConvergedStepIsSettledToTheTolerance) {
  // The default tolerance promises a step's positions settled to about 1e-7 of the mesh's size,
  // in the mass-weighted mean (the test bounds half the Newton decrement by tolerance^2 M (L /
  // dt)^2). Along a trajectory solved to 1e-12, each step taken again from there at the default
  // tolerance (with whatever Newton matrix it would reuse) lands within twice that.
  const TetMesh block = hanging_block();
  Material material;
  material.model = GetParam();
  Simulator tight(block, material);
  pin_top(block, &tight);
  StepOptions options, tight_options;
  options.dt = tight_options.dt = 0.01;
  tight_options.tolerance = 1e-12;
  const double size = (block.rest().colwise().maxCoeff() - block.rest().colwise().minCoeff()).norm();
  for (int s = 0; s < 10; ++s) {
    Simulator loose = tight;
    EXPECT_TRUE(loose.step(options).converged);
    EXPECT_TRUE(tight.step(tight_options).converged) << "step " << s;
    const Points difference = loose.positions() - tight.positions();
    double weighted = 0;
    for (Index n = 0; n < tight.num_nodes(); ++n) weighted += tight.masses()[n] * difference.row(n).squaredNorm();
    EXPECT_LT(std::sqrt(weighted / tight.masses().sum()), 2 * options.tolerance * size) << "step " << s;
  }
}

TEST_P(Integrator, AnAnchorPullsItsPointToTheTarget) {
  // A block held at its base; a hook (anchor) on a top corner pulled sideways. The stiffer the
  // hook, the closer the corner follows; released (no anchors), it springs back.
  const TetMesh block = make_grid(Box{}, {3, 3, 3}, 5);
  Material material;
  material.model = GetParam();
  const EmbeddedPoint corner{block.num_tets() - 1, Eigen::Vector4d(0.25, 0.25, 0.25, 0.25)};
  const auto pulled = [&](double stiffness) {
    Simulator sim(block, material);
    for (Index n = 0; n < block.num_nodes(); ++n) {
      if (block.rest()(n, 2) == 0) sim.pin(n);
    }
    const Vec3 start = sim.position(corner), target = start + Vec3(0.2, 0, 0);
    sim.set_anchors({{corner, target, stiffness}});
    StepOptions options;
    options.gravity = Vec3::Zero();
    EXPECT_TRUE(sim.solve_static(options).converged);
    const double reached = (sim.position(corner) - start).dot(Vec3(1, 0, 0)) / 0.2;
    sim.set_anchors({});
    EXPECT_TRUE(sim.solve_static(options).converged);
    EXPECT_LT((sim.position(corner) - start).norm(), 1e-6);  // back where it was
    return reached;
  };
  const double soft = pulled(1e3), stiff = pulled(1e7);
  EXPECT_GT(soft, 0.001);
  EXPECT_LT(soft, stiff);
  EXPECT_GT(stiff, 0.95);
  EXPECT_LE(stiff, 1.0 + 1e-9);
  // Bad anchors are refused.
  Simulator sim(block, material);
  EXPECT_THROW(sim.set_anchors({{EmbeddedPoint{block.num_tets(), corner.weights}, Vec3::Zero(), 1}}), Error);
  EXPECT_THROW(sim.set_anchors({{corner, Vec3(std::nan(""), 0, 0), 1}}), Error);
  EXPECT_THROW(sim.set_anchors({{corner, Vec3::Zero(), -1}}), Error);
}

TEST(Simulator, RealTimeBudgetIsRescuedWhereItWouldDiverge) {
  // A soft column held at its base, its top dragged 0.9 sideways by a stiff hook for a second
  // and let go: one Newton iteration a step started from the prediction cannot follow the snap
  // back, and without the safety valve the error it leaves grows step after step until the
  // positions overflow (1e84 here). With it, the steps that would end beyond a residual of 1
  // take further iterations. Started where the step starts (FirstGuess::kStart), one iteration
  // follows it, valve or not: nothing is extrapolated past where the material turns.
  const TetMesh column = make_grid(Box{Vec3(0, 0, 0), Vec3(0.2, 0.2, 1)}, {2, 2, 10}, 5);
  Material material;
  material.youngs_modulus = 1e4;
  material.poissons_ratio = 0.4;
  const EmbeddedPoint top{column.num_tets() - 1, Eigen::Vector4d::Constant(0.25)};
  const auto run = [&](double rescue_residual, int* rescues, FirstGuess first_guess = FirstGuess::kPrediction) {
    Simulator sim(column, material);
    for (Index n = 0; n < column.num_nodes(); ++n) {
      if (column.rest()(n, 2) == 0) sim.pin(n);
    }
    StepOptions options = StepOptions::real_time(1.0 / 30);
    EXPECT_EQ(options.rescue_residual, 1);
    EXPECT_EQ(options.first_guess, FirstGuess::kPrediction);
    options.rescue_residual = rescue_residual;
    options.first_guess = first_guess;
    const Vec3 start = sim.position(top);
    double worst = 0;
    for (int s = 0; s < 150; ++s) {
      if (s < 30) sim.set_anchors({{top, start + Vec3(0.03 * s, 0, 0), 1e6}});
      if (s == 30) sim.set_anchors({});
      const StepReport report = sim.step(options);
      EXPECT_LE(report.newton_iterations, 1 + options.rescue_iterations);
      *rescues += report.rescue_iterations;
      worst = std::max(worst, report.residual);
      if (!sim.positions().allFinite()) return std::numeric_limits<double>::infinity();
    }
    return worst;
  };
  int unrescued = 0, rescued = 0;
  EXPECT_GT(run(0, &unrescued), 1e3);  // diverged
  EXPECT_EQ(unrescued, 0);
  EXPECT_LT(run(1, &rescued), 2);
  EXPECT_GT(rescued, 0);
  int from_start = 0;
  EXPECT_LT(run(0, &from_start, FirstGuess::kStart), 0.1);
  EXPECT_EQ(from_start, 0);
}

TEST(Simulator, RejectsBadParameters) {
  const TetMesh cube = make_grid(Box{}, {1, 1, 1}, 5);
  Material bad;
  bad.density = -1;
  EXPECT_THROW(Simulator(cube, bad), Error);
  std::vector<double> fractions(3, 1.0);
  EXPECT_THROW(Simulator(cube, Material{}, fractions), Error);
  Simulator sim(cube, Material{});
  EXPECT_THROW(sim.add_obstacle(Obstacle::plane(Vec3::Zero(), Vec3(0, 0, 1)).with_friction(-0.1)), Error);
  EXPECT_THROW(sim.add_obstacle(Obstacle::sphere(Vec3::Zero(), 1).with_friction(std::nan(""))), Error);
}

}  // namespace
}  // namespace tetcut::sim
