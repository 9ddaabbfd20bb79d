#pragma once
// Parametric cutting surfaces, as triangle soups to feed a Cutter: a square in a plane, the side of
// a cylinder, a helical ribbon, and a "cookie cutter" (a closed 2D profile extruded along a
// direction). Each is open; tets are cut only where the surface passes.

#include <tetcut/surface.hpp>

#include <span>

namespace tetcut {

/// A square of side `size` centred on `centre`, in the plane with normal `normal`.
TriangleSurface plane_square(const Vec3& centre, const Vec3& normal, double size);

/// The side of a cylinder: radius `radius` around the axis through `centre` along `axis`,
/// `length` long (centred on `centre`), as `segments` flat panels (at least 3).
TriangleSurface cylinder_side(const Vec3& centre, const Vec3& axis, double radius, double length, int segments);

/// A helical ribbon (a strip of a helicoid) around the axis through `centre` along `axis`:
/// between radii `inner` and `outer`, rising `pitch` per turn for `turns` turns starting at
/// `centre`, with `segments_per_turn` panels per turn (at least 3).
TriangleSurface helical_ribbon(const Vec3& centre, const Vec3& axis, double inner, double outer, double pitch,
                               double turns, int segments_per_turn);

/// A closed profile (2D points, at least 3, in the plane through `origin` spanned by `u` and `v`)
/// extruded along u x v from `origin` by `depth` (negative: the other way): the walls of a
/// cookie cutter.
TriangleSurface cookie_cutter(std::span<const Eigen::Vector2d> profile, const Vec3& origin, const Vec3& u, const Vec3& v,
                              double depth);

}  // namespace tetcut
