// Combinatorial checks of a surface to embed, and the lattice around it.

#include <tetcut/embed.hpp>
#include <tetcut/error.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "geometry/predicates.hpp"
#include "mesh/surface_checks.hpp"
#include "util/union_find.hpp"

namespace tetcut {
namespace {

// Welded id per vertex: vertices with identical coordinates (-0.0 and 0.0 alike) share the id of
// the first of them. O(V log V).
std::vector<Index> weld(const Points& vertices, Index* distinct) {
  std::vector<Index> order(static_cast<std::size_t>(vertices.rows()));
  std::iota(order.begin(), order.end(), Index{0});
  const auto key = [&](Index v) {
    return std::array<double, 3>{vertices(v, 0) + 0.0, vertices(v, 1) + 0.0, vertices(v, 2) + 0.0};
  };
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) { return key(a) < key(b); });
  std::vector<Index> id(order.size());
  *distinct = 0;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i > 0 && key(order[i]) == key(order[i - 1])) {
      id[order[i]] = id[order[i - 1]];
    } else {
      id[order[i]] = order[i];
      ++*distinct;
    }
  }
  return id;
}

}  // namespace

SurfaceCheck check_surface(const TriangleSurface& surface) {
  SurfaceCheck check;
  check.triangles = surface.num_triangles();
  check_triangles(surface, "surface");
  const std::vector<Index> id = weld(surface.vertices, &check.vertices);

  // Directed edges as (low, high, +1 when it runs low -> high); sorted, each undirected edge is a
  // run whose direction sum says whether it is balanced.
  struct DirectedEdge {
    Index low, high;
    int direction;
  };
  std::vector<DirectedEdge> edges;
  edges.reserve(3 * static_cast<std::size_t>(surface.num_triangles()));
  UnionFind vertex_classes(static_cast<std::size_t>(surface.num_vertices()));
  for (Index t = 0; t < surface.num_triangles(); ++t) {
    std::array<Index, 3> v;
    std::array<Vec3, 3> x;
    for (int k = 0; k < 3; ++k) {
      v[k] = id[surface.triangles(t, k)];
      x[k] = surface.vertices.row(v[k]).transpose();
    }
    if (geometry::collinear(x[0], x[1], x[2])) ++check.degenerate_triangles;
    for (int k = 0; k < 3; ++k) {
      const Index a = v[k], b = v[(k + 1) % 3];
      if (a == b) continue;
      edges.push_back({std::min(a, b), std::max(a, b), a < b ? 1 : -1});
      vertex_classes.join(a, b);
    }
  }
  std::sort(edges.begin(), edges.end(),
            [](const DirectedEdge& p, const DirectedEdge& q) { return std::tie(p.low, p.high) < std::tie(q.low, q.high); });
  for (std::size_t begin = 0; begin < edges.size();) {
    std::size_t end = begin;
    int balance = 0;
    while (end < edges.size() && edges[end].low == edges[begin].low && edges[end].high == edges[begin].high) {
      balance += edges[end].direction;
      ++end;
    }
    const auto uses = static_cast<int>(end - begin);
    if (uses > 2) ++check.nonmanifold_edges;
    if (balance != 0) {
      ++check.unbalanced_edges;
      if (uses >= 2 && std::abs(balance) == uses) ++check.misoriented_edges;
    }
    begin = end;
  }
  // Components: classes of the vertices used by triangles.
  std::vector<std::uint8_t> used(static_cast<std::size_t>(surface.num_vertices()), 0);
  for (Index t = 0; t < surface.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) used[id[surface.triangles(t, k)]] = 1;
  }
  for (Index v = 0; v < surface.num_vertices(); ++v) {
    if (used[v] && vertex_classes.find(v) == v) ++check.components;
  }
  return check;
}

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
