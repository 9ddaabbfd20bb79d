#include "surface/material_surface.hpp"

#include <Eigen/LU>  // 3x3 inverse
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

#include "util/broken.hpp"

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

// Vertex ids by key, for numbering the surface's corners. Keys are looked up by their point (an
// index below the number of points): a head per point, stamped with the numbering it belongs to
// so that starting a numbering clears nothing, and a chain through the point's vertices (one,
// except where cuts have split the point between copies). O(1) per corner, and the table reads
// only what the corners' points touch; allocates nothing once warm.
class VertexIds {
 public:
  // Starts a numbering of ids 0, 1, ... (each find_or_insert that inserts takes the next), over
  // points 0 .. points - 1.
  void reset(std::size_t points) {
    if (head_.size() < points) {
      head_.resize(points, -1);
      stamp_.resize(points, 0);
    }
    if (++generation_ == 0) {  // wrapped: every stamp may look current
      std::fill(stamp_.begin(), stamp_.end(), 0);
      generation_ = 1;
    }
    next_.clear();
    nodes_.clear();
  }
  // The id of `key`; a new one (and *inserted set) when it is new.
  Index find_or_insert(const VertexKey& key, bool* inserted) {
    const auto p = static_cast<std::size_t>(key.point);
    if (stamp_[p] != generation_) {
      stamp_[p] = generation_;
      head_[p] = -1;
    }
    for (Index v = head_[p]; v >= 0; v = next_[static_cast<std::size_t>(v)]) {
      if (nodes_[static_cast<std::size_t>(v)] == key.nodes) {
        *inserted = false;
        return v;
      }
    }
    const auto id = static_cast<Index>(next_.size());
    next_.push_back(head_[p]);
    nodes_.push_back(key.nodes);
    head_[p] = id;
    *inserted = true;
    return id;
  }

 private:
  std::vector<Index> head_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t generation_ = 0;
  std::vector<Index> next_;                  // per id: the point's previous vertex
  std::vector<std::array<Index, 4>> nodes_;  // per id: its key's nodes
};

// A polygon corner before it gets a vertex id: its key, the copy whose material the polygon
// bounds (the vertex is embedded there when this corner is its first use), which of that copy's
// barycentric weights vanish exactly there (bit k: weight k), and the weights, computed when its
// patch is built (so that assembling the surface after a cut only copies them).
struct PatchCorner {
  VertexKey key;
  Index copy;
  std::uint8_t zero_mask;
  std::array<double, 4> weights{};
};

// Computes keys of polygon corners; safe to run concurrently (side tests are, outside insertion).
class Keys {
 public:
  Keys(const CellComplex& complex, const connectivity::TetCopies& copies)
      : complex_(complex), copies_(copies), mesh_(complex.mesh()) {}

