// Cloth: the membrane and bending energies against finite differences and analytic values, and
// the simulator on a hanging square, before and after a cut.

#include <tetcut/cloth.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/planar_cutter.hpp>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <random>

#include "sim/cloth_energy.hpp"

namespace tetcut::sim {
namespace {

using detail::Mat9;
using detail::Vec9;

std::array<Vec3, 3> corners_of(const Vec9& x) { return {x.segment<3>(0), x.segment<3>(3), x.segment<3>(6)}; }

TEST(ClothEnergy, MembraneGradientAndHessianMatchFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const double mu = 3.0, lambda = 2.0;
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector2d a(u(rng), u(rng)), b = a + Eigen::Vector2d(1 + 0.5 * u(rng), 0.3 * u(rng)),
                          c = a + Eigen::Vector2d(0.3 * u(rng), 1 + 0.5 * u(rng));
    const detail::MembraneElement e = detail::make_membrane(a, b, c, 0.25 + 0.75 * (u(rng) + 1) / 2);
    // Stretched, compressed and near-flat deformations alike.
    Vec9 x;
    for (int k = 0; k < 9; ++k) x[k] = (trial % 3 == 0 ? 0.05 : 1.0) * u(rng);
    Vec9 g = Vec9::Zero();
    Mat9 h = Mat9::Zero();
    detail::membrane_energy(e, mu, lambda, corners_of(x), &g, &h, false);
    const double step = 1e-6;
    for (int k = 0; k < 9; ++k) {
      Vec9 xp = x, xm = x;
      xp[k] += step;
      xm[k] -= step;
      const double fd = (detail::membrane_energy(e, mu, lambda, corners_of(xp), nullptr, nullptr, false) -
                         detail::membrane_energy(e, mu, lambda, corners_of(xm), nullptr, nullptr, false)) /
                        (2 * step);
      EXPECT_NEAR(g[k], fd, 1e-6 * (1 + std::abs(fd))) << "trial " << trial << ", coordinate " << k;
      Vec9 gp = Vec9::Zero(), gm = Vec9::Zero();
      detail::membrane_energy(e, mu, lambda, corners_of(xp), &gp, nullptr, false);
      detail::membrane_energy(e, mu, lambda, corners_of(xm), &gm, nullptr, false);
      const Vec9 column = (gp - gm) / (2 * step);
      for (int j = 0; j < 9; ++j) EXPECT_NEAR(h(j, k), column[j], 1e-5 * (1 + std::abs(column[j])));
    }
    // The projection keeps the Hessian where it is positive semi-definite and is so itself.
    Mat9 projected = Mat9::Zero();
    detail::membrane_energy(e, mu, lambda, corners_of(x), nullptr, &projected, true);
    const Eigen::SelfAdjointEigenSolver<Mat9> exact(h), clamped(projected);
    EXPECT_GE(clamped.eigenvalues().minCoeff(), -1e-9 * (1 + exact.eigenvalues().cwiseAbs().maxCoeff()));
    if (exact.eigenvalues().minCoeff() >= 0) {
      EXPECT_LE((projected - h).norm(), 1e-9 * (1 + h.norm()));
    }
  }
}

TEST(ClothEnergy, MembraneIsZeroUnderRigidMotion) {
  const Eigen::Vector2d a(0, 0), b(1, 0), c(0.2, 0.9);
  const detail::MembraneElement e = detail::make_membrane(a, b, c, 1.0);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 shift(0.3, -2, 5);
  const std::array<Vec3, 3> x = {rotation * Vec3(a.x(), a.y(), 0) + shift, rotation * Vec3(b.x(), b.y(), 0) + shift,
                                 rotation * Vec3(c.x(), c.y(), 0) + shift};
  Vec9 g = Vec9::Zero();
  EXPECT_NEAR(detail::membrane_energy(e, 5, 3, x, &g, nullptr, false), 0, 1e-14);
  EXPECT_LE(g.norm(), 1e-13);
  // Stretching by 10% along x costs mu |E|^2 + lambda tr(E)^2 / 2 with E = diag(0.105, 0).
  const std::array<Vec3, 3> stretched = {Vec3(0, 0, 0), Vec3(1.1, 0, 0), Vec3(0.22, 0.9, 0)};
  const double strain = 0.5 * (1.1 * 1.1 - 1);
  EXPECT_NEAR(detail::membrane_energy(e, 5, 3, stretched, nullptr, nullptr, false),
              0.45 * (5 * strain * strain + 1.5 * strain * strain), 1e-12);
}

TEST(ClothEnergy, HingeIsZeroOnAffineImagesAndMatchesTheDihedralEnergy) {
  // Edge (0, 1) on the x axis, wings above and below.
  const std::array<Eigen::Vector2d, 4> rest = {Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0), Eigen::Vector2d(0.4, 0.7),
                                               Eigen::Vector2d(0.6, -0.5)};
  const double kb = 0.01;
  const detail::Hinge hinge = detail::make_hinge({0, 1, 2, 3}, rest, kb);
  Eigen::Matrix3d map;
  map << 1.2, 0.3, -0.4, 0.1, 0.8, 0.5, -0.7, 0.2, 1.1;
  std::array<Vec3, 4> x;
  for (int i = 0; i < 4; ++i) x[i] = map * Vec3(rest[i].x(), rest[i].y(), 0) + Vec3(1, 2, 3);
  EXPECT_NEAR(detail::hinge_energy(hinge, x, nullptr), 0, 1e-15);
  // Folding the lower wing by theta about the edge.
  const double theta = 1e-3;
  for (int i = 0; i < 4; ++i) x[i] = Vec3(rest[i].x(), rest[i].y(), 0);
  x[3] = Vec3(rest[3].x(), rest[3].y() * std::cos(theta), -rest[3].y() * std::sin(theta));
  const double a1 = 0.5 * 0.7, a2 = 0.5 * 0.5;
  EXPECT_NEAR(detail::hinge_energy(hinge, x, nullptr), 3 * kb * theta * theta / (a1 + a2), 1e-3 * 3 * kb * theta * theta / (a1 + a2));
  // Gradient against finite differences, at a general configuration.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (auto& p : x) p = Vec3(u(rng), u(rng), u(rng));
  Eigen::Matrix<double, 12, 1> g = Eigen::Matrix<double, 12, 1>::Zero();
  detail::hinge_energy(hinge, x, &g);
  for (int k = 0; k < 12; ++k) {
    auto xp = x, xm = x;
    xp[k / 3][k % 3] += 1e-6;
    xm[k / 3][k % 3] -= 1e-6;
    const double fd = (detail::hinge_energy(hinge, xp, nullptr) - detail::hinge_energy(hinge, xm, nullptr)) / 2e-6;
    EXPECT_NEAR(g[k], fd, 1e-7 * (1 + std::abs(fd)));
  }
}

