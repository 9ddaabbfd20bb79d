#pragma once
// What the parts of surface contact share (surface_contact.cpp: the surface and the barrier's terms;
// surface_contact_list.cpp: the candidate list, its motion bounds and conservative advancement;
// surface_contact_guards.cpp: the guards and joins of a cut's two sides): timing, normals and the
// pairs' measures.

#include "collision/proximity.hpp"
#include "util/stopwatch.hpp"

#include <tetcut/cutter.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace tetcut::sim::detail::contact_parts {

// A triangle whose height is below this share of its longest edge, or of the contact thickness
// where that is longer, has no normal a guard could use: fans over the surface's polygons make
// triangles of collinear points and of points a rounding apart (exactly, in the material), whose
// rounded corners give them a normal in any direction.
constexpr double kFlat = 1e-6;

// Adds a scope's wall time to *total, less what *rebuild (the rebuilds' total) grew by within it:
// the rebuilds a part sets off are counted apart.
class PartTimer {
 public:
  PartTimer(double* total, const double* rebuild) : total_(total), rebuild_(rebuild), rebuild_start_(rebuild ? *rebuild : 0.0) {}
  PartTimer(const PartTimer&) = delete;
  PartTimer& operator=(const PartTimer&) = delete;
  ~PartTimer() { *total_ += seconds_since(start_) - (rebuild_ ? *rebuild_ - rebuild_start_ : 0.0); }

 private:
  double* total_;
  const double* rebuild_;
  double rebuild_start_;
  Clock::time_point start_ = Clock::now();
};

// The unit normal of triangle (a, b, c), or zero where it is flat for a scale of `length`.
inline Vec3 unit_normal(const Vec3& a, const Vec3& b, const Vec3& c, double length) {
  const Vec3 n = (b - a).cross(c - a);
  const double longest = std::sqrt(std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()}));
  return n.norm() > kFlat * longest * std::max(longest, length) ? Vec3(n.normalized()) : Vec3::Zero();
}

// A guard's vertex faces its triangle when one of its triangles' normals makes an angle of more
// than 120 degrees with the triangle's in the material (the two sides of a cut: 180).
constexpr double kFacing = 0.5;

// A lower bound of the distance between a pair's two primitives (the vertex, or the first edge,
// against the rest): how far apart their boxes are along the axis that separates them most.
// About a tenth of an exact distance's cost, and most listed pairs are farther apart than the
// thickness (on a hand cut in two, sliding: 5k of 29k within it), so the exact distance is taken
// only where this cannot decide.
inline double gap_between(const std::array<Vec3, 4>& y, bool edges) {
  const int split = edges ? 2 : 1;
  double gap = 0;
  for (int k = 0; k < 3; ++k) {
    double lo_a = y[0][k], hi_a = y[0][k], lo_b = y[split][k], hi_b = y[split][k];
    for (int i = 1; i < split; ++i) lo_a = std::min(lo_a, y[i][k]), hi_a = std::max(hi_a, y[i][k]);
    for (int i = split + 1; i < 4; ++i) lo_b = std::min(lo_b, y[i][k]), hi_b = std::max(hi_b, y[i][k]);
    gap = std::max({gap, lo_b - hi_a, lo_a - hi_b});
  }
  return gap;
}

// The proximity of a pair at its corner positions (vertex and triangle, or two segments).
inline collision::Proximity proximity_at(const std::array<Vec3, 4>& y, bool edges) {
  return edges ? collision::segment_segment(y[0], y[1], y[2], y[3]) : collision::point_triangle(y[0], y[1], y[2], y[3]);
}

// The same into *p where the boxes come within `reach` of each other; beyond, only p's distance,
// set to infinity (the readers ask only whether a pair is within reach).
inline void measure_within(const std::array<Vec3, 4>& y, bool edges, double reach, collision::Proximity* p) {
  if (gap_between(y, edges) < reach) {
    *p = proximity_at(y, edges);
  } else {
    p->distance = std::numeric_limits<double>::infinity();
  }
}

}  // namespace tetcut::sim::detail::contact_parts
