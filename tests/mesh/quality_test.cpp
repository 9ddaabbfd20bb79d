#include <tetcut/quality.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace tetcut {
namespace {

TEST(Quality, RegularTetAnglesAndAltitude) {
  Points p(4, 3);
  p << 1, 1, 1, -1, 1, -1, 1, -1, -1, -1, -1, 1;  // regular tet, edge 2*sqrt(2)
  Tets t(1, 4);
  t << 0, 1, 2, 3;
  const MeshQuality q = measure_quality(TetMesh(p, t));
  const double dihedral = std::acos(1.0 / 3.0) * 180 / std::numbers::pi;
  EXPECT_NEAR(q.min_dihedral_degrees, dihedral, 1e-9);
  EXPECT_NEAR(q.max_dihedral_degrees, dihedral, 1e-9);
  const double edge = 2 * std::sqrt(2.0);
  EXPECT_NEAR(q.min_altitude, edge * std::sqrt(2.0 / 3.0), 1e-12);
  EXPECT_NEAR(q.volume, edge * edge * edge / (6 * std::sqrt(2.0)), 1e-12);
}

TEST(Quality, CornerTetAndUnusedNodes) {
  Points p(5, 3);
  p << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 9, 9, 9;
  Tets t(1, 4);
  t << 0, 1, 2, 3;
  const MeshQuality q = measure_quality(TetMesh(p, t));
  EXPECT_NEAR(q.min_dihedral_degrees, std::acos(1 / std::sqrt(3.0)) * 180 / std::numbers::pi, 1e-9);
  EXPECT_NEAR(q.max_dihedral_degrees, 90, 1e-9);
  EXPECT_NEAR(q.min_altitude, 1 / std::sqrt(3.0), 1e-12);
  EXPECT_EQ(q.num_unused_nodes, 1);
  EXPECT_EQ(q.bbox_max, Vec3(9, 9, 9));
}

TEST(Quality, SurfaceStatsOfAnOpenAndADegenerateSurface) {
  TriangleSurface s;
  s.vertices.resize(4, 3);
  s.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0;
  s.triangles.resize(2, 3);
  s.triangles << 0, 1, 2, 0, 1, 3;  // the second is degenerate (collinear)
  const SurfaceStats stats = measure_surface(s);
  EXPECT_FALSE(stats.two_manifold);
  EXPECT_EQ(stats.num_degenerate_triangles, 1);
  EXPECT_EQ(stats.num_boundary_edges, 4);  // 1-2, 2-0, 1-3, 3-0; edge 0-1 is shared
  EXPECT_DOUBLE_EQ(stats.area, 0.5);
}

}  // namespace
}  // namespace tetcut
