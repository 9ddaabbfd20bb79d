#include "surface/material_surface.hpp"

#include <Eigen/LU>
#include <tbb/parallel_for.h>

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

// One polygon of the surface before its vertices get ids: corners as keys, triangles as corner
// index triples.
struct Polygon {
  Index copy = -1;
  std::int64_t source = 0;
  std::vector<VertexKey> keys;
  std::vector<std::int64_t> points;     // per corner: the point (see VertexKey::point)
  std::vector<std::uint8_t> zero_mask;  // per corner: bit k set when weight k is exactly zero
  std::vector<std::array<int, 3>> triangles;
};

// Computes keys of polygon corners; safe to run concurrently (side tests are, outside insertion).
class Keys {
 public:
  Keys(const CellComplex& complex, const connectivity::TetCopies& copies)
      : complex_(complex), copies_(copies), mesh_(complex.mesh()) {}

  // Corner for registry vertex v in tet copy `copy`.
  void add_vertex(VertexId v, Index copy, Polygon* polygon) const {
    const registry::IntersectionRegistry& reg = complex_.registry();
    const Index node = reg.vertex(v).node;
    if (node >= 0) {
      add_node(node, copy, polygon);
      return;
    }
    // Weight k vanishes exactly where the point lies on the face opposite node k. Faces of refined
    // tets have registry planes (cached exact forms); others are built here.
    const Index tet = copies_.copy_tet()[copy];
    const Points& rest = mesh_.rest();
    const Tets& tets = mesh_.tets();
    std::uint8_t mask = 0;
    for (int k = 0; k < 4; ++k) {
      const PlaneId plane = complex_.face_plane_id(mesh_.adjacency().tet_faces(tet, k));
      int side;
      if (plane >= 0) {
        side = reg.side(v, plane);
      } else {
        const auto& f = kTetFaces[k];
        side = reg.side(v, geometry::Plane::through(rest.row(tets(tet, f[0])).transpose(),
                                                    rest.row(tets(tet, f[1])).transpose(),
                                                    rest.row(tets(tet, f[2])).transpose()));
      }
      if (side == 0) mask = static_cast<std::uint8_t>(mask | (1u << k));
    }
    VertexKey key{mesh_.num_nodes() + static_cast<std::int64_t>(v), {-1, -1, -1, -1}};
    for (int k = 0; k < 4; ++k) key.nodes[k] = (mask >> k) & 1u ? -1 : copies_.copy_nodes()[copy][k];
    std::sort(key.nodes.begin(), key.nodes.end());
    polygon->keys.push_back(key);
    polygon->points.push_back(key.point);
    polygon->zero_mask.push_back(mask);
  }

  // Corner for mesh node `node` in tet copy `copy`.
  void add_node(Index node, Index copy, Polygon* polygon) const {
    const Index tet = copies_.copy_tet()[copy];
    std::uint8_t mask = 0;
    int local = 0;
    for (int k = 0; k < 4; ++k) {
      if (mesh_.tets()(tet, k) == node) {
        local = k;
      } else {
        mask = static_cast<std::uint8_t>(mask | (1u << k));
      }
    }
    polygon->keys.push_back(VertexKey{node, {-1, -1, -1, copies_.copy_nodes()[copy][local]}});
    polygon->points.push_back(node);
    polygon->zero_mask.push_back(mask);
  }

 private:
  const CellComplex& complex_;
  const connectivity::TetCopies& copies_;
  const TetMesh& mesh_;
};

// Barycentric weights of p in the rest tet, with the weights known to vanish set to exactly zero.
Eigen::Vector4d barycentric(const TetMesh& mesh, Index tet, const Vec3& p, std::uint8_t zero_mask) {
  const Points& rest = mesh.rest();
  const Tets& tets = mesh.tets();
  const Vec3 r0 = rest.row(tets(tet, 0)).transpose();
  Eigen::Matrix3d edges;
  for (int k = 0; k < 3; ++k) edges.col(k) = rest.row(tets(tet, k + 1)).transpose() - r0;
  const Vec3 w = edges.partialPivLu().solve(p - r0);
  Eigen::Vector4d weights(1 - w.sum(), w[0], w[1], w[2]);
  for (int k = 0; k < 4; ++k) {
    if ((zero_mask >> k) & 1u) weights[k] = 0;
  }
  return weights / weights.sum();
}

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

