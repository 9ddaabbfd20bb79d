#include "surface/material_surface.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <limits>
#include <unordered_map>

namespace tetcut::surface {
namespace {

using cells::CellComplex;
using cells::Corner;
using cells::Facet;
using cells::Side;
using registry::PlaneId;
using registry::VertexId;

// A surface vertex: a point (mesh node n as n, intersection v as num_nodes + v) and the nodes of
// the copy that carry weight there, ascending, padded with -1.
struct VertexKey {
  std::int64_t point;
  std::array<Index, 4> nodes;
  bool operator==(const VertexKey&) const = default;
};

struct VertexKeyHash {
  std::size_t operator()(const VertexKey& k) const {
    std::uint64_t h = static_cast<std::uint64_t>(k.point) * 0x9e3779b97f4a7c15ULL;
    for (const Index n : k.nodes) h = (h ^ static_cast<std::uint32_t>(n)) * 0xbf58476d1ce4e5b9ULL;
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

class SurfaceBuilder {
 public:
  SurfaceBuilder(const CellComplex& complex, const connectivity::TetCopies& copies)
      : complex_(complex), copies_(copies), mesh_(complex.mesh()) {}

  // Surface vertex for registry vertex v in tet copy `copy`.
  Index vertex(VertexId v, Index copy) {
    const std::uint64_t cache_key = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(v)) << 32) |
                                    static_cast<std::uint32_t>(copy);
    const auto cached = by_vertex_and_copy_.find(cache_key);
    if (cached != by_vertex_and_copy_.end()) return cached->second;
    const registry::IntersectionRegistry& reg = complex_.registry();
    const Index tet = copies_.copy_tet[copy];
    const Index node = reg.vertex(v).node;
    Index id;
    if (node >= 0) {
      id = node_vertex(node, copy);
    } else {
      // Weight k vanishes exactly where the point lies on the face opposite node k. Faces of refined
      // tets have registry planes (cached exact forms); others are built here.
      const Points& rest = mesh_.rest();
      const Tets& tets = mesh_.tets();
      bool zero[4];
      for (int k = 0; k < 4; ++k) {
        const PlaneId plane = complex_.face_plane_id(mesh_.adjacency().tet_faces(tet, k));
        if (plane >= 0) {
          zero[k] = reg.side(v, plane) == 0;
        } else {
          const auto& f = kTetFaces[k];
          zero[k] = reg.side(v, geometry::Plane::through(rest.row(tets(tet, f[0])).transpose(),
                                                        rest.row(tets(tet, f[1])).transpose(),
                                                        rest.row(tets(tet, f[2])).transpose())) == 0;
        }
      }
      VertexKey key{mesh_.num_nodes() + static_cast<std::int64_t>(v), {-1, -1, -1, -1}};
      for (int k = 0; k < 4; ++k) key.nodes[k] = zero[k] ? -1 : copies_.copy_nodes(copy, k);
      std::sort(key.nodes.begin(), key.nodes.end());
      id = find_or_add(key, reg.position(v), copy, zero);
    }
    by_vertex_and_copy_.emplace(cache_key, id);
    return id;
  }

  // Surface vertex for mesh node `node` in tet copy `copy`.
  Index node_vertex(Index node, Index copy) {
    const Index tet = copies_.copy_tet[copy];
    bool zero[4];
    int local = 0;
    for (int k = 0; k < 4; ++k) {
      zero[k] = mesh_.tets()(tet, k) != node;
      if (!zero[k]) local = k;
    }
    const VertexKey key{node, {-1, -1, -1, copies_.copy_nodes(copy, local)}};
    return find_or_add(key, mesh_.rest().row(node).transpose(), copy, zero);
  }

  void add_triangle(Index a, Index b, Index c, std::int64_t source, Index copy) {
    triangles_.push_back({a, b, c});
    sources_.push_back(source);
    triangle_tets_.push_back(copy);
  }