// Rest (u, v) hung in the x-z plane: x = u, z = v (the top edge v = 1 at z = 1).
Points hang(const PlanarMesh& mesh) {
  Points x(mesh.num_nodes(), 3);
  for (Index i = 0; i < mesh.num_nodes(); ++i) x.row(i) << mesh.rest(i, 0), 0, mesh.rest(i, 1);
  return x;
}

TEST(ClothSimulator, HangingClothSettlesToRest) {
  const int n = 8;
  const PlanarMesh mesh = make_planar_grid(n);
  PlanarCutter cutter(mesh);
  const PlanarCutResult cut = cutter.result();
  // Start flat and horizontal, pinned along the edge v = 1: it swings down and comes to rest
  // hanging below that edge.
  Points start(mesh.num_nodes(), 3);
  for (Index i = 0; i < mesh.num_nodes(); ++i) start.row(i) << mesh.rest(i, 0), mesh.rest(i, 1), 0;
  ClothMaterial material;
  material.mass_damping = 2;
  ClothSimulator cloth(cut.mesh, start, material);
  for (int i = 0; i <= n; ++i) cloth.pin(n * (n + 1) + i);
  EXPECT_EQ(cloth.num_hinges(), 3 * n * n - 2 * n);  // interior edges of the grid
  ClothStepOptions options;
  options.dt = 1.0 / 30;
  for (int step = 0; step < 400; ++step) {
    const ClothStepReport report = cloth.step(options);
    ASSERT_TRUE(report.converged) << "step " << step << ": residual " << report.residual;
  }
  EXPECT_LT(cloth.kinetic_energy(), 1e-8);
  // Hanging: the free edge is about a metre below the pinned one, and nothing moved sideways
  // from the plane through the pins beyond the swing's settling.
  double bottom = 0;
  for (int i = 0; i <= n; ++i) bottom += cloth.positions()(i, 2) / (n + 1);
  EXPECT_LT(bottom, -0.95);
  EXPECT_GT(bottom, -1.1);
  for (Index v = 0; v < cloth.num_nodes(); ++v) EXPECT_NEAR(cloth.positions()(v, 1), 1.0, 0.05);
}

