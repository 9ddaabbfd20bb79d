#pragma once
// Parametric cutting surfaces, as triangle soups to feed a Cutter: a square in a plane, the side of
// a cylinder, a helical ribbon, and a "cookie cutter" (a closed 2D profile extruded along a
// direction). Each is open; tets are cut only where the surface passes. And a planar cut for the
// planar cutter: a spiral polyline (the paper's Figure 1).

#include <tetcut/planar_cutter.hpp>
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

/// A spiral in the plane (|P| x 2 points, for a Polyline): from the point `outer_radius` straight
/// below `centre` (towards -v), clockwise about it, the radius shrinking by `spacing` a turn, to
/// where it would fall below `inner_radius`; points about `step` apart along the arc. Throws
/// Error(kInvalidArgument) unless step, spacing and outer_radius are positive and inner_radius
/// lies in [0, outer_radius], or when that would take more than ten million points.
Points2 spiral(const Eigen::Vector2d& centre, double outer_radius, double inner_radius, double spacing, double step);

}  // namespace tetcut
