#pragma once
// Exact geometric predicates on input (double) points.
//
// Each predicate first evaluates in double precision with a forward error bound; only when the
// rounded value is too close to zero for the bound to fix its sign does it evaluate exactly with
// GMP rationals (every double is a rational, so the exact value is the true sign for the inputs).

#include <tetcut/types.hpp>

namespace tetcut::geometry {

/// Sign (+1, 0, -1) of det[b - a, c - a, d - a]: +1 when d lies on the side of the plane (a, b, c)
/// that (b - a) x (c - a) points to. Exact for all finite inputs.
int orient3d(const double* a, const double* b, const double* c, const double* d);

inline int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return orient3d(a.data(), b.data(), c.data(), d.data());
}

/// Sign of det[b - a, c - a] for 2D points (x, y). Exact.
int orient2d(const double* a, const double* b, const double* c);

/// True when a, b, c lie exactly on one line (including coincident points): all three
/// coordinate-plane projections have zero orientation.
bool collinear(const Vec3& a, const Vec3& b, const Vec3& c);

/// The same sign computed only exactly (no filter); for tests of the filter.
int orient3d_exact(const double* a, const double* b, const double* c, const double* d);

}  // namespace tetcut::geometry
