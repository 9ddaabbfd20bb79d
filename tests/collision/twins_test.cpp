// Twins: one material point held by two copies, matched by rest position up to its rounding
// (bit-for-bit matching missed those two copies rounded differently, and with them springs
// across incisions and welds in the intersection check).

#include <gtest/gtest.h>

#include <tetcut/sim.hpp>

#include "collision/twins.hpp"

#include <cmath>
#include <limits>

namespace tetcut {
namespace {

TEST(Twins, MatchRestPositionsUpToRoundingAndCurrentOnesUpToTheTolerance) {
  Points rest(5, 3), now(5, 3);
  const double x = 0.013;
  rest << x, -0.3, 0.3,                                          // 0
      std::nextafter(std::nextafter(x, 1.0), 1.0), -0.3, 0.3,    // 1: two ulps away from 0
      x, -0.3, 0.3 + 1e-9,                                       // 2: a different point
      x, -0.3, 0.3,                                              // 3: 0's twin, but moved away now
      std::nextafter(x, 0.0), -0.3, 0.3;                         // 4: an ulp below 0
  now = rest;
  now(3, 0) += 1e-3;
  const double rounding = 64 * std::numeric_limits<double>::epsilon() * 0.3;
  const std::vector<Index> ids = collision::twin_ids(rest, now, rounding, 1e-6);
  EXPECT_EQ(ids[0], ids[1]);
  EXPECT_EQ(ids[0], ids[4]);
  EXPECT_NE(ids[0], ids[2]);
  EXPECT_NE(ids[0], ids[3]);
  // Rest twins only.
  const std::vector<Index> rest_only = collision::twin_ids(rest, rest, rounding, std::numeric_limits<double>::infinity());
  EXPECT_EQ(rest_only[0], rest_only[3]);
  EXPECT_NE(rest_only[0], rest_only[2]);
}

TEST(Twins, IncisionSpringsJoinTwinsRoundedDifferently) {
  // Two triangles on cut 0, one per side (copies 0 and 1), whose shared corners were rounded an
  // ulp apart by the two copies.
  MaterialSurface s;
  s.surface.vertices.resize(6, 3);
  const double up = std::nextafter(0.5, 1.0);
  s.surface.vertices << 0.5, 0, 0, 0.5, 1, 0, 0.5, 0, 1,  //
      up, 0, 0, 0.5, 1, 0, 0.5, 0, std::nextafter(1.0, 2.0);
  s.surface.triangles.resize(2, 3);
  s.surface.triangles << 0, 1, 2, 3, 5, 4;
  s.vertex_tet = {0, 0, 0, 1, 1, 1};
  s.vertex_weights = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>::Constant(6, 4, 0.25);
  s.triangle_source = {0, 0};
  s.triangle_tet = {0, 1};
  EXPECT_EQ(sim::incision_pairs(s, 0, 1).size(), 3u);
  EXPECT_TRUE(sim::incision_pairs(s, 1, 2).empty());  // another cut's triangles: none
}

}  // namespace
}  // namespace tetcut
