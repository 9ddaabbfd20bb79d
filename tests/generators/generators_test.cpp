// Generators: exact volume, positive tets, conforming faces, boundary exactly on the box.

#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>

#include <gtest/gtest.h>

#include <cmath>
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

}  // namespace
}  // namespace tetcut
