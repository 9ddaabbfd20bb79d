#pragma once
// Checks of triangle surfaces handed to the library (cut batches, surfaces to embed).

#include <tetcut/surface.hpp>

#include <string_view>

namespace tetcut {

/// Throws Error(kInvalidInput) naming the triangle ("<what> triangle i ...") when it refers to a
/// vertex that does not exist or has a corner that is not finite. O(F).
void check_triangles(const TriangleSurface& surface, std::string_view what);

}  // namespace tetcut