TEST(ClothSimulator, CutPieceFallsAndTheRestHangs) {
  const int n = 8;
  const PlanarMesh mesh = make_planar_grid(n);
  PlanarCutter cutter(mesh);
  ClothSimulator cloth(cutter.result().mesh, hang(mesh), ClothMaterial{});
  for (int i = 0; i <= n; ++i) cloth.pin(n * (n + 1) + i);
  ClothStepOptions options;
  for (int step = 0; step < 10; ++step) cloth.step(options);
  Polyline across;
  across.points.resize(2, 2);
  across.points << -0.1, 0.4375, 1.1, 0.4375;
  const PlanarCutReport report = cutter.cut(std::span<const Polyline>(&across, 1));
  const PlanarCutResult cut = cutter.result();
  ASSERT_EQ(cut.mesh.num_pieces(), 2);
  cloth.remesh(cut.mesh, report);
  EXPECT_EQ(cloth.num_nodes(), cut.mesh.mesh.num_nodes());
  for (int step = 0; step < 30; ++step) ASSERT_TRUE(cloth.step(options).converged);
  // Half a second of free fall for the lower piece (g t^2 / 2 = 1.2 m); the upper one hangs on.
  // A node belongs to the piece of the copies using it (copy 0 is the bottom-left triangle).
  std::vector<Index> node_piece(cloth.num_nodes(), -1);
  for (Index c = 0; c < cut.mesh.mesh.num_triangles(); ++c) {
    for (int k = 0; k < 3; ++k) node_piece[cut.mesh.mesh.triangles(c, k)] = cut.mesh.triangle_piece[c];
  }
  const Index lower = cut.mesh.triangle_piece[0];
  Index fell = 0;
  for (Index v = 0; v < cloth.num_nodes(); ++v) {
    if (node_piece[v] == lower) {
      EXPECT_LT(cloth.positions()(v, 2), cut.mesh.mesh.rest(v, 1) - 1.0) << "node " << v;
      ++fell;
    } else {
      EXPECT_GT(cloth.positions()(v, 2), cut.mesh.mesh.rest(v, 1) - 0.1) << "node " << v;
    }
  }
  // Rows 0 to 3, and row 4 once more: the lower copies of the triangles the cut crosses have
  // their own corners there.
  EXPECT_EQ(fell, 5 * (n + 1));
  for (int i = 0; i <= n; ++i) EXPECT_TRUE(cloth.pinned(n * (n + 1) + i));
  EXPECT_NEAR(cloth.positions()(n * (n + 1), 2), 1.0, 1e-12);
}

}  // namespace
}  // namespace tetcut::sim
