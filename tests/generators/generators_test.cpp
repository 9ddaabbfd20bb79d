// Generators: exact volume, positive tets, conforming faces, boundary exactly on the box.

#include <tetcut/cutting_surfaces.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>

#include "support/invariants.hpp"

namespace tetcut {
namespace {

using testing::check_boundary_on_box;
using testing::check_positive_and_conforming;
using testing::exact_volume;

// Bounds that are not exactly representable make the exact-volume claim non-trivial.
const Box kOddBox{Vec3(-0.3, 0.1, 2.7), Vec3(1.9, 0.7, 3.3)};

class GridTest : public ::testing::TestWithParam<std::tuple<int, int, int, int>> {};

TEST_P(GridTest, VolumeIsExactAndFacesConform) {
  const auto [nx, ny, nz, per_cube] = GetParam();
  const TetMesh mesh = make_grid(kOddBox, {nx, ny, nz}, per_cube);
  EXPECT_EQ(mesh.num_tets(), nx * ny * nz * per_cube);
  EXPECT_EQ(mesh.num_nodes(), (nx + 1) * (ny + 1) * (nz + 1));
  EXPECT_EQ(exact_volume(mesh), exact_volume(kOddBox));
  EXPECT_EQ(check_positive_and_conforming(mesh), "");
  EXPECT_EQ(check_boundary_on_box(mesh, kOddBox), "");
  // Each boundary square is split into two triangles.
  EXPECT_EQ(mesh.adjacency().num_boundary_faces(), 4 * (nx * ny + ny * nz + nz * nx));
}

INSTANTIATE_TEST_SUITE_P(Grids, GridTest,
                         ::testing::Values(std::make_tuple(1, 1, 1, 5), std::make_tuple(1, 1, 1, 6),
                                           std::make_tuple(4, 4, 4, 5), std::make_tuple(4, 4, 4, 6),
                                           std::make_tuple(3, 5, 2, 5), std::make_tuple(7, 2, 3, 6)));

TEST(Grid, RejectsBadParameters) {
  EXPECT_THROW(make_grid(Box{}, {0, 1, 1}, 5), Error);
  EXPECT_THROW(make_grid(Box{}, {1, 1, 1}, 4), Error);
  EXPECT_THROW(make_grid(Box{Vec3(0, 0, 0), Vec3(1, 0, 1)}, {1, 1, 1}, 5), Error);
}

class BccTest : public ::testing::TestWithParam<double> {};

TEST_P(BccTest, FillsItsLatticeBoxExactly) {
  const double spacing = GetParam();
  const TetMesh mesh = make_bcc(kOddBox, spacing);
  Box lattice{mesh.rest().colwise().minCoeff().transpose(), mesh.rest().colwise().maxCoeff().transpose()};
  // The lattice covers the requested box.
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(lattice.min[a], kOddBox.min[a]);
    EXPECT_GE(lattice.max[a], kOddBox.max[a]);
  }
  EXPECT_EQ(exact_volume(mesh), exact_volume(lattice));
  EXPECT_EQ(check_positive_and_conforming(mesh), "");
  EXPECT_EQ(check_boundary_on_box(mesh, lattice), "");
  // Whole cubes of the given size along each axis, and the fewest that cover the box.
  Index n[3];
  for (int a = 0; a < 3; ++a) {
    n[a] = static_cast<Index>(std::lround((lattice.max[a] - lattice.min[a]) / spacing));
    EXPECT_NEAR(n[a] * spacing, lattice.max[a] - lattice.min[a], 1e-12);
    EXPECT_LT((n[a] - 1) * spacing, kOddBox.max[a] - kOddBox.min[a]);
  }
  // 12 tets per cube: 4 per face shared by two cubes (2 per cube side), 2 per boundary face.
  EXPECT_EQ(mesh.num_tets(), 12 * n[0] * n[1] * n[2]);
  EXPECT_EQ(mesh.num_nodes(), (n[0] + 1) * (n[1] + 1) * (n[2] + 1) + n[0] * n[1] * n[2]);
}

INSTANTIATE_TEST_SUITE_P(Spacings, BccTest, ::testing::Values(0.1, 0.25, 0.3, 0.6, 5.0));

TEST(Bcc, CountsOfAUnitCubeLattice) {
  const TetMesh mesh = make_bcc(Box{}, 0.125);
  const int n = 8;
  EXPECT_EQ(mesh.num_nodes(), (n + 1) * (n + 1) * (n + 1) + n * n * n);
  EXPECT_EQ(mesh.num_tets(), 12 * n * n * n);
  EXPECT_EQ(exact_volume(mesh), 1);
}

TEST(Bcc, RejectsBadSpacing) {
  EXPECT_THROW(make_bcc(Box{}, 0), Error);
  EXPECT_THROW(make_bcc(Box{}, -1), Error);
  EXPECT_THROW(make_bcc(Box{}, 1e-6), Error);
}

TEST(Spiral, TurnsInwardsClockwiseFromBelowTheCentreInSteps) {
  const Eigen::Vector2d centre(0.5, 0.5);
  const Points2 p = spiral(centre, 0.4, 0.1, 0.1, 0.01);
  ASSERT_GT(p.rows(), 100);
  EXPECT_NEAR(p(0, 0), 0.5, 1e-15);  // straight below the centre, at the outer radius
  EXPECT_NEAR(p(0, 1), 0.1, 1e-15);
  double previous_radius = 0.4, turned = 0;
  for (Index i = 1; i < p.rows(); ++i) {
    const Eigen::Vector2d a = p.row(i - 1).transpose() - centre, b = p.row(i).transpose() - centre;
    EXPECT_NEAR((b - a).norm(), 0.01, 1e-3) << "point " << i;        // about a step apart
    EXPECT_LT(a.x() * b.y() - a.y() * b.x(), 0) << "point " << i;     // clockwise
    EXPECT_LT(b.norm(), previous_radius) << "point " << i;            // inwards
    EXPECT_GE(b.norm(), 0.1) << "point " << i;                        // not past the inner radius
    previous_radius = b.norm();
    turned += std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0));
  }
  // Three turns from radius 0.4 to 0.1 at 0.1 a turn, less the last step.
  EXPECT_NEAR(turned / (2 * std::numbers::pi), 3, 0.02);
  EXPECT_THROW(spiral(centre, 0.4, 0.5, 0.1, 0.01), Error);
  EXPECT_THROW(spiral(centre, 0.4, 0.1, 0, 0.01), Error);
  EXPECT_THROW(spiral(centre, 1e3, 0, 1e-6, 1e-6), Error);  // far too many points
}

}  // namespace
}  // namespace tetcut