  MaterialSurface finish() {
    MaterialSurface s;
    s.surface.vertices.resize(static_cast<Index>(positions_.size()), 3);
    s.vertex_weights.resize(static_cast<Index>(positions_.size()), 4);
    for (std::size_t i = 0; i < positions_.size(); ++i) {
      s.surface.vertices.row(static_cast<Index>(i)) = positions_[i].transpose();
      s.vertex_weights.row(static_cast<Index>(i)) = weights_[i].transpose();
    }
    s.surface.triangles.resize(static_cast<Index>(triangles_.size()), 3);
    for (std::size_t i = 0; i < triangles_.size(); ++i) {
      for (int k = 0; k < 3; ++k) s.surface.triangles(static_cast<Index>(i), k) = triangles_[i][k];
    }
    s.vertex_tet = std::move(vertex_tets_);
    s.triangle_source = std::move(sources_);
    s.triangle_tet = std::move(triangle_tets_);
    return s;
  }

 private:
  Index find_or_add(const VertexKey& key, const Vec3& position, Index copy, const bool (&zero)[4]) {
    const auto [it, inserted] = by_key_.try_emplace(key, static_cast<Index>(positions_.size()));
    if (!inserted) return it->second;
    positions_.push_back(position);
    vertex_tets_.push_back(copy);
    weights_.push_back(barycentric(copies_.copy_tet[copy], position, zero));
    return it->second;
  }

  // Barycentric weights of p in the rest tet, with the weights known to vanish set to exactly zero.
  Eigen::Vector4d barycentric(Index tet, const Vec3& p, const bool (&zero)[4]) const {
    const Points& rest = mesh_.rest();
    const Tets& tets = mesh_.tets();
    const Vec3 r0 = rest.row(tets(tet, 0)).transpose();
    Eigen::Matrix3d edges;
    for (int k = 0; k < 3; ++k) edges.col(k) = rest.row(tets(tet, k + 1)).transpose() - r0;
    const Vec3 w = edges.partialPivLu().solve(p - r0);
    Eigen::Vector4d weights(1 - w.sum(), w[0], w[1], w[2]);
    double sum = 0;
    for (int k = 0; k < 4; ++k) {
      if (zero[k]) weights[k] = 0;
      sum += weights[k];
    }
    return weights / sum;
  }