  // Corner for registry vertex v in tet copy `copy`.
  void add_vertex(VertexId v, Index copy, std::vector<PatchCorner>* corners) const {
    const registry::IntersectionRegistry& reg = complex_.registry();
    const Index node = reg.vertex(v).node;
    if (node >= 0) {
      add_node(node, copy, corners);
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
    corners->push_back({key, copy, mask});
  }

  // Corner for mesh node `node` in tet copy `copy`.
  void add_node(Index node, Index copy, std::vector<PatchCorner>* corners) const {
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
    corners->push_back({VertexKey{node, {-1, -1, -1, copies_.copy_nodes()[copy][local]}}, copy, mask});
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
  const Vec3 w = edges.inverse() * (p - r0);  // closed form: the rest tet is well shaped
  Eigen::Vector4d weights(1 - w.sum(), w[0], w[1], w[2]);
  for (int k = 0; k < 4; ++k) {
    if ((zero_mask >> k) & 1u) weights[k] = 0;
  }
  return weights / weights.sum();
}

// The rest position of a surface point (mesh node n as n, intersection v as num_nodes + v).
Vec3 point_position(const TetMesh& mesh, const registry::IntersectionRegistry& reg, std::int64_t point) {
  return point < mesh.num_nodes() ? Vec3(mesh.rest().row(static_cast<Index>(point)).transpose())
                                  : reg.position(static_cast<VertexId>(point - mesh.num_nodes()));
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
    if (ear < 0) broken("surface", "a polygon has no clippable corner");
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

// A surface triangle of a patch: its corners (indices into the patch's corners), the copy whose
// material it bounds, and its source (see MaterialSurface::triangle_source).
struct PatchTriangle {
  std::array<std::int32_t, 3> corners;
  Index copy;
  std::int64_t source;
};

// The polygons bounding the material of one input tet's copies, as built.
struct Patch {
  std::vector<PatchCorner> corners;
  std::vector<PatchTriangle> triangles;
};

// Where a tet's patch lies in the arenas.
struct PatchRange {
  std::size_t corner_begin = 0, triangle_begin = 0;
  std::uint32_t corners = 0, triangles = 0;
};

struct SurfacePatches::State {
  explicit State(const TetMesh& m)
      : mesh(m), ranges(static_cast<std::size_t>(m.num_tets())), marked(static_cast<std::size_t>(m.num_tets()), 1) {
    out_of_date.resize(static_cast<std::size_t>(m.num_tets()));
    for (Index t = 0; t < m.num_tets(); ++t) out_of_date[t] = t;
  }

  void mark(Index tet) {
    if (marked[tet]) return;
    marked[tet] = 1;
    out_of_date.push_back(tet);
  }

  // Tets around each node (CSR), built on first use: only progressive updates need it.
  void build_node_tets() {
    if (!node_tets_begin.empty()) return;
    const Tets& tets = mesh.tets();
    node_tets_begin.assign(static_cast<std::size_t>(mesh.num_nodes()) + 1, 0);
    for (Index t = 0; t < mesh.num_tets(); ++t) {
      for (int k = 0; k < 4; ++k) ++node_tets_begin[tets(t, k) + 1];
    }
    for (Index n = 0; n < mesh.num_nodes(); ++n) node_tets_begin[n + 1] += node_tets_begin[n];
    node_tets.resize(static_cast<std::size_t>(node_tets_begin.back()));
    std::vector<Index> fill(node_tets_begin.begin(), node_tets_begin.end() - 1);
    for (Index t = 0; t < mesh.num_tets(); ++t) {
      for (int k = 0; k < 4; ++k) node_tets[fill[tets(t, k)]++] = t;
    }
  }

  const TetMesh& mesh;
  // Patches live in two arenas, so that numbering reads them nearly in order: a rebuilt patch is
  // appended and its old place becomes garbage; when garbage outgrows the live part, the arenas
  // are rewritten in tet order. Amortised O(size of the rebuilt patches).
  std::vector<PatchRange> ranges;  // per input tet
  std::vector<PatchCorner> corner_arena;
  std::vector<PatchTriangle> triangle_arena;
  std::size_t live_corners = 0, live_triangles = 0;
  std::vector<Index> non_empty;  // tets with a non-empty patch, ascending
  std::vector<Patch> built;      // patches being rebuilt, kept to reuse their memory
  std::vector<std::uint8_t> marked;              // per tet: out of date
  std::vector<Index> out_of_date;
  std::vector<Index> node_tets_begin, node_tets;
  VertexIds ids;  // kept to reuse its table
};

SurfacePatches::SurfacePatches(const TetMesh& mesh) : state_(std::make_unique<State>(mesh)) {}
SurfacePatches::~SurfacePatches() = default;
SurfacePatches::SurfacePatches(SurfacePatches&&) noexcept = default;
SurfacePatches& SurfacePatches::operator=(SurfacePatches&&) noexcept = default;

void SurfacePatches::mark(std::span<const Index> tets) {
  for (const Index t : tets) state_->mark(t);
}

void SurfacePatches::mark_around(std::span<const Index> tets) {
  State& s = *state_;
  s.build_node_tets();
  const Tets& mesh_tets = s.mesh.tets();
  for (const Index t : tets) {
    s.mark(t);
    for (int k = 0; k < 4; ++k) {
      const Index node = mesh_tets(t, k);
      for (Index i = s.node_tets_begin[node]; i < s.node_tets_begin[node + 1]; ++i) {
        const Index other = s.node_tets[i];
        if (s.marked[other]) continue;
        int shared = 0;
        for (int a = 0; a < 4; ++a) {
          for (int b = 0; b < 4; ++b) shared += mesh_tets(t, a) == mesh_tets(other, b);
        }
        if (shared >= 2) s.mark(other);
      }
    }
  }
}

namespace {

// Builds the patch of one tet: for a refined tet, the material sides of its cells' facets; for an
// unrefined one, its faces (whole, or as the facets refined neighbours put on them).
void build_patch(const CellComplex& complex, const connectivity::TetCopies& copies, const Keys& keys, Index tet,
                 Patch* patch) {
  const TetAdjacency& adj = complex.mesh().adjacency();
  const Tets& tets = complex.mesh().tets();
  const auto& facets = complex.facets();
  const auto add_triangles = [&](const std::vector<std::array<int, 3>>& triangles, std::size_t base, Index copy,
                                 std::int64_t source) {
    for (const auto& t : triangles) {
      patch->triangles.push_back({{static_cast<std::int32_t>(base + static_cast<std::size_t>(t[0])),
                                   static_cast<std::int32_t>(base + static_cast<std::size_t>(t[1])),
                                   static_cast<std::int32_t>(base + static_cast<std::size_t>(t[2]))},
                                  copy,
                                  source});
    }
  };
  std::vector<std::array<int, 3>> triangles;
  // The side of facet f facing `side` (front when `front`): a polygon when that side holds
  // material and the facet is covered or has no material on its other side.
  const auto emit_facet_side = [&](cells::FacetId f, bool front) {
    const Facet& facet = facets[f];
    const Side side = front ? facet.front : facet.back;
    const Side other = front ? facet.back : facet.front;
    if (!complex.side_is_material(side) || (!facet.covered() && complex.side_is_material(other))) return;
    const Index copy = copies.copy_on(complex, side);
    const std::int64_t source = facet.covered() ? complex.cut_id(facet)
                                : facet.mesh_face >= 0 ? face_source(facet.mesh_face)
                                                       : std::numeric_limits<std::int64_t>::min();
    triangles.clear();
    // Stored order is outward for the cell behind the facet.
    triangulate_facet(complex, facet, front, &triangles);
    const std::size_t base = patch->corners.size();
    for (const Corner& corner : facet.corners) keys.add_vertex(corner.vertex, copy, &patch->corners);
    add_triangles(triangles, base, copy, source);
  };

  if (complex.refined(tet)) {
    for (cells::CellId c = complex.first_cell(tet); c >= 0; c = complex.cells()[c].next_in_tet) {
      for (const cells::FacetId f : complex.cells()[c].facets) emit_facet_side(f, facets[f].front == c);
    }
    return;
  }
  if (!complex.tet_material(tet)) return;
  std::vector<VertexId> points;
  std::vector<std::uint8_t> strict;
  for (int local = 0; local < 4; ++local) {
    const Index face = adj.tet_faces(tet, local);
    if (complex.first_facet_on_face(face) >= 0) {
      // A refined neighbour has split the face: its facets, on this tet's side.
      for (cells::FacetId f = complex.first_facet_on_face(face); f >= 0; f = facets[f].next_on_mesh_face) {
        for (const bool front : {false, true}) {
          if ((front ? facets[f].front : facets[f].back) == cells::unrefined_side(tet)) emit_facet_side(f, front);
        }
      }
      continue;
    }
    // The whole face, when nothing holds material across it.
    const auto around = adj.tets_of_face(face);
    bool exposed = around.size() == 1;
    for (const Index other : around) exposed = exposed || (other != tet && !complex.tet_material(other));
    if (!exposed) continue;
    // Its nodes in outward order, and the points refined tets around its edges have put on them.
    const Index copy = copies.copy_of(tet, 0);
    const std::size_t base = patch->corners.size();
    strict.clear();
    for (int k = 0; k < 3; ++k) {
      const Index from = tets(tet, kTetFaces[local][k]), to = tets(tet, kTetFaces[local][(k + 1) % 3]);
      keys.add_node(from, copy, &patch->corners);
      strict.push_back(1);
      Index mesh_edge = -1;
      for (int e = 0; e < 6; ++e) {
        const Index a = tets(tet, kTetEdges[e][0]), b = tets(tet, kTetEdges[e][1]);
        if ((a == from && b == to) || (a == to && b == from)) mesh_edge = adj.tet_edges(tet, e);
      }
      points.clear();
      complex.mesh_edge_points(mesh_edge, from, to, &points);
      for (const VertexId v : points) {
        keys.add_vertex(v, copy, &patch->corners);
        strict.push_back(0);
      }
    }
    triangles.clear();
    triangulate_convex_polygon(strict, false, &triangles);
    add_triangles(triangles, base, copy, face_source(face));
  }
}

}  // namespace

MaterialSurface SurfacePatches::assemble(const CellComplex& complex, const connectivity::TetCopies& copies) {
  State& s = *state_;
  const TetMesh& mesh = complex.mesh();
  const registry::IntersectionRegistry& reg = complex.registry();
  const Keys keys(complex, copies);

  // 1. Rebuild the out-of-date patches: in parallel, a chunk at a time (bounding the memory of
  //    patches in flight when every tet is out of date), then appended to the arenas in order.
  std::vector<Index>& rebuilt = s.out_of_date;
  std::sort(rebuilt.begin(), rebuilt.end());
  constexpr std::size_t kChunk = 8192;
  std::vector<Patch>& built = s.built;
  if (built.size() < std::min(kChunk, rebuilt.size())) built.resize(std::min(kChunk, rebuilt.size()));
  for (std::size_t first = 0; first < rebuilt.size(); first += kChunk) {
    const std::size_t count = std::min(kChunk, rebuilt.size() - first);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        built[i].corners.clear();
        built[i].triangles.clear();
        build_patch(complex, copies, keys, rebuilt[first + i], &built[i]);
        for (PatchCorner& corner : built[i].corners) {
          const Eigen::Vector4d w = barycentric(mesh, copies.copy_tet()[corner.copy], point_position(mesh, reg, corner.key.point), corner.zero_mask);
          corner.weights = {w[0], w[1], w[2], w[3]};
        }
      }
    });
    for (std::size_t i = 0; i < count; ++i) {
      PatchRange& range = s.ranges[rebuilt[first + i]];
      s.live_corners -= range.corners;
      s.live_triangles -= range.triangles;
      range = PatchRange{s.corner_arena.size(), s.triangle_arena.size(), static_cast<std::uint32_t>(built[i].corners.size()),
                         static_cast<std::uint32_t>(built[i].triangles.size())};
      s.corner_arena.insert(s.corner_arena.end(), built[i].corners.begin(), built[i].corners.end());
      s.triangle_arena.insert(s.triangle_arena.end(), built[i].triangles.begin(), built[i].triangles.end());
      s.live_corners += range.corners;
      s.live_triangles += range.triangles;
    }
  }
  std::vector<Index> non_empty;
  non_empty.reserve(s.non_empty.size() + rebuilt.size());
  const auto keep_if_non_empty = [&](Index tet) {
    if (s.ranges[tet].triangles > 0) non_empty.push_back(tet);
  };
  std::size_t r = 0;
  for (const Index tet : s.non_empty) {
    for (; r < rebuilt.size() && rebuilt[r] < tet; ++r) keep_if_non_empty(rebuilt[r]);
    if (r < rebuilt.size() && rebuilt[r] == tet) ++r;
    keep_if_non_empty(tet);
  }
  for (; r < rebuilt.size(); ++r) keep_if_non_empty(rebuilt[r]);
  s.non_empty = std::move(non_empty);
  for (const Index tet : rebuilt) s.marked[tet] = 0;
  rebuilt.clear();
  if (s.corner_arena.size() > 2 * s.live_corners + 4096) {
    std::vector<PatchCorner> corners;
    std::vector<PatchTriangle> triangles;
    corners.reserve(s.live_corners);
    triangles.reserve(s.live_triangles);
    for (const Index tet : s.non_empty) {
      PatchRange& range = s.ranges[tet];
      const auto c = s.corner_arena.begin() + static_cast<std::ptrdiff_t>(range.corner_begin);
      const auto t = s.triangle_arena.begin() + static_cast<std::ptrdiff_t>(range.triangle_begin);
      range.corner_begin = corners.size();
      range.triangle_begin = triangles.size();
      corners.insert(corners.end(), c, c + range.corners);
      triangles.insert(triangles.end(), t, t + range.triangles);
    }
    s.corner_arena = std::move(corners);
    s.triangle_arena = std::move(triangles);
  }

