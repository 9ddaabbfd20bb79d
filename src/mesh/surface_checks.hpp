#pragma once
// Checks of triangle surfaces handed to the library (cut batches, surfaces to embed). The public
// measures and checks of a surface, measure_surface and check_surface (tetcut/quality.hpp), are
// defined beside these, in surface_checks.cpp.

#include <tetcut/surface.hpp>

#include <array>
#include <string_view>

namespace tetcut {

/// Throws Error(kInvalidInput) naming the triangle ("<what> triangle i ...") when it refers to a
/// vertex that does not exist or has a corner that is not finite. O(F).
void check_triangles(const TriangleSurface& surface, std::string_view what);

/// The corners of triangle i.
inline std::array<Vec3, 3> triangle_corners(const TriangleSurface& surface, Index i) {
  return {surface.vertices.row(surface.triangles(i, 0)).transpose(), surface.vertices.row(surface.triangles(i, 1)).transpose(),
          surface.vertices.row(surface.triangles(i, 2)).transpose()};
}

}  // namespace tetcut
