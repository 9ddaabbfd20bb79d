#include <tetcut/blade.hpp>

#include <vector>

#include "geometry/predicates.hpp"

namespace tetcut {

TriangleSurface swept_blade(std::span<const BladePose> poses) {
  TriangleSurface s;
  const Index n = static_cast<Index>(poses.size());
  s.vertices.resize(2 * n, 3);
  for (Index i = 0; i < n; ++i) {
    s.vertices.row(2 * i) = poses[i].a.transpose();
    s.vertices.row(2 * i + 1) = poses[i].b.transpose();
  }

  std::vector<std::array<Index, 3>> triangles;
  const auto add = [&](Index p, Index q, Index r) {
    const Vec3 a = s.vertices.row(p), b = s.vertices.row(q), c = s.vertices.row(r);
    if (!geometry::collinear(a, b, c)) triangles.push_back({p, q, r});
  };
  for (Index i = 0; i + 1 < n; ++i) {
    const Index a0 = 2 * i, b0 = 2 * i + 1, a1 = 2 * i + 2, b1 = 2 * i + 3;
    add(a0, b0, b1);
    add(a0, b1, a1);
  }
  s.triangles.resize(static_cast<Index>(triangles.size()), 3);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) s.triangles(static_cast<Index>(t), k) = triangles[t][k];
  }
  return s;
}

}  // namespace tetcut
