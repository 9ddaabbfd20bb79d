// Closest points of surface primitives and the contact barrier: distances against brute-force
// sampling, gradients and Hessians against central finite differences in every region (face,
// edge, corner; crossing and clamped segments), and near touching.

#include <gtest/gtest.h>

#include "collision/proximity.hpp"
#include "sim/surface_contact.hpp"

#include <random>

namespace tetcut {
namespace {

using collision::Mat12;
using collision::Proximity;
using collision::Vec12;

Proximity measure(const std::array<Vec3, 4>& y, bool edges) {
  return edges ? collision::segment_segment(y[0], y[1], y[2], y[3]) : collision::point_triangle(y[0], y[1], y[2], y[3]);
}

std::array<Vec3, 4> moved(std::array<Vec3, 4> y, int coordinate, double by) {
  y[coordinate / 3][coordinate % 3] += by;
  return y;
}

// The smallest distance over a fine grid of the primitives' parameters: an upper bound that the
// closest points must not exceed, and come within the grid's resolution of.
double sampled_distance(const std::array<Vec3, 4>& y, bool edges) {
  constexpr int kSteps = 200;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kSteps; ++i) {
    for (int j = 0; j <= kSteps; ++j) {
      const double u = static_cast<double>(i) / kSteps, v = static_cast<double>(j) / kSteps;
      if (edges) {
        best = std::min(best, ((1 - u) * y[0] + u * y[1] - (1 - v) * y[2] - v * y[3]).norm());
      } else if (u + v <= 1) {
        best = std::min(best, (y[0] - ((1 - u - v) * y[1] + u * y[2] + v * y[3])).norm());
      }
    }
  }
  return best;
}

TEST(Proximity, DistancesMatchSampling) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    std::array<Vec3, 4> y;
    for (Vec3& p : y) p = Vec3(coordinate(random), coordinate(random), coordinate(random));
    for (const bool edges : {false, true}) {
      const Proximity p = measure(y, edges);
      const double sampled = sampled_distance(y, edges);
      EXPECT_LE(p.distance, sampled + 1e-12) << trial;
      EXPECT_GE(p.distance, sampled - 0.02) << trial;  // the grid's resolution
      // r is the combination its weights say, and the weights are those of two points.
      Vec3 r = Vec3::Zero();
      for (int k = 0; k < 4; ++k) r += p.w[k] * y[k];
      EXPECT_LT((r - p.r).norm(), 1e-14);
      EXPECT_NEAR(edges ? p.w[0] + p.w[1] : p.w[0], 1.0, 1e-15);
      EXPECT_NEAR(edges ? p.w[2] + p.w[3] : p.w[1] + p.w[2] + p.w[3], -1.0, 1e-15);
    }
  }
}

TEST(Proximity, RegionsAreTheExpectedOnes) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(collision::point_triangle(Vec3(0.2, 0.2, 0.5), a, b, c).free, 2);   // above the face
  EXPECT_EQ(collision::point_triangle(Vec3(0.5, -0.5, 0.1), a, b, c).free, 1);  // beyond edge ab
  EXPECT_EQ(collision::point_triangle(Vec3(-1, -1, 0.3), a, b, c).free, 0);     // beyond corner a
  EXPECT_NEAR(collision::point_triangle(Vec3(0.2, 0.2, 0.5), a, b, c).distance, 0.5, 1e-15);
  EXPECT_NEAR(collision::point_triangle(Vec3(-1, -1, 0), a, b, c).distance, std::sqrt(2.0), 1e-15);
  // Crossing segments one above the other, and a segment whose end is nearest.
  const Proximity crossing = collision::segment_segment(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, -1, 0.25), Vec3(0, 1, 0.25));
  EXPECT_EQ(crossing.free, 2);
  EXPECT_NEAR(crossing.distance, 0.25, 1e-15);
  const Proximity clamped = collision::segment_segment(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(2, -1, 0.25), Vec3(2, 1, 0.25));
  EXPECT_EQ(clamped.free, 1);
  EXPECT_NEAR(clamped.distance, std::sqrt(1 + 0.0625), 1e-15);
  // A degenerate triangle is its segment.
  EXPECT_NEAR(collision::point_triangle(Vec3(0.5, 1, 0), a, b, Vec3(2, 0, 0)).distance, 1.0, 1e-15);
  // Coincident corners (a fan over a polygon's repeated point, as placed): still a segment, or a
  // point, never 0 / 0. Every region of the point's position.
  for (const Vec3& p : {Vec3(-1, 0.5, 0.3), Vec3(0.5, 0.5, 0.3), Vec3(2, -0.5, 0.1), Vec3(0, 0, 1)}) {
    const Proximity two = collision::point_triangle(p, a, a, b);
    const Proximity two_last = collision::point_triangle(p, a, b, b);
    const double to_segment = (p - Vec3(std::clamp(p.x(), 0.0, 1.0), 0, 0)).norm();
    EXPECT_NEAR(two.distance, to_segment, 1e-15);
    EXPECT_NEAR(two_last.distance, to_segment, 1e-15);
    EXPECT_NEAR(collision::point_triangle(p, b, b, b).distance, (p - b).norm(), 1e-15);
  }
}