  // 2. Vertex ids in order of first use over the patches in tet order (sequential, so ids are
  //    deterministic).
  MaterialSurface result;
  result.triangle_source.resize(s.live_triangles);
  result.triangle_tet.resize(s.live_triangles);
  result.surface.triangles.resize(static_cast<Index>(s.live_triangles), 3);
  s.ids.reset(static_cast<std::size_t>(mesh.num_nodes()) + static_cast<std::size_t>(reg.num_vertices()));
  std::vector<const PatchCorner*> vertices;
  std::vector<Index> ids;
  Index row = 0;
  for (const Index tet : s.non_empty) {
    const PatchRange& range = s.ranges[tet];
    const PatchCorner* corners = s.corner_arena.data() + range.corner_begin;
    ids.resize(range.corners);
    for (std::uint32_t c = 0; c < range.corners; ++c) {
      bool inserted;
      ids[c] = s.ids.find_or_insert(corners[c].key, &inserted);
      if (inserted) vertices.push_back(&corners[c]);
    }
    const PatchTriangle* triangles = s.triangle_arena.data() + range.triangle_begin;
    for (std::uint32_t t = 0; t < range.triangles; ++t, ++row) {
      for (int k = 0; k < 3; ++k) result.surface.triangles(row, k) = ids[static_cast<std::size_t>(triangles[t].corners[k])];
      result.triangle_source[static_cast<std::size_t>(row)] = triangles[t].source;
      result.triangle_tet[static_cast<std::size_t>(row)] = triangles[t].copy;
    }
  }

  // 3. Positions and embedding weights (those of each vertex's first corner), in parallel.
  const Index n = static_cast<Index>(vertices.size());
  result.surface.vertices.resize(n, 3);
  result.vertex_weights.resize(n, 4);
  result.vertex_tet.resize(static_cast<std::size_t>(n));
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, 1024), [&](const auto& range) {
    for (Index v = range.begin(); v != range.end(); ++v) {
      const PatchCorner& corner = *vertices[v];
      result.surface.vertices.row(v) = point_position(mesh, reg, corner.key.point).transpose();
      for (int k = 0; k < 4; ++k) result.vertex_weights(v, k) = corner.weights[static_cast<std::size_t>(k)];
      result.vertex_tet[v] = corner.copy;
    }
  });
  return result;
}

MaterialSurface extract_material_surface(const CellComplex& complex, const connectivity::TetCopies& copies) {
  SurfacePatches patches(complex.mesh());
  return patches.assemble(complex, copies);
}

}  // namespace tetcut::surface
