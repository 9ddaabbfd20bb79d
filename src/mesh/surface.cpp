// Triangle surfaces: their edges.

#include <tetcut/surface.hpp>

#include <algorithm>
#include <array>
#include <vector>

namespace tetcut {

Edges triangle_edges(const Triangles& triangles) {
  std::vector<std::array<Index, 2>> edges;
  edges.reserve(3 * static_cast<std::size_t>(triangles.rows()));
  for (Index t = 0; t < triangles.rows(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Index a = triangles(t, k), b = triangles(t, (k + 1) % 3);
      edges.push_back({std::min(a, b), std::max(a, b)});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Edges out(static_cast<Index>(edges.size()), 2);
  for (std::size_t i = 0; i < edges.size(); ++i) out.row(static_cast<Index>(i)) << edges[i][0], edges[i][1];
  return out;
}

}  // namespace tetcut