// Configurations in every region, away from region boundaries (where the Hessian jumps).
std::vector<std::pair<std::array<Vec3, 4>, bool>> configurations(double scale) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0.2, 1, 0);
  return {
      {{Vec3(0.3, 0.3, scale), a, b, c}, false},                              // face
      {{Vec3(0.5, -0.2 * scale, 0.4 * scale), a, b, c}, false},              // edge ab
      {{Vec3(-0.3 * scale, -0.4 * scale, 0.5 * scale), a, b, c}, false},     // corner a
      {{Vec3(-1, 0, 0), Vec3(1, 0.2, 0), Vec3(0.1, -1, scale), Vec3(-0.2, 1, scale)}, true},  // crossing
      {{Vec3(-1, 0, 0), Vec3(1, 0.2, 0), Vec3(1 + 0.3 * scale, -1, 0.5 * scale), Vec3(1 + 0.2 * scale, 1, 0.6 * scale)}, true},  // clamped
  };
}

TEST(Proximity, GradientAndHessianMatchFiniteDifferences) {
  for (const double scale : {0.5, 1e-3}) {
    for (const auto& [y, edges] : configurations(scale)) {
      const Proximity p = measure(y, edges);
      const Vec12 g = collision::distance_gradient(p);
      const Mat12 H = collision::distance_hessian(p, y);
      const double h = 1e-4 * p.distance;
      for (int i = 0; i < 12; ++i) {
        const Proximity plus = measure(moved(y, i, h), edges), minus = measure(moved(y, i, -h), edges);
        EXPECT_NEAR(g[i], (plus.distance - minus.distance) / (2 * h), 1e-6 * (1 + std::abs(g[i]))) << "scale " << scale << " edges " << edges << " i " << i;
        const Vec12 column = (collision::distance_gradient(plus) - collision::distance_gradient(minus)) / (2 * h);
        for (int j = 0; j < 12; ++j) {
          EXPECT_NEAR(H(j, i), column[j], 1e-5 * (1 + H.cwiseAbs().maxCoeff())) << "scale " << scale << " edges " << edges << " " << i << "," << j;
        }
      }
      EXPECT_LT((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-9 * (1 + H.cwiseAbs().maxCoeff()));
    }
  }
}

TEST(ContactBarrier, DerivativesMatchFiniteDifferences) {
  const double dhat = 0.01;
  for (const double d : {0.9 * dhat, 0.5 * dhat, 1e-2 * dhat, 1e-5 * dhat}) {
    const double h = 1e-5 * d;
    EXPECT_NEAR(sim::detail::barrier_first(d, dhat), (sim::detail::barrier(d + h, dhat) - sim::detail::barrier(d - h, dhat)) / (2 * h),
                1e-6 * std::abs(sim::detail::barrier_first(d, dhat)) + 1e-14);
    EXPECT_NEAR(sim::detail::barrier_second(d, dhat),
                (sim::detail::barrier_first(d + h, dhat) - sim::detail::barrier_first(d - h, dhat)) / (2 * h),
                1e-6 * std::abs(sim::detail::barrier_second(d, dhat)) + 1e-10);
    EXPECT_GT(sim::detail::barrier(d, dhat), 0);
    EXPECT_LT(sim::detail::barrier_first(d, dhat), 0);  // repels
    EXPECT_GT(sim::detail::barrier_second(d, dhat), 0);
  }
  // Zero, with zero slope and curvature, from dhat on (C2 there); unbounded at 0.
  EXPECT_EQ(sim::detail::barrier(dhat, dhat), 0);
  EXPECT_EQ(sim::detail::barrier(2 * dhat, dhat), 0);
  EXPECT_LT(std::abs(sim::detail::barrier_first(dhat * (1 - 1e-9), dhat)), 1e-15);
  EXPECT_LT(std::abs(sim::detail::barrier_second(dhat * (1 - 1e-9), dhat)), 1e-7);
  EXPECT_EQ(sim::detail::barrier(0, dhat), std::numeric_limits<double>::infinity());
}

TEST(ContactBarrier, PairEnergyGradientAndHessianMatchFiniteDifferences) {
  // Near touching (a thousandth of the thickness) and halfway, in each region.
  for (const double scale : {0.004, 1e-5}) {
    const double dhat = 0.01, kappa = 1e4;
    for (const auto& [y, edges] : configurations(scale)) {
      collision::Vec12 g;
      collision::Mat12 H;
      const double energy = sim::detail::pair_energy(y, edges, dhat, kappa, &g, &H);
      ASSERT_GT(energy, 0) << scale;
      const double h = 1e-4 * measure(y, edges).distance;
      for (int i = 0; i < 12; ++i) {
        collision::Vec12 gp, gm;
        const double ep = sim::detail::pair_energy(moved(y, i, h), edges, dhat, kappa, &gp);
        const double em = sim::detail::pair_energy(moved(y, i, -h), edges, dhat, kappa, &gm);
        EXPECT_NEAR(g[i], (ep - em) / (2 * h), 1e-6 * (1 + g.cwiseAbs().maxCoeff())) << scale << " " << i;
        const collision::Vec12 column = (gp - gm) / (2 * h);
        for (int j = 0; j < 12; ++j) EXPECT_NEAR(H(j, i), column[j], 1e-5 * (1 + H.cwiseAbs().maxCoeff())) << scale << " " << i << "," << j;
      }
    }
  }
}

}  // namespace
}  // namespace tetcut