MaterialSurface extract_material_surface(const CellComplex& complex, const connectivity::TetCopies& copies) {
  const TetMesh& mesh = complex.mesh();
  const TetAdjacency& adj = mesh.adjacency();
  const registry::IntersectionRegistry& reg = complex.registry();
  reg.update_positions();
  const Keys keys(complex, copies);
  const auto copy_on = [&](Side s) { return copies.copy_on(complex, s); };

  // 1. Polygons, in parallel. Slot 2f (back side) and 2f + 1 (front side) of facet f, then two
  //    per mesh face for the whole faces of unrefined tets. A first pass says which slots hold a
  //    polygon; only those are allocated, in slot order, so the result does not depend on
  //    scheduling.
  const auto& facets = complex.facets();
  const std::size_t num_facets = facets.size();
  const Index num_faces = adj.num_faces();
  const Tets& tets = mesh.tets();
  const auto facet_side_has_polygon = [&](std::size_t f, bool front) {
    const Facet& facet = facets[f];
    const Side side = front ? facet.front : facet.back;
    const Side other = front ? facet.back : facet.front;
    return complex.side_is_material(side) && (facet.covered() || !complex.side_is_material(other));
  };
  const auto face_side_has_polygon = [&](Index face, std::size_t i) {
    if (complex.first_facet_on_face(face) >= 0) return false;
    const auto around = adj.tets_of_face(face);
    if (i >= around.size() || !complex.tet_material(around[i])) return false;
    bool exposed = around.size() == 1;
    for (const Index other : around) exposed = exposed || (other != around[i] && !complex.tet_material(other));
    return exposed;
  };
  const std::size_t num_slots = 2 * num_facets + 2 * static_cast<std::size_t>(num_faces);
  std::vector<std::int64_t> slot_index(num_slots + 1, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, num_slots, 1024), [&](const auto& range) {
    for (std::size_t slot = range.begin(); slot != range.end(); ++slot) {
      const bool has = slot < 2 * num_facets
                           ? facet_side_has_polygon(slot / 2, slot % 2 == 1)
                           : face_side_has_polygon(static_cast<Index>((slot - 2 * num_facets) / 2), slot % 2);
      slot_index[slot + 1] = has ? 1 : 0;
    }
  });
  for (std::size_t slot = 0; slot < num_slots; ++slot) slot_index[slot + 1] += slot_index[slot];
  std::vector<Polygon> polygons(static_cast<std::size_t>(slot_index[num_slots]));
  const auto polygon_at = [&](std::size_t slot) -> Polygon* {
    return slot_index[slot + 1] > slot_index[slot] ? &polygons[static_cast<std::size_t>(slot_index[slot])] : nullptr;
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, num_facets, 256), [&](const auto& range) {
    for (std::size_t f = range.begin(); f != range.end(); ++f) {
      const Facet& facet = facets[f];
      for (const bool front : {false, true}) {
        Polygon* polygon = polygon_at(2 * f + (front ? 1 : 0));
        if (polygon == nullptr) continue;
        polygon->copy = copy_on(front ? facet.front : facet.back);
        polygon->source = facet.covered() ? complex.cut_id(facet)
                          : facet.mesh_face >= 0 ? face_source(facet.mesh_face)
                                                 : std::numeric_limits<std::int64_t>::min();
        // Stored order is outward for the cell behind the facet.
        triangulate_facet(complex, facet, front, &polygon->triangles);
        for (const Corner& corner : facet.corners) keys.add_vertex(corner.vertex, polygon->copy, polygon);
      }
    }
  });
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_faces, 256), [&](const auto& range) {
    std::vector<VertexId> points;
    for (Index face = range.begin(); face != range.end(); ++face) {
      for (std::size_t i = 0; i < 2; ++i) {
        Polygon* polygon = polygon_at(2 * num_facets + 2 * static_cast<std::size_t>(face) + i);
        if (polygon == nullptr) continue;
        // The face's polygon: its nodes in outward order, and the points refined tets around its
        // edges have put on them.
        const Index tet = adj.tets_of_face(face)[i];
        int local = 0;
        while (adj.tet_faces(tet, local) != face) ++local;
        polygon->copy = copies.copy_of(tet, 0);
        polygon->source = face_source(face);
        std::vector<std::uint8_t> strict;
        for (int k = 0; k < 3; ++k) {
          const Index from = tets(tet, kTetFaces[local][k]), to = tets(tet, kTetFaces[local][(k + 1) % 3]);
          keys.add_node(from, polygon->copy, polygon);
          strict.push_back(1);
          Index mesh_edge = -1;
          for (int e = 0; e < 6; ++e) {
            const Index a = tets(tet, kTetEdges[e][0]), b = tets(tet, kTetEdges[e][1]);
            if ((a == from && b == to) || (a == to && b == from)) mesh_edge = adj.tet_edges(tet, e);
          }
          points.clear();
          complex.mesh_edge_points(mesh_edge, from, to, &points);
          for (const VertexId v : points) {
            keys.add_vertex(v, polygon->copy, polygon);
            strict.push_back(0);
          }
        }
        triangulate_convex_polygon(std::move(strict), false, &polygon->triangles);
      }
    }
  });

  // 2. Vertex ids in polygon order (sequential, so ids are deterministic).
  std::unordered_map<VertexKey, Index, VertexKeyHash> id_of;
  struct NewVertex {
    std::int64_t point;
    Index copy;
    std::uint8_t zero_mask;
  };
  std::vector<NewVertex> vertices;
  MaterialSurface result;
  std::vector<std::array<Index, 3>> triangles;
  std::vector<Index> ids;
  for (const Polygon& polygon : polygons) {
    ids.clear();
    for (std::size_t c = 0; c < polygon.keys.size(); ++c) {
      const auto [it, inserted] = id_of.try_emplace(polygon.keys[c], static_cast<Index>(vertices.size()));
      if (inserted) vertices.push_back({polygon.points[c], polygon.copy, polygon.zero_mask[c]});
      ids.push_back(it->second);
    }
    for (const auto& t : polygon.triangles) {
      triangles.push_back({ids[t[0]], ids[t[1]], ids[t[2]]});
      result.triangle_source.push_back(polygon.source);
      result.triangle_tet.push_back(polygon.copy);
    }
  }

  polygons = {};

  // 3. Positions and embedding weights, in parallel.
  const Index n = static_cast<Index>(vertices.size());
  result.surface.vertices.resize(n, 3);
  result.vertex_weights.resize(n, 4);
  result.vertex_tet.resize(static_cast<std::size_t>(n));
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, 1024), [&](const auto& range) {
    for (Index v = range.begin(); v != range.end(); ++v) {
      const NewVertex& vertex = vertices[v];
      const Vec3 p = vertex.point < mesh.num_nodes()
                         ? Vec3(mesh.rest().row(static_cast<Index>(vertex.point)).transpose())
                         : reg.position(static_cast<VertexId>(vertex.point - mesh.num_nodes()));
      result.surface.vertices.row(v) = p.transpose();
      result.vertex_weights.row(v) = barycentric(mesh, copies.copy_tet()[vertex.copy], p, vertex.zero_mask).transpose();
      result.vertex_tet[v] = vertex.copy;
    }
  });
  result.surface.triangles.resize(static_cast<Index>(triangles.size()), 3);
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) result.surface.triangles(static_cast<Index>(i), k) = triangles[i][k];
  }
  return result;
}

}  // namespace tetcut::surface
