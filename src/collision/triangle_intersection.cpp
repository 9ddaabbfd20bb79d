// Exact intersection of closed triangles. Two non-coplanar triangles meet exactly when an edge of
// one meets the other (their common points lie on the planes' line, and an end of that segment
// is on an edge); coplanar ones meet when an edge of one meets the other in their plane, which
// also covers one inside the other (its edges' ends are inside). Each test is a sign of orient3d
// or, in a plane, of orient2d on a coordinate projection: no arithmetic outside the predicates.

#include <tetcut/collision.hpp>

#include "geometry/predicates.hpp"

namespace tetcut {
namespace {

using geometry::orient2d;
using geometry::orient3d;

using Point2 = std::array<double, 2>;

// Drops coordinate `axis`.
Point2 project(const Vec3& p, int axis) {
  return axis == 0 ? Point2{p[1], p[2]} : axis == 1 ? Point2{p[0], p[2]} : Point2{p[0], p[1]};
}

int o2(const Point2& a, const Point2& b, const Point2& c) { return orient2d(a.data(), b.data(), c.data()); }

// Whether c (collinear with a, b) lies on the closed segment ab.
bool within(const Point2& a, const Point2& b, const Point2& c) {
  return std::min(a[0], b[0]) <= c[0] && c[0] <= std::max(a[0], b[0]) && std::min(a[1], b[1]) <= c[1] && c[1] <= std::max(a[1], b[1]);
}

bool segments_meet(const Point2& p, const Point2& q, const Point2& r, const Point2& s) {
  const int d1 = o2(p, q, r), d2 = o2(p, q, s), d3 = o2(r, s, p), d4 = o2(r, s, q);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && within(p, q, r)) || (d2 == 0 && within(p, q, s)) || (d3 == 0 && within(r, s, p)) || (d4 == 0 && within(r, s, q));
}

bool inside(const Point2& p, const std::array<Point2, 3>& t) {
  const int s0 = o2(t[0], t[1], p), s1 = o2(t[1], t[2], p), s2 = o2(t[2], t[0], p);
  return !((s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0));
}

// Segment pq in the plane of the non-degenerate triangle t: in a projection where t keeps its area.
bool coplanar_segment_meets(const Vec3& p, const Vec3& q, const std::array<Vec3, 3>& t) {
  int axis = 0;
  for (; axis < 3; ++axis) {
    if (o2(project(t[0], axis), project(t[1], axis), project(t[2], axis)) != 0) break;
  }
  const std::array<Point2, 3> t2{project(t[0], axis), project(t[1], axis), project(t[2], axis)};
  const Point2 p2 = project(p, axis), q2 = project(q, axis);
  if (inside(p2, t2) || inside(q2, t2)) return true;
  for (int k = 0; k < 3; ++k) {
    if (segments_meet(p2, q2, t2[k], t2[(k + 1) % 3])) return true;
  }
  return false;
}

// Whether the closed segment pq meets the closed, non-degenerate triangle t.
bool segment_meets(const Vec3& p, const Vec3& q, const std::array<Vec3, 3>& t) {
  const int sp = orient3d(t[0], t[1], t[2], p), sq = orient3d(t[0], t[1], t[2], q);
  if (sp != 0 && sp == sq) return false;  // both strictly on one side
  if (sp == 0 && sq == 0) return coplanar_segment_meets(p, q, t);
  // pq meets the plane in one point; it is in the triangle when the line pq passes on no
  // edge's outer side (the three signs do not differ).
  const int s0 = orient3d(p, q, t[0], t[1]), s1 = orient3d(p, q, t[1], t[2]), s2 = orient3d(p, q, t[2], t[0]);
  return !((s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0));
}

}  // namespace

bool triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
  for (int k = 0; k < 3; ++k) {
    if (segment_meets(a[k], a[(k + 1) % 3], b) || segment_meets(b[k], b[(k + 1) % 3], a)) return true;
  }
  return false;
}

}  // namespace tetcut
