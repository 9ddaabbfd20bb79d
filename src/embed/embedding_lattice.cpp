// The lattice around a surface to embed, and its spacing.

#include <tetcut/embed.hpp>
#include <tetcut/error.hpp>

#include <cmath>
#include <limits>

#include "mesh/surface_checks.hpp"

namespace tetcut {
namespace {

Box surface_box(const TriangleSurface& surface) {
  if (surface.num_triangles() == 0) throw Error(ErrorKind::kInvalidInput, "the surface has no triangles");
  check_triangles(surface, "surface");
  Box box{Vec3::Constant(std::numeric_limits<double>::infinity()), Vec3::Constant(-std::numeric_limits<double>::infinity())};
  for (Index t = 0; t < surface.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Vec3 x = surface.vertices.row(surface.triangles(t, k)).transpose();
      box.min = box.min.cwiseMin(x);
      box.max = box.max.cwiseMax(x);
    }
  }
  return box;
}

}  // namespace

TetMesh embedding_lattice(const TriangleSurface& surface, double spacing) {
  if (!(spacing > 0) || !std::isfinite(spacing)) {
    throw Error(ErrorKind::kInvalidArgument, "lattice spacing must be a positive number");
  }
  Box box = surface_box(surface);
  box.min -= Vec3::Constant(spacing);
  box.max += Vec3::Constant(spacing);
  return make_bcc(box, spacing);
}

double spacing_for_cubes(const TriangleSurface& surface, Index cubes) {
  if (cubes < 1) throw Error(ErrorKind::kInvalidArgument, "the number of lattice cubes must be at least 1");
  const Box box = surface_box(surface);
  const double extent = (box.max - box.min).maxCoeff();
  if (!(extent > 0)) throw Error(ErrorKind::kInvalidInput, "the surface has no extent: all its corners coincide");
  return extent / cubes;
}

}  // namespace tetcut
