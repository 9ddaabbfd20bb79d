#include "mesh/surface_checks.hpp"

#include <tetcut/error.hpp>

#include <string>

namespace tetcut {

void check_triangles(const TriangleSurface& surface, std::string_view what) {
  for (Index i = 0; i < surface.num_triangles(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const Index v = surface.triangles(i, k);
      const std::string triangle = std::string(what) + " triangle " + std::to_string(i);
      if (v < 0 || v >= surface.num_vertices()) {
        throw Error(ErrorKind::kInvalidInput, triangle + " refers to vertex " + std::to_string(v) + ", which does not exist");
      }
      if (!surface.vertices.row(v).allFinite()) {
        throw Error(ErrorKind::kInvalidInput, triangle + " has a corner that is not finite");
      }
    }
  }
}

}  // namespace tetcut
