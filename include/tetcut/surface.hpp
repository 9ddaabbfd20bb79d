#pragma once
// Triangle surfaces: cut soups and material surfaces. A soup need not be manifold, closed or
// free of self-intersections.

#include <tetcut/types.hpp>

namespace tetcut {

struct TriangleSurface {
  Points vertices;     ///< |V| x 3
  Triangles triangles; ///< |F| x 3, ids below |V|

  Index num_vertices() const { return static_cast<Index>(vertices.rows()); }
  Index num_triangles() const { return static_cast<Index>(triangles.rows()); }
};

/// The distinct edges of a set of triangles (|F| x 3 vertex ids), each once with its smaller id
/// first, sorted: |E| x 2. For drawing a mesh's edges. O(F log F).
Edges triangle_edges(const Triangles& triangles);

}  // namespace tetcut
