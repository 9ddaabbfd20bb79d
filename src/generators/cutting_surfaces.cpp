#include <tetcut/cutting_surfaces.hpp>
#include <tetcut/error.hpp>

#include <cmath>
#include <numbers>
#include <vector>

namespace tetcut {
namespace {

// Two unit vectors completing `axis` (normalised) to a right-handed frame.
void frame(const Vec3& axis, Vec3* a, Vec3* b, Vec3* w) {
  if (!(axis.norm() > 0) || !axis.allFinite()) throw Error(ErrorKind::kInvalidArgument, "a cutting surface's axis or normal is zero");
  *w = axis.normalized();
  const Vec3 helper = std::abs((*w)[0]) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
  *a = w->cross(helper).normalized();
  *b = w->cross(*a);
}

// A grid of quads between two rows of points, as triangles.
TriangleSurface strip(const std::vector<Vec3>& lower, const std::vector<Vec3>& upper, bool closed) {
  const Index n = static_cast<Index>(lower.size());
  TriangleSurface s;
  s.vertices.resize(2 * n, 3);
  for (Index i = 0; i < n; ++i) {
    s.vertices.row(i) = lower[i].transpose();
    s.vertices.row(n + i) = upper[i].transpose();
  }
  const Index quads = closed ? n : n - 1;
  s.triangles.resize(2 * quads, 3);
  for (Index i = 0; i < quads; ++i) {
    const Index j = (i + 1) % n;
    s.triangles.row(2 * i) << i, j, n + j;
    s.triangles.row(2 * i + 1) << i, n + j, n + i;
  }
  return s;
}

void check_positive(double value, const char* what) {
  if (!(value > 0) || !std::isfinite(value)) throw Error(ErrorKind::kInvalidArgument, std::string(what) + " must be a positive number");
}

}  // namespace

TriangleSurface plane_square(const Vec3& centre, const Vec3& normal, double size) {
  check_positive(size, "a plane's size");
  Vec3 a, b, w;
  frame(normal, &a, &b, &w);
  const double h = size / 2;
  return strip({centre - h * a - h * b, centre + h * a - h * b}, {centre - h * a + h * b, centre + h * a + h * b}, false);
}

TriangleSurface cylinder_side(const Vec3& centre, const Vec3& axis, double radius, double length, int segments) {
  check_positive(radius, "a cylinder's radius");
  check_positive(length, "a cylinder's length");
  if (segments < 3) throw Error(ErrorKind::kInvalidArgument, "a cylinder needs at least 3 segments");
  Vec3 a, b, w;
  frame(axis, &a, &b, &w);
  std::vector<Vec3> lower, upper;
  for (int i = 0; i < segments; ++i) {
    const double angle = 2 * std::numbers::pi * i / segments;
    const Vec3 r = radius * (std::cos(angle) * a + std::sin(angle) * b);
    lower.push_back(centre + r - length / 2 * w);
    upper.push_back(centre + r + length / 2 * w);
  }
  return strip(lower, upper, true);
}

TriangleSurface helical_ribbon(const Vec3& centre, const Vec3& axis, double inner, double outer, double pitch, double turns,
                               int segments_per_turn) {
  if (!(inner >= 0) || !(outer > inner)) throw Error(ErrorKind::kInvalidArgument, "a helix needs 0 <= inner radius < outer radius");
  check_positive(turns, "a helix's number of turns");
  if (!std::isfinite(pitch)) throw Error(ErrorKind::kInvalidArgument, "a helix's pitch must be finite");
  if (segments_per_turn < 3) throw Error(ErrorKind::kInvalidArgument, "a helix needs at least 3 segments per turn");
  Vec3 a, b, w;
  frame(axis, &a, &b, &w);
  const int steps = static_cast<int>(std::ceil(turns * segments_per_turn));
  std::vector<Vec3> lower, upper;
  for (int i = 0; i <= steps; ++i) {
    const double t = turns * i / steps;  // in turns
    const double angle = 2 * std::numbers::pi * t;
    const Vec3 radial = std::cos(angle) * a + std::sin(angle) * b;
    const Vec3 along = centre + pitch * t * w;
    lower.push_back(along + inner * radial);
    upper.push_back(along + outer * radial);
  }
  return strip(lower, upper, false);
}

TriangleSurface cookie_cutter(std::span<const Eigen::Vector2d> profile, const Vec3& origin, const Vec3& u, const Vec3& v,
                              double depth) {
  if (profile.size() < 3) throw Error(ErrorKind::kInvalidArgument, "a cookie cutter's profile needs at least 3 points");
  if (!(depth != 0) || !std::isfinite(depth)) throw Error(ErrorKind::kInvalidArgument, "a cookie cutter's depth must be non-zero");
  const Vec3 normal = u.cross(v);
  if (!(normal.norm() > 0)) throw Error(ErrorKind::kInvalidArgument, "a cookie cutter's u and v must not be parallel");
  std::vector<Vec3> lower, upper;
  for (const Eigen::Vector2d& p : profile) {
    const Vec3 x = origin + p[0] * u + p[1] * v;
    lower.push_back(x);
    upper.push_back(x + depth * normal.normalized());
  }
  return strip(lower, upper, true);
}

Points2 spiral(const Eigen::Vector2d& centre, double outer_radius, double inner_radius, double spacing, double step) {
  const bool finite = centre.allFinite() && std::isfinite(outer_radius) && std::isfinite(inner_radius) &&
                      std::isfinite(spacing) && std::isfinite(step);
  if (!finite || !(step > 0) || !(spacing > 0) || !(outer_radius > 0) || !(inner_radius >= 0 && inner_radius <= outer_radius)) {
    throw Error(ErrorKind::kInvalidArgument,
                "a spiral needs a positive step, spacing and outer radius, and an inner radius from 0 to the outer one");
  }
  // Its length is about pi (R^2 - r^2) / spacing, the points that over step (each at least step
  // apart at the largest radius, closer inside): bound the count before making them.
  constexpr double kMaxPoints = 1e7;
  const double turns = (outer_radius - inner_radius) / spacing;
  if (2 * std::numbers::pi * turns * outer_radius / step > kMaxPoints) {
    throw Error(ErrorKind::kInvalidArgument, "a spiral of more than ten million points: give a larger step or spacing");
  }
  std::vector<Eigen::Vector2d> points;
  for (double turned = 0;;) {
    const double r = outer_radius - spacing * turned / (2 * std::numbers::pi);
    if (r < inner_radius || r <= 0) break;
    const double angle = -std::numbers::pi / 2 - turned;
    points.push_back(centre + r * Eigen::Vector2d(std::cos(angle), std::sin(angle)));
    turned += step / r;  // about `step` of arc
  }
  Points2 out(static_cast<Index>(points.size()), 2);
  for (std::size_t i = 0; i < points.size(); ++i) out.row(static_cast<Index>(i)) = points[i].transpose();
  return out;
}

}  // namespace tetcut
