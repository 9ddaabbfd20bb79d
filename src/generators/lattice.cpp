#include "generators/lattice.hpp"

#include <tetcut/error.hpp>

#include <cmath>
#include <utility>

#include "geometry/predicates.hpp"

namespace tetcut {
namespace generators {

void check_box(const Box& box) {
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(box.min[a]) || !std::isfinite(box.max[a]) || !(box.min[a] < box.max[a])) {
      throw Error(ErrorKind::kInvalidArgument, "the box must have finite bounds with min < max on every axis");
    }
  }
}

TetMesh assemble(Points points, std::vector<std::array<Index, 4>>& tets) {
  Tets buffer(static_cast<Eigen::Index>(tets.size()), 4);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    std::array<Index, 4>& tet = tets[t];
    const int orientation = geometry::orient3d(points.row(tet[0]).data(), points.row(tet[1]).data(),
                                               points.row(tet[2]).data(), points.row(tet[3]).data());
    if (orientation < 0) std::swap(tet[2], tet[3]);
    for (int k = 0; k < 4; ++k) buffer(static_cast<Eigen::Index>(t), k) = tet[k];
  }
  return TetMesh(std::move(points), std::move(buffer), "generated mesh");
}

}  // namespace generators

}  // namespace tetcut
