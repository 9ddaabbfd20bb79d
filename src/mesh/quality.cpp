#include <tetcut/quality.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace tetcut {

MeshQuality measure_quality(const TetMesh& mesh, bool current) {
  const Points& p = current ? mesh.current() : mesh.rest();
  MeshQuality q;
  if (p.rows() > 0) {
    q.bbox_min = p.colwise().minCoeff().transpose();
    q.bbox_max = p.colwise().maxCoeff().transpose();
  }
  std::vector<char> used(static_cast<std::size_t>(mesh.num_nodes()), 0);
  q.min_volume = std::numeric_limits<double>::infinity();
  q.min_altitude = std::numeric_limits<double>::infinity();
  double min_cos = -1, max_cos = 1;  // cosines of the largest and smallest angles seen
  const Tets& tets = mesh.tets();
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    std::array<Vec3, 4> x;
    for (int k = 0; k < 4; ++k) {
      x[k] = p.row(tets(t, k));
      used[tets(t, k)] = 1;
    }
    const double volume = signed_volume(x[0], x[1], x[2], x[3]);
    q.volume += volume;
    q.min_volume = std::min(q.min_volume, volume);
    double max_face_area = 0;
    for (const auto& face : kTetFaces) {
      const double area = 0.5 * (x[face[1]] - x[face[0]]).cross(x[face[2]] - x[face[0]]).norm();
      max_face_area = std::max(max_face_area, area);
    }
    if (max_face_area > 0) q.min_altitude = std::min(q.min_altitude, 3.0 * volume / max_face_area);
    for (const auto& edge : kTetEdges) {
      // The two vertices off this edge.
      int others[2], n = 0;
      for (int k = 0; k < 4; ++k) {
        if (k != edge[0] && k != edge[1]) others[n++] = k;
      }
      const Vec3 axis = x[edge[1]] - x[edge[0]];
      const Vec3 n1 = axis.cross(x[others[0]] - x[edge[0]]);
      const Vec3 n2 = axis.cross(x[others[1]] - x[edge[0]]);
      const double denominator = n1.norm() * n2.norm();
      if (denominator == 0) continue;
      const double c = std::clamp(n1.dot(n2) / denominator, -1.0, 1.0);
      max_cos = std::min(max_cos, c);  // smallest cosine: largest angle
      min_cos = std::max(min_cos, c);  // largest cosine: smallest angle
    }
  }
  if (mesh.num_tets() == 0) {
    q.min_volume = 0;
    q.min_altitude = 0;
  }
  const double to_degrees = 180.0 / std::numbers::pi;
  q.min_dihedral_degrees = std::acos(min_cos) * to_degrees;
  q.max_dihedral_degrees = std::acos(max_cos) * to_degrees;
  q.num_unused_nodes = static_cast<Index>(std::count(used.begin(), used.end(), 0));
  return q;
}

}  // namespace tetcut
