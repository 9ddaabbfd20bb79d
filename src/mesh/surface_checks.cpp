// Everything that checks a triangle surface: its indices and corners (check_triangles), its
// measures as given (measure_surface) and its combinatorics after welding (check_surface). The two
// counts of edges share one census.

#include "mesh/surface_checks.hpp"

#include <tetcut/error.hpp>
#include <tetcut/quality.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

#include "geometry/predicates.hpp"
#include "util/union_find.hpp"

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

namespace {

// One use of an undirected edge by a triangle: its ends, lower id first, and +1 when the triangle
// runs it from low to high, -1 when back.
struct EdgeUse {
  Index low, high;
  int direction;
};

EdgeUse edge_use(Index from, Index to) { return from < to ? EdgeUse{from, to, 1} : EdgeUse{to, from, -1}; }

// Calls visit(uses, balance) once per undirected edge in `uses`: how many triangles use it and
// the sum of their directions, zero when it is used as often one way as the other. O(E log E).
template <typename Visit>
void for_each_edge(std::vector<EdgeUse>& uses, Visit&& visit) {
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& p, const EdgeUse& q) { return std::tie(p.low, p.high) < std::tie(q.low, q.high); });
  for (std::size_t begin = 0; begin < uses.size();) {
    std::size_t end = begin;
    int balance = 0;
    while (end < uses.size() && uses[end].low == uses[begin].low && uses[end].high == uses[begin].high) balance += uses[end++].direction;
    visit(static_cast<int>(end - begin), balance);
    begin = end;
  }
}

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

SurfaceStats measure_surface(const TriangleSurface& surface) {
  SurfaceStats s;
  const Points& v = surface.vertices;
  if (v.rows() > 0) {
    s.bbox_min = v.colwise().minCoeff().transpose();
    s.bbox_max = v.colwise().maxCoeff().transpose();
  }
  std::vector<EdgeUse> edges;
  edges.reserve(static_cast<std::size_t>(surface.num_triangles()) * 3);
  for (Index f = 0; f < surface.num_triangles(); ++f) {
    const Vec3 a = v.row(surface.triangles(f, 0)), b = v.row(surface.triangles(f, 1)), c = v.row(surface.triangles(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    s.area += 0.5 * n.norm();
    s.enclosed_volume += a.dot(b.cross(c)) / 6.0;
    if (geometry::collinear(a, b, c)) ++s.num_degenerate_triangles;
    for (int k = 0; k < 3; ++k) edges.push_back(edge_use(surface.triangles(f, k), surface.triangles(f, (k + 1) % 3)));
  }
  for_each_edge(edges, [&](int uses, int balance) {
    if (uses == 1) ++s.num_boundary_edges;
    if (uses > 2) ++s.num_nonmanifold_edges;
    if (balance != 0) ++s.num_unbalanced_edges;
  });
  s.two_manifold = surface.num_triangles() > 0 && s.num_boundary_edges == 0 && s.num_nonmanifold_edges == 0;
  s.balanced = surface.num_triangles() > 0 && s.num_unbalanced_edges == 0;
  return s;
}

SurfaceCheck check_surface(const TriangleSurface& surface) {
  SurfaceCheck check;
  check.triangles = surface.num_triangles();
  check_triangles(surface, "surface");
  const std::vector<Index> id = weld(surface.vertices, &check.vertices);

  std::vector<EdgeUse> edges;
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
      if (a == b) continue;  // welded into a point: no edge
      edges.push_back(edge_use(a, b));
      vertex_classes.join(a, b);
    }
  }
  for_each_edge(edges, [&](int uses, int balance) {
    if (uses > 2) ++check.nonmanifold_edges;
    if (balance != 0) {
      ++check.unbalanced_edges;
      if (uses >= 2 && std::abs(balance) == uses) ++check.misoriented_edges;
    }
  });
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

}  // namespace tetcut