  const CellComplex& complex_;
  const connectivity::TetCopies& copies_;
  const TetMesh& mesh_;
  std::unordered_map<std::uint64_t, Index> by_vertex_and_copy_;
  std::unordered_map<VertexKey, Index, VertexKeyHash> by_key_;
  std::vector<Vec3> positions_;
  std::vector<Eigen::Vector4d> weights_;
  std::vector<Index> vertex_tets_;
  std::vector<std::array<Index, 3>> triangles_;
  std::vector<std::int64_t> sources_;
  std::vector<Index> triangle_tets_;
};

// Source of an uncovered facet on the material's boundary: the mesh face it lies on.
std::int64_t face_source(Index face) { return -1 - static_cast<std::int64_t>(face); }

}  // namespace

void triangulate_convex_polygon(std::vector<std::uint8_t> strict, bool reverse, std::vector<std::array<int, 3>>* triangles) {
  const int n = static_cast<int>(strict.size());
  const auto emit = [&](int a, int b, int c) {
    triangles->push_back(reverse ? std::array<int, 3>{a, c, b} : std::array<int, 3>{a, b, c});
  };
  std::vector<int> prev(static_cast<std::size_t>(n)), next(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    prev[i] = (i + n - 1) % n;
    next[i] = (i + 1) % n;
  }
  // Clip a strict corner; with only three strict corners left, clip one next to a collinear run,
  // so the rest keeps positive area. The neighbours of a clipped strict corner become strict (a
  // line through three boundary points of a convex polygon supports it, so the new diagonal
  // cannot be collinear with the next corner unless the whole rest were).
  int remaining = n, start = 0;
  while (remaining > 3) {
    int strict_count = 0;
    for (int i = start, k = 0; k < remaining; i = next[i], ++k) strict_count += strict[i];
    int ear = -1;
    for (int i = start, k = 0; k < remaining && ear < 0; i = next[i], ++k) {
      if (strict[i] && (strict_count > 3 || !strict[prev[i]] || !strict[next[i]])) ear = i;
    }
    if (ear < 0) throw std::logic_error("surface: a polygon has no clippable corner");
    emit(prev[ear], ear, next[ear]);
    strict[prev[ear]] = strict[next[ear]] = 1;
    next[prev[ear]] = next[ear];
    prev[next[ear]] = prev[ear];
    start = next[ear];
    --remaining;
  }
  emit(prev[start], start, next[start]);
}

void triangulate_facet(const CellComplex& complex, const Facet& facet, bool reverse,
                       std::vector<std::array<int, 3>>* triangles) {
  const registry::IntersectionRegistry& reg = complex.registry();
  const auto& corners = facet.corners;
  const int n = static_cast<int>(corners.size());
  // Corner i is strict when the next corner is off the line of the edge arriving at i.
  std::vector<std::uint8_t> strict(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const cells::Edge& arriving = complex.edges()[corners[(i + n - 1) % n].edge];
    const VertexId w = corners[(i + 1) % n].vertex;
    strict[i] = n == 3 || reg.side(w, arriving.line[0]) != 0 || reg.side(w, arriving.line[1]) != 0;
  }
  triangulate_convex_polygon(std::move(strict), reverse, triangles);
}

MaterialSurface extract_material_surface(const CellComplex& complex, const components::MaterialComponents& components,
                                         const connectivity::TetCopies& copies) {
  const TetMesh& mesh = complex.mesh();
  const TetAdjacency& adj = mesh.adjacency();
  complex.registry().update_positions();
  SurfaceBuilder builder(complex, copies);
  const auto copy_on = [&](Side s) -> Index {
    if (cells::is_cell(s)) return copies.copy_of(complex.cells()[s].tet, components.cell_component[s]);
    return copies.first_copy[cells::unrefined_tet(s)];
  };

  // Facets of refined tets.
  std::vector<std::array<int, 3>> triangles;
  std::vector<Index> ids;
  for (const Facet& facet : complex.facets()) {
    for (const bool front : {false, true}) {
      const Side side = front ? facet.front : facet.back;
      const Side other = front ? facet.back : facet.front;
      if (!complex.side_is_material(side) || (!facet.covered() && complex.side_is_material(other))) continue;
      const Index copy = copy_on(side);
      // Stored order is outward for the cell behind the facet.
      triangles.clear();
      triangulate_facet(complex, facet, front, &triangles);
      ids.clear();
      for (const Corner& corner : facet.corners) ids.push_back(builder.vertex(corner.vertex, copy));
      const std::int64_t source = facet.covered() ? facet.cut
                                  : facet.mesh_face >= 0 ? face_source(facet.mesh_face)
                                                         : std::numeric_limits<std::int64_t>::min();
      for (const auto& t : triangles) builder.add_triangle(ids[t[0]], ids[t[1]], ids[t[2]], source, copy);
    }
  }

  // Whole faces between unrefined tets, or of an unrefined tet on the boundary.
  const Tets& tets = mesh.tets();
  std::vector<VertexId> points;
  for (Index face = 0; face < adj.num_faces(); ++face) {
    if (complex.first_facet_on_face(face) >= 0) continue;
    const auto around = adj.tets_of_face(face);
    for (const Index tet : around) {
      if (!complex.tet_material(tet)) continue;
      bool exposed = around.size() == 1;
      for (const Index other : around) exposed = exposed || (other != tet && !complex.tet_material(other));
      if (!exposed) continue;
      // The face's polygon: its nodes in outward order, and the points refined tets around its
      // edges have put on them.
      int local = 0;
      while (adj.tet_faces(tet, local) != face) ++local;
      const Index copy = copies.first_copy[tet];
      ids.clear();
      std::vector<std::uint8_t> strict;
      for (int k = 0; k < 3; ++k) {
        const Index from = tets(tet, kTetFaces[local][k]), to = tets(tet, kTetFaces[local][(k + 1) % 3]);
        ids.push_back(builder.node_vertex(from, copy));
        strict.push_back(1);
        Index mesh_edge = -1;
        for (int e = 0; e < 6; ++e) {
          const Index a = tets(tet, kTetEdges[e][0]), b = tets(tet, kTetEdges[e][1]);
          if ((a == from && b == to) || (a == to && b == from)) mesh_edge = adj.tet_edges(tet, e);
        }
        points.clear();
        complex.mesh_edge_points(mesh_edge, from, to, &points);
        for (const VertexId v : points) {
          ids.push_back(builder.vertex(v, copy));
          strict.push_back(0);
        }
      }
      triangles.clear();
      triangulate_convex_polygon(std::move(strict), false, &triangles);
      for (const auto& t : triangles) builder.add_triangle(ids[t[0]], ids[t[1]], ids[t[2]], face_source(face), copy);
    }
  }
  return builder.finish();
}

}  // namespace tetcut::surface
