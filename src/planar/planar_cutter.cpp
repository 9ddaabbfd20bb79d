// The planar cutter: triangle arrangements refined by segments, and the copies and nodes of the
// cut mesh kept up to date batch by batch, as connectivity::TetCopies does for tets.
//
// Ids are stable for the same reason as in 3D: a cut only separates material, so each new
// component of a triangle lies in one old copy (its faces carry that copy as their label), and
// each new class of node slots lies in one old class. The first new component in an old copy
// keeps its id and the first class keeps the node's id; the others are appended.

#include <tetcut/error.hpp>
#include <tetcut/planar_cutter.hpp>
#include <tetcut/surface.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <unordered_map>

#include "collision/proximity.hpp"
#include "geometry/predicates.hpp"
#include "mesh/surface_checks.hpp"
#include "planar/triangle_arrangement.hpp"
#include "registry/plane_book.hpp"
#include "spatial/box_tree.hpp"
#include "util/broken.hpp"
#include "util/union_find.hpp"

namespace tetcut {

using planar::PlaneId;
using planar::VertexId;

namespace {
// Both the planar mesh and the cut points live in the registry at z = 0.
Vec3 lift(double x, double y) { return {x, y, 0.0}; }

std::string triangle_name(Index t) { return "triangle " + std::to_string(t); }

// Whether the segment from p to q (distinct) runs at least as far along x as along y; then it
// does not run along y alone. Decided on rounded differences, which are zero exactly when the
// coordinates are equal: a choice of axis, not a topological decision.
bool runs_along_x(const Vec3& p, const Vec3& q) {
  return p.x() != q.x() && (p.y() == q.y() || std::abs(q.x() - p.x()) >= std::abs(q.y() - p.y()));
}

// The line through distinct p and q: the wall through them along z. Only the plane matters, not
// its orientation, so the point "inside" is any point off the line: a step away along the other axis.
PlaneId line_through(registry::IntersectionRegistry& registry, const Vec3& p, const Vec3& q) {
  const Vec3 off = runs_along_x(p, q) ? Vec3(p.x(), p.y() + 1 + 2 * std::abs(p.y()), 0)
                                      : Vec3(p.x() + 1 + 2 * std::abs(p.x()), p.y(), 0);
  return registry.wall(p, q, 2, off).id;
}
}  // namespace

struct PlanarCutter::State {
  explicit State(PlanarMesh mesh_in);

  PlanarMesh input;
  Points rest3;
  planar::PlanarGeometry geometry;
  std::vector<std::array<Index, 2>> edges;                 // mesh edges, smaller node first
  std::vector<std::array<Index, 3>> triangle_edges;        // per triangle, side k: its edge
  std::vector<std::array<std::array<Index, 2>, 2>> edge_sides;  // per edge: (triangle, side) x 2, -1
  std::vector<std::unique_ptr<planar::TriangleArrangement>> arrangements;  // null: one cell
  spatial::BoxTree triangle_tree;
  std::vector<Index> node_triangles_begin, node_triangles;  // CSR

  std::vector<std::array<Index, 3>> copy_nodes;
  std::vector<Index> copy_triangle;
  std::vector<Index> node_parent;
  std::vector<std::vector<Index>> triangle_copies;
  std::vector<double> copy_area;
  std::int64_t next_segment_id = 0;
  // Per mesh edge: the copy pairs joined across it, cached until a triangle on it changes.
  std::vector<std::vector<std::array<Index, 2>>> edge_joins;
  std::vector<std::uint8_t> edge_joins_valid;
  // World planes of cuts placed on the deformed mesh, and their pull-backs per copy.
  registry::PlaneBook planes;

  planar::TriangleArrangement& refine(Index t);
  // Inserts a segment into triangle t's cells; marks t when its material changed.
  void insert(Index t, const planar::PreparedSegment& segment, std::vector<std::uint8_t>* touched);
  // Components, copies and nodes of the marked triangles; fills the rest of the report.
  void finish_batch(const std::vector<std::uint8_t>& touched, PlanarCutReport* report);
  planar::PreparedSegment prepare(const Vec3& p, const Vec3& q, std::int64_t id);
  const std::vector<std::array<Index, 2>>& joins(Index edge);
  planar::SideIntervals side(Index t, int k) const;
  int compare_on_edge(Index edge, VertexId x, VertexId y) const;
  void update_copies(Index t, PlanarCutReport* report);
  void recollapse(Index node, PlanarCutReport* report);
};

PlanarCutter::State::State(PlanarMesh mesh_in) : input(std::move(mesh_in)), geometry(rest3) {
  const Index n = input.num_nodes(), m = input.num_triangles();
  for (Index v = 0; v < n; ++v) {
    if (!std::isfinite(input.rest(v, 0)) || !std::isfinite(input.rest(v, 1))) {
      throw Error(ErrorKind::kInvalidInput, "node " + std::to_string(v) + " has a non-finite coordinate");
    }
  }
  rest3.resize(n, 3);
  for (Index v = 0; v < n; ++v) rest3.row(v) = lift(input.rest(v, 0), input.rest(v, 1)).transpose();
  std::map<std::array<Index, 2>, Index> edge_id;
  triangle_edges.resize(m);
  for (Index t = 0; t < m; ++t) {
    for (int k = 0; k < 3; ++k) {
      const Index v = input.triangles(t, k);
      if (v < 0 || v >= n) {
        throw Error(ErrorKind::kInvalidInput, triangle_name(t) + " names node " + std::to_string(v) + ", but there are " +
                                                  std::to_string(n) + " nodes");
      }
    }
    const Index a = input.triangles(t, 0), b = input.triangles(t, 1), c = input.triangles(t, 2);
    const double pa[2] = {input.rest(a, 0), input.rest(a, 1)}, pb[2] = {input.rest(b, 0), input.rest(b, 1)},
                 pc[2] = {input.rest(c, 0), input.rest(c, 1)};
    const int orientation = geometry::orient2d(pa, pb, pc);
    if (orientation <= 0) {
      throw Error(ErrorKind::kInvalidInput, triangle_name(t) + (orientation == 0 ? " has zero area (its corners are collinear)"
                                                                               : " is clockwise; the planar cutter takes "
                                                                                 "counter-clockwise triangles"));
    }
    for (int k = 0; k < 3; ++k) {
      const Index u = input.triangles(t, k), v = input.triangles(t, (k + 1) % 3);
      const std::array<Index, 2> key = {std::min(u, v), std::max(u, v)};
      const auto [it, inserted] = edge_id.try_emplace(key, static_cast<Index>(edges.size()));
      if (inserted) {
        edges.push_back(key);
        edge_sides.push_back({{{-1, -1}, {-1, -1}}});
      }
      auto& sides = edge_sides[it->second];
      const int slot = sides[0][0] < 0 ? 0 : sides[1][0] < 0 ? 1 : 2;
      if (slot == 2) {
        throw Error(ErrorKind::kInvalidInput, "the edge between nodes " + std::to_string(key[0]) + " and " +
                                                  std::to_string(key[1]) + " has more than two triangles (" +
                                                  triangle_name(t) + " is the third)");
      }
      if (slot == 1 && input.triangles(sides[0][0], sides[0][1]) == u) {
        throw Error(ErrorKind::kInvalidInput, triangle_name(t) + " runs along the edge between nodes " +
                                                  std::to_string(key[0]) + " and " + std::to_string(key[1]) +
                                                  " in the same direction as " + triangle_name(sides[0][0]) +
                                                  ": the two overlap");
      }
      sides[slot] = {t, k};
      triangle_edges[t][k] = it->second;
    }
  }

  // The rest plane and the lines of the edges, then the nodes as points on two of their lines.
  auto& registry = geometry.registry;
  geometry.rest_plane = registry.triangle_plane(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)).id;
  geometry.edge_line.resize(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    geometry.edge_line[e] = line_through(registry, rest3.row(edges[e][0]).transpose(), rest3.row(edges[e][1]).transpose());
  }
  geometry.edge_points.resize(edges.size());
  geometry.node_vertex.assign(n, -1);
  for (Index t = 0; t < m; ++t) {
    for (int k = 0; k < 3; ++k) {
      const Index v = input.triangles(t, k);
      if (geometry.node_vertex[v] >= 0) continue;
      geometry.node_vertex[v] = registry.add_node(v, geometry.edge_line[triangle_edges[t][k]],
                                                  geometry.edge_line[triangle_edges[t][(k + 2) % 3]], geometry.rest_plane);
    }
  }
  geometry.vertex_edge.assign(registry.num_vertices(), -1);

  arrangements.resize(m);
  std::vector<spatial::Aabb> boxes(m);
  for (Index t = 0; t < m; ++t) {
    for (int k = 0; k < 3; ++k) boxes[t].extend(rest3.row(input.triangles(t, k)).transpose());
  }
  triangle_tree = spatial::BoxTree(std::move(boxes));

  node_triangles_begin.assign(n + 1, 0);
  for (Index t = 0; t < m; ++t) {
    for (int k = 0; k < 3; ++k) ++node_triangles_begin[input.triangles(t, k) + 1];
  }
  std::partial_sum(node_triangles_begin.begin(), node_triangles_begin.end(), node_triangles_begin.begin());
  node_triangles.resize(3 * static_cast<std::size_t>(m));
  std::vector<Index> fill(node_triangles_begin.begin(), node_triangles_begin.end() - 1);
  for (Index t = 0; t < m; ++t) {
    for (int k = 0; k < 3; ++k) node_triangles[fill[input.triangles(t, k)]++] = t;
  }

  copy_nodes.resize(m);
  copy_triangle.resize(m);
  triangle_copies.resize(m);
  copy_area.resize(m);
  for (Index t = 0; t < m; ++t) {
    copy_nodes[t] = {input.triangles(t, 0), input.triangles(t, 1), input.triangles(t, 2)};
    copy_triangle[t] = t;
    triangle_copies[t] = {t};
    const Vec3 a = rest3.row(copy_nodes[t][0]).transpose(), b = rest3.row(copy_nodes[t][1]).transpose(),
               c = rest3.row(copy_nodes[t][2]).transpose();
    copy_area[t] = 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
  }
  node_parent.resize(n);
  std::iota(node_parent.begin(), node_parent.end(), Index{0});
  edge_joins.resize(edges.size());
  edge_joins_valid.assign(edges.size(), 0);
}

planar::TriangleArrangement& PlanarCutter::State::refine(Index t) {
  if (!arrangements[t]) {
    std::array<VertexId, 3> corners{};
    std::array<PlaneId, 3> lines{};
    for (int k = 0; k < 3; ++k) {
      corners[k] = geometry.node_vertex[input.triangles(t, k)];
      lines[k] = geometry.edge_line[triangle_edges[t][k]];
    }
    arrangements[t] = std::make_unique<planar::TriangleArrangement>(corners, lines, triangle_edges[t], triangle_copies[t][0]);
  }
  return *arrangements[t];
}

planar::PreparedSegment PlanarCutter::State::prepare(const Vec3& p, const Vec3& q, std::int64_t id) {
  auto& registry = geometry.registry;
  planar::PreparedSegment s;
  s.id = id;
  s.line = line_through(registry, p, q);
  // End walls: through the endpoint and the endpoint lifted to z = 1 (exact), along the axis the
  // segment runs least along, so never parallel to it; the other end is on the positive side.
  const int axis = runs_along_x(p, q) ? 1 : 0;
  s.walls[0] = registry.wall(p, Vec3(p.x(), p.y(), 1), axis, q);
  s.walls[1] = registry.wall(q, Vec3(q.x(), q.y(), 1), axis, p);
  return s;
}

planar::SideIntervals PlanarCutter::State::side(Index t, int k) const {
  if (arrangements[t]) return arrangements[t]->side_intervals(k);
  planar::SideIntervals whole;
  whole.points = {geometry.node_vertex[input.triangles(t, k)], geometry.node_vertex[input.triangles(t, (k + 1) % 3)]};
  whole.labels = {triangle_copies[t][0]};
  whole.covered = {0};
  return whole;
}

// Order of two vertices on mesh edge `edge`, from its first node: -1 when x comes first, 0 when
// they are one vertex. Vertices on an edge are never duplicated (PlanarGeometry::edge_point), so
// two ids are two points. Decided by a line through y that separates the edge's nodes: x is on
// the first node's side of it exactly when x comes first.
int PlanarCutter::State::compare_on_edge(Index edge, VertexId x, VertexId y) const {
  if (x == y) return 0;
  const VertexId first = geometry.node_vertex[edges[edge][0]], last = geometry.node_vertex[edges[edge][1]];
  if (x == first || y == last) return -1;
  if (y == first || x == last) return 1;
  const auto& registry = geometry.registry;
  const Vec3 a = rest3.row(edges[edge][0]).transpose();
  for (const PlaneId line : registry.vertex(y).planes) {
    if (line == geometry.rest_plane || line == geometry.edge_line[edge]) continue;
    const int at_first = registry.side_of_input(line, a);
    if (at_first == 0) continue;  // the line runs along the edge; y's other line crosses it
    return registry.side(x, line) == at_first ? -1 : 1;
  }
  broken("planar", "a point on a mesh edge has no line crossing it");
}

const std::vector<std::array<Index, 2>>& PlanarCutter::State::joins(Index edge) {
  auto& out = edge_joins[edge];
  if (edge_joins_valid[edge]) return out;
  edge_joins_valid[edge] = 1;
  out.clear();
  const auto& sides = edge_sides[edge];
  if (sides[1][0] < 0) return out;
  // Both sides' intervals from the edge's first node to its last.
  std::array<planar::SideIntervals, 2> lists;
  for (int s = 0; s < 2; ++s) {
    lists[s] = side(sides[s][0], sides[s][1]);
    if (input.triangles(sides[s][0], sides[s][1]) != edges[edge][0]) {
      std::reverse(lists[s].points.begin(), lists[s].points.end());
      std::reverse(lists[s].labels.begin(), lists[s].labels.end());
      std::reverse(lists[s].covered.begin(), lists[s].covered.end());
    }
  }
  // Merge: each elementary stretch lies in one interval of each side; material passes where
  // neither side covers it.
  std::size_t i = 0, j = 0;
  const std::size_t ni = lists[0].labels.size(), nj = lists[1].labels.size();
  while (i < ni && j < nj) {
    if (!lists[0].covered[i] && !lists[1].covered[j]) {
      const std::array<Index, 2> pair = {lists[0].labels[i], lists[1].labels[j]};
      if (std::find(out.begin(), out.end(), pair) == out.end()) out.push_back(pair);
    }
    const int order = compare_on_edge(edge, lists[0].points[i + 1], lists[1].points[j + 1]);
    if (order <= 0) ++i;
    if (order >= 0) ++j;
  }
  return out;
}

void PlanarCutter::State::update_copies(Index t, PlanarCutReport* report) {
  planar::TriangleArrangement& arrangement = *arrangements[t];
  std::vector<int> face_component;
  const int count = arrangement.components(&face_component);
  auto& faces = arrangement.mutable_faces();
  // Each component's old copy, and its area.
  std::vector<Index> component_label(count, -1);
  std::vector<double> component_area(count, 0);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const int c = face_component[f];
    if (component_label[c] >= 0 && component_label[c] != faces[f].label) {
      broken("planar", "a component spans two old copies");
    }
    component_label[c] = faces[f].label;
    component_area[c] += arrangement.face_area(geometry.registry, static_cast<int>(f));
  }
  // The first component in each old copy keeps it; the others become new copies.
  std::vector<Index> component_copy(count, -1);
  std::vector<Index> kept;  // old copies already given to a component (a triangle has few)
  std::vector<Index> copies;
  for (int c = 0; c < count; ++c) {
    const Index old = component_label[c];
    Index copy = old;
    if (std::find(kept.begin(), kept.end(), old) != kept.end()) {
      copy = static_cast<Index>(copy_nodes.size());
      copy_nodes.push_back(copy_nodes[old]);
      copy_triangle.push_back(t);
      copy_area.push_back(0);
      report->new_triangle_source.push_back(old);
    }
    kept.push_back(old);
    component_copy[c] = copy;
    copy_area[copy] = component_area[c];
    copies.push_back(copy);
  }
  for (std::size_t f = 0; f < faces.size(); ++f) faces[f].label = component_copy[face_component[f]];
  triangle_copies[t] = std::move(copies);
}

void PlanarCutter::State::recollapse(Index node, PlanarCutReport* report) {
  // Slots: (copy, corner) of every copy around the node; joined across the node's edges.
  struct Slot {
    Index copy;
    int corner;
  };
  std::vector<Slot> slots;
  std::unordered_map<Index, Index> copy_slot;
  for (Index i = node_triangles_begin[node]; i < node_triangles_begin[node + 1]; ++i) {
    const Index t = node_triangles[i];
    int corner = 0;
    while (input.triangles(t, corner) != node) ++corner;
    for (const Index copy : triangle_copies[t]) {
      copy_slot[copy] = static_cast<Index>(slots.size());
      slots.push_back({copy, corner});
    }
  }
  UnionFind sets(slots.size());
  for (Index i = node_triangles_begin[node]; i < node_triangles_begin[node + 1]; ++i) {
    const Index t = node_triangles[i];
    for (int k = 0; k < 3; ++k) {
      const Index e = triangle_edges[t][k];
      if (edges[e][0] != node && edges[e][1] != node) continue;
      for (const auto& [a, b] : joins(e)) sets.join(copy_slot.at(a), copy_slot.at(b));
    }
  }
  // Classes in order of their first slot; the first class with an old node keeps it.
  std::unordered_map<Index, Index> class_node;
  std::unordered_map<Index, std::uint8_t> old_taken;
  for (std::size_t s = 0; s < slots.size(); ++s) {
    const Index root = sets.find(static_cast<Index>(s));
    const auto [it, inserted] = class_node.try_emplace(root, -1);
    if (inserted) {
      const Index old = copy_nodes[slots[root].copy][slots[root].corner];
      if (!old_taken[old]) {
        old_taken[old] = 1;
        it->second = old;
      } else {
        it->second = static_cast<Index>(node_parent.size());
        node_parent.push_back(node_parent[old]);
        report->new_node_source.push_back(old);
      }
    }
    Index& slot_node = copy_nodes[slots[s].copy][slots[s].corner];
    if (slot_node != it->second) {
      slot_node = it->second;
      if (slots[s].copy < report->first_new_triangle) report->changed_triangles.push_back(slots[s].copy);
    }
  }
}

PlanarCutter::PlanarCutter(PlanarMesh mesh) : state_(std::make_unique<State>(std::move(mesh))) {}
PlanarCutter::~PlanarCutter() = default;
PlanarCutter::PlanarCutter(PlanarCutter&&) noexcept = default;
PlanarCutter& PlanarCutter::operator=(PlanarCutter&&) noexcept = default;

void PlanarCutter::State::insert(Index t, const planar::PreparedSegment& segment, std::vector<std::uint8_t>* touched) {
  const bool was_refined = arrangements[t] != nullptr;
  if (refine(t).insert(geometry, segment)) {
    (*touched)[t] = 1;
  } else if (!was_refined) {
    arrangements[t].reset();  // the segment missed it: keep it one implicit cell
  }
}

void PlanarCutter::State::finish_batch(const std::vector<std::uint8_t>& touched, PlanarCutReport* report) {
  for (std::size_t t = 0; t < touched.size(); ++t) {
    if (touched[t]) report->touched.push_back(static_cast<Index>(t));
  }
  for (const Index t : report->touched) {
    update_copies(t, report);
    for (int k = 0; k < 3; ++k) edge_joins_valid[triangle_edges[t][k]] = 0;
  }
  std::vector<Index> nodes;
  for (const Index t : report->touched) {
    for (int k = 0; k < 3; ++k) nodes.push_back(input.triangles(t, k));
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  for (const Index n : nodes) recollapse(n, report);
  std::sort(report->changed_triangles.begin(), report->changed_triangles.end());
  report->changed_triangles.erase(std::unique(report->changed_triangles.begin(), report->changed_triangles.end()),
                                  report->changed_triangles.end());
}

PlanarCutReport PlanarCutter::cut(std::span<const Polyline> batch) {
  State& s = *state_;
  // Check everything first, so that a bad batch changes nothing.
  for (std::size_t l = 0; l < batch.size(); ++l) {
    for (Index i = 0; i < batch[l].points.rows(); ++i) {
      if (!std::isfinite(batch[l].points(i, 0)) || !std::isfinite(batch[l].points(i, 1))) {
        throw Error(ErrorKind::kInvalidInput, "polyline " + std::to_string(l) + ", point " + std::to_string(i) +
                                                  " has a non-finite coordinate");
      }
    }
  }
  PlanarCutReport report;
  report.first_new_node = num_nodes();
  report.first_new_triangle = num_triangles();
  std::vector<std::uint8_t> touched(s.arrangements.size(), 0);
  std::vector<Index> candidates;
  for (const Polyline& line : batch) {
    for (Index i = 0; i < line.num_segments(); ++i) {
      const Index j = (i + 1) % static_cast<Index>(line.points.rows());
      const Vec3 p = lift(line.points(i, 0), line.points(i, 1)), q = lift(line.points(j, 0), line.points(j, 1));
      const Index in_batch = report.segments++;
      const std::int64_t id = s.next_segment_id++;
      if (p == q) {
        report.degenerate.push_back(in_batch);
        continue;
      }
      const planar::PreparedSegment segment = s.prepare(p, q, id);
      spatial::Aabb box;
      box.extend(p);
      box.extend(q);
      candidates.clear();
      s.triangle_tree.query(box, &candidates);
      for (const Index t : candidates) s.insert(t, segment, &touched);
    }
  }
  s.finish_batch(touched, &report);
  return report;
}

namespace {
// Signs of a plane at three points: how many are positive, zero, negative.
struct SignCount {
  int positive = 0, zero = 0, negative = 0;
};
SignCount signs_at(const geometry::Plane& plane, int sign, const std::array<Vec3, 3>& points) {
  SignCount c;
  for (const Vec3& x : points) {
    const int s = sign * geometry::side_of_point(plane, x);
    (s > 0 ? c.positive : s < 0 ? c.negative : c.zero) += 1;
  }
  return c;
}
}  // namespace

PlanarCutReport PlanarCutter::cut_deformed(const TriangleSurface& batch, const Points& nodes) {
  State& s = *state_;
  check_triangles(batch, "cut");
  if (nodes.rows() != num_nodes() || nodes.cols() != 3) {
    throw Error(ErrorKind::kInvalidInput, "cut_deformed: " + std::to_string(nodes.rows()) + " node positions for " +
                                              std::to_string(num_nodes()) + " nodes");
  }
  if (!nodes.allFinite()) throw Error(ErrorKind::kInvalidInput, "cut_deformed: a node position is not finite");
  PlanarCutReport report;
  report.first_new_node = num_nodes();
  report.first_new_triangle = num_triangles();
  report.segments = batch.num_triangles();

  // The copies near the batch in their current shapes: a pass over all copies' current boxes
  // against the batch's box (O(copies)), then a tree over those near it (O(k log k)). Box
  // comparisons are exact, so no copy a triangle reaches is missed.
  spatial::Aabb reach;
  for (Index v = 0; v < batch.num_vertices(); ++v) reach.extend(batch.vertices.row(v).transpose());
  std::vector<Index> near;
  std::vector<spatial::Aabb> boxes;
  for (Index c = 0; c < num_triangles(); ++c) {
    spatial::Aabb box;
    for (const Index n : s.copy_nodes[c]) box.extend(nodes.row(n).transpose());
    if (!box.meets(reach)) continue;
    near.push_back(c);
    boxes.push_back(box);
  }
  const spatial::BoxTree current(std::move(boxes));
  s.planes.forget_pulled_back();  // pulled back through other positions

  std::vector<std::uint8_t> touched(s.arrangements.size(), 0);
  std::vector<Index> candidates;
  for (Index i = 0; i < batch.num_triangles(); ++i) {
    const std::array<Vec3, 3> corners = triangle_corners(batch, i);
    const std::int64_t id = s.next_segment_id++;
    if (geometry::collinear(corners[0], corners[1], corners[2])) {
      report.degenerate.push_back(i);
      continue;
    }
    // The triangle in world space: its plane, and its edges' walls oriented towards the opposite
    // corner, as the 3D cutter makes them (shared with earlier triangles on the same plane or edge).
    using Found = registry::PlaneBook::Found;
    const Found plane = s.planes.triangle_plane(geometry::Plane::through(corners[0], corners[1], corners[2]), 4 * id);
    const int axis = geometry::wall_axis(*plane.plane);
    std::array<Found, 3> walls;
    for (int e = 0; e < 3; ++e) walls[e] = s.planes.wall(corners[e], corners[(e + 1) % 3], axis, corners[(e + 2) % 3], 4 * id + 1 + e);
    spatial::Aabb box;
    for (const Vec3& x : corners) box.extend(x);
    candidates.clear();
    current.query(box, &candidates);
    for (const Index candidate : candidates) {
      const Index copy = near[candidate];
      const std::array<Vec3, 3> now = {nodes.row(s.copy_nodes[copy][0]).transpose(), nodes.row(s.copy_nodes[copy][1]).transpose(),
                                       nodes.row(s.copy_nodes[copy][2]).transpose()};
      // The pull-backs are affine on the copy, so their signs at its corners bound them: a plane
      // on one side (touching at most a corner) misses it; a wall the copy is inside of bounds
      // nothing there; one it is outside of (touching at most a corner) leaves no cut in it.
      const SignCount on_plane = signs_at(*plane.plane, 1, now);
      if (on_plane.zero == 3) {
        report.skipped_coplanar.push_back(copy);  // the cut would be an area, not a line
        continue;
      }
      if ((on_plane.positive == 0 || on_plane.negative == 0) && on_plane.zero <= 1) continue;
      std::array<int, 3> kept{};
      int num_kept = 0;
      bool misses = false;
      for (int e = 0; e < 3 && !misses; ++e) {
        const SignCount on_wall = signs_at(*walls[e].plane, walls[e].sign, now);
        if (on_wall.negative == 0) continue;
        misses = on_wall.positive == 0 && on_wall.zero <= 1;
        kept[num_kept++] = e;
      }
      if (misses) continue;
      // Pulled back through the copy's motion. A planar triangle is lifted to the tet over it
      // with its fourth corner one unit above its first, moving with that corner: the pull-back's
      // trace on the rest plane (all that the planar cutter uses) is the interpolation of the
      // world plane's values at the copy's three current corners, and the plane is vertical, a
      // line like every other line here. Copies sharing an edge and its nodes agree on it exactly.
      const Index t = s.copy_triangle[copy];
      std::array<Vec3, 4> rest, moved;
      for (int k = 0; k < 3; ++k) {
        rest[k] = s.rest3.row(s.input.triangles(t, k)).transpose();
        moved[k] = now[k];
      }
      rest[3] = rest[0] + Vec3::UnitZ();
      moved[3] = now[0];
      const auto pulled = [&](const Found& found) {
        return s.planes.per_copy(found.key, copy, [&] {
          return s.geometry.registry.add_plane(geometry::Plane::pulled_back(*found.plane, rest, moved, found.key));
        });
      };
      planar::PreparedSegment segment;
      segment.id = id;
      segment.label = copy;
      segment.line = pulled(plane);
      segment.num_walls = num_kept;
      for (int w = 0; w < num_kept; ++w) segment.walls[w] = {pulled(walls[kept[w]]), walls[kept[w]].sign};
      s.insert(t, segment, &touched);
    }
  }
  std::sort(report.skipped_coplanar.begin(), report.skipped_coplanar.end());
  report.skipped_coplanar.erase(std::unique(report.skipped_coplanar.begin(), report.skipped_coplanar.end()),
                                report.skipped_coplanar.end());
  s.finish_batch(touched, &report);
  return report;
}

Points2 PlanarCutter::to_rest(const Points& world, const Points& nodes) const {
  const State& s = *state_;
  if (nodes.rows() != num_nodes()) {
    throw Error(ErrorKind::kInvalidInput, "to_rest: " + std::to_string(nodes.rows()) + " node positions for " +
                                              std::to_string(num_nodes()) + " nodes");
  }
  Points2 rest(world.rows(), 2);
  for (Index i = 0; i < world.rows(); ++i) {
    const Vec3 x = world.row(i).transpose();
    if (!x.allFinite()) throw Error(ErrorKind::kInvalidInput, "to_rest: point " + std::to_string(i) + " is not finite");
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector2d mapped = Eigen::Vector2d::Zero();
    for (Index c = 0; c < num_triangles(); ++c) {
      const auto& n = s.copy_nodes[c];
      const Vec3 a = nodes.row(n[0]).transpose(), b = nodes.row(n[1]).transpose(), d = nodes.row(n[2]).transpose();
      if ((b - a).cross(d - a).squaredNorm() == 0) continue;
      const collision::Proximity near = collision::point_triangle(x, a, b, d);
      if (near.distance >= best) continue;
      best = near.distance;
      // r = x - q with q = sum of the corners by -w[1..3]: the same weights on the rest corners.
      mapped.setZero();
      for (int k = 0; k < 3; ++k) mapped -= near.w[k + 1] * s.input.rest.row(s.input.triangles(s.copy_triangle[c], k)).transpose();
    }
    if (!std::isfinite(best)) throw Error(ErrorKind::kInvalidInput, "to_rest: every triangle is degenerate in the given positions");
    rest.row(i) = mapped.transpose();
  }
  return rest;
}

PlanarCutResult PlanarCutter::result() const {
  State& s = *state_;
  PlanarCutResult r;
  PlanarCutMesh& m = r.mesh;
  const Index copies = num_triangles();
  m.mesh.rest.resize(num_nodes(), 2);
  for (Index n = 0; n < num_nodes(); ++n) m.mesh.rest.row(n) = s.input.rest.row(s.node_parent[n]);
  m.mesh.triangles.resize(copies, 3);
  for (Index c = 0; c < copies; ++c) {
    for (int k = 0; k < 3; ++k) m.mesh.triangles(c, k) = s.copy_nodes[c][k];
  }
  m.node_parent = s.node_parent;
  m.triangle_parent = s.copy_triangle;
  m.triangle_material_area = s.copy_area;

  // Pieces: copies joined across edges, by area, largest first (ties by first copy).
  UnionFind sets(copies);
  for (Index e = 0; e < static_cast<Index>(s.edges.size()); ++e) {
    for (const auto& [a, b] : s.joins(e)) sets.join(a, b);
  }
  std::vector<Index> root_piece(copies, -1), copy_class(copies);
  std::vector<double> class_area;
  for (Index c = 0; c < copies; ++c) {
    Index& p = root_piece[sets.find(c)];
    if (p < 0) {
      p = static_cast<Index>(class_area.size());
      class_area.push_back(0);
    }
    copy_class[c] = p;
    class_area[p] += s.copy_area[c];
  }
  std::vector<Index> order(class_area.size());
  std::iota(order.begin(), order.end(), Index{0});
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) { return class_area[a] > class_area[b]; });
  std::vector<Index> rank(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) rank[order[i]] = static_cast<Index>(i);
  m.triangle_piece.resize(copies);
  for (Index c = 0; c < copies; ++c) m.triangle_piece[c] = rank[copy_class[c]];
  m.piece_areas.resize(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) m.piece_areas[i] = class_area[order[i]];

  // The material. A vertex is one per point and per set of nodes its position depends on: a node
  // is itself; a point inside a mesh edge follows the copy's two nodes of that edge; a point inside
  // a triangle follows the copy. So both sides of a cut get their own vertices, and copies that move
  // together share them.
  PlanarMaterial& material = r.material;
  std::map<std::array<Index, 4>, Index> vertex_of;
  std::vector<Eigen::Vector2d> rest;
  std::vector<Index> vertex_copy;
  std::vector<Eigen::Vector3d> weights;
  const auto& registry = s.geometry.registry;
  auto vertex = [&](VertexId v, Index copy) {
    const Index t = s.copy_triangle[copy];
    auto corner_node = [&](Index input_node) {
      int k = 0;
      while (s.input.triangles(t, k) != input_node) ++k;
      return s.copy_nodes[copy][k];
    };
    std::array<Index, 4> key{};
    if (const Index node = registry.vertex(v).node; node >= 0) {
      key = {0, corner_node(node), -1, -1};
    } else if (const Index e = s.geometry.vertex_edge[v]; e >= 0) {
      key = {1, v, corner_node(s.edges[e][0]), corner_node(s.edges[e][1])};
    } else {
      key = {2, v, copy, -1};
    }
    const auto [it, inserted] = vertex_of.try_emplace(key, static_cast<Index>(rest.size()));
    if (inserted) {
      const Vec3& x = registry.position(v);
      rest.emplace_back(x.x(), x.y());
      vertex_copy.push_back(copy);
      // Barycentric weights in the rest triangle (rounded; geometry only).
      const Eigen::Vector2d a = s.input.rest.row(s.input.triangles(t, 0)).transpose(),
                            b = s.input.rest.row(s.input.triangles(t, 1)).transpose(),
                            c = s.input.rest.row(s.input.triangles(t, 2)).transpose();
      const Eigen::Vector2d p(x.x(), x.y());
      auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& w) { return u.x() * w.y() - u.y() * w.x(); };
      const double area = cross(b - a, c - a);
      const double w1 = cross(p - a, c - a) / area, w2 = cross(b - a, p - a) / area;
      weights.emplace_back(1 - w1 - w2, w1, w2);
    }
    return it->second;
  };
  std::vector<std::array<Index, 3>> triangles;
  std::vector<Index> triangle_copy;
  std::vector<std::array<Index, 2>> segments;
  std::vector<std::int64_t> source;
  std::vector<Index> segment_copy;
  auto boundary_edge = [&](Index e) { return s.edge_sides[e][1][0] < 0; };
  for (Index t = 0; t < s.input.num_triangles(); ++t) {
    if (!s.arrangements[t]) {
      const Index copy = s.triangle_copies[t][0];
      std::array<Index, 3> corners{};
      for (int k = 0; k < 3; ++k) corners[k] = vertex(s.geometry.node_vertex[s.input.triangles(t, k)], copy);
      triangles.push_back(corners);
      triangle_copy.push_back(copy);
      for (int k = 0; k < 3; ++k) {
        const Index e = s.triangle_edges[t][k];
        if (!boundary_edge(e)) continue;
        segments.push_back({corners[k], corners[(k + 1) % 3]});
        source.push_back(-1 - e);
        segment_copy.push_back(copy);
      }
      continue;
    }
    const auto& arrangement = *s.arrangements[t];
    for (int f = 0; f < static_cast<int>(arrangement.faces().size()); ++f) {
      // A fan from the first corner; cells are convex, and collinear corners give zero-area
      // triangles, which renderers ignore and which keep every boundary vertex in the fan.
      const Index copy = arrangement.faces()[f].label;
      const std::vector<VertexId> corners = arrangement.face_corners(f);
      const Index first = vertex(corners[0], copy);
      for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
        triangles.push_back({first, vertex(corners[i], copy), vertex(corners[i + 1], copy)});
        triangle_copy.push_back(copy);
      }
    }
    const auto& half_edges = arrangement.half_edges();
    for (const planar::HalfEdge& h : half_edges) {
      if (h.face < 0) continue;
      const bool outer = h.side >= 0 && boundary_edge(s.triangle_edges[t][h.side]);
      if (h.covering < 0 && !outer) continue;
      const Index copy = arrangement.faces()[h.face].label;
      segments.push_back({vertex(h.origin, copy), vertex(half_edges[h.twin].origin, copy)});
      source.push_back(h.covering >= 0 ? h.covering : -1 - s.triangle_edges[t][h.side]);
      segment_copy.push_back(copy);
    }
  }
  const auto vertices = static_cast<Index>(rest.size());
  material.rest.resize(vertices, 2);
  material.vertex_weights.resize(vertices, 3);
  for (Index i = 0; i < vertices; ++i) {
    material.rest.row(i) = rest[i].transpose();
    material.vertex_weights.row(i) = weights[i].transpose();
  }
  material.vertex_copy = std::move(vertex_copy);
  material.triangles.resize(static_cast<Index>(triangles.size()), 3);
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) material.triangles(static_cast<Index>(i), k) = triangles[i][k];
  }
  material.triangle_copy = std::move(triangle_copy);
  material.segments.resize(static_cast<Index>(segments.size()), 2);
  for (std::size_t i = 0; i < segments.size(); ++i) {
    material.segments(static_cast<Index>(i), 0) = segments[i][0];
    material.segments(static_cast<Index>(i), 1) = segments[i][1];
  }
  material.segment_source = std::move(source);
  material.segment_copy = std::move(segment_copy);
  return r;
}

Index PlanarCutter::num_nodes() const { return static_cast<Index>(state_->node_parent.size()); }
Index PlanarCutter::num_triangles() const { return static_cast<Index>(state_->copy_nodes.size()); }
const std::vector<std::array<Index, 3>>& PlanarCutter::triangle_nodes() const { return state_->copy_nodes; }
const std::vector<Index>& PlanarCutter::node_parent() const { return state_->node_parent; }
const std::vector<Index>& PlanarCutter::triangle_parent() const { return state_->copy_triangle; }
const std::vector<std::array<Index, 2>>& PlanarCutter::edge_nodes() const { return state_->edges; }
const PlanarMesh& PlanarCutter::input() const { return state_->input; }
Index PlanarCutter::num_cells() const {
  Index cells = 0;
  for (Index t = 0; t < state_->input.num_triangles(); ++t) {
    cells += state_->arrangements[t] ? static_cast<Index>(state_->arrangements[t]->faces().size()) : 1;
  }
  return cells;
}

PlanarMesh planar_mesh(const TriangleSurface& surface, RestPlane* plane) {
  const Index n = surface.num_vertices();
  if (n == 0 || surface.num_triangles() == 0) throw Error(ErrorKind::kInvalidInput, "the surface has no triangles");
  int normal = -1;
  for (int k = 2; k >= 0 && normal < 0; --k) {
    if ((surface.vertices.col(k).array() == surface.vertices(0, k)).all()) normal = k;
  }
  if (normal < 0) {
    throw Error(ErrorKind::kInvalidInput,
                "a planar mesh must lie in a coordinate plane (x, y or z the same at every vertex); this one does not");
  }
  RestPlane p;
  p.normal = normal;
  p.u = normal == 0 ? 1 : 0;
  p.v = normal == 2 ? 1 : 2;
  p.offset = surface.vertices(0, normal);
  PlanarMesh mesh;
  mesh.rest = to_plane(surface.vertices, p);
  mesh.triangles = surface.triangles;
  for (Index t = 0; t < mesh.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      if (mesh.triangles(t, k) < 0 || mesh.triangles(t, k) >= n) {
        throw Error(ErrorKind::kInvalidInput, triangle_name(t) + " names a vertex out of range");
      }
    }
  }
  // One orientation throughout: counter-clockwise in (u, v), or all clockwise (then swap u and v).
  auto orientation = [&](Index t) {
    const double a[2] = {mesh.rest(mesh.triangles(t, 0), 0), mesh.rest(mesh.triangles(t, 0), 1)};
    const double b[2] = {mesh.rest(mesh.triangles(t, 1), 0), mesh.rest(mesh.triangles(t, 1), 1)};
    const double c[2] = {mesh.rest(mesh.triangles(t, 2), 0), mesh.rest(mesh.triangles(t, 2), 1)};
    return geometry::orient2d(a, b, c);
  };
  int first = 0;
  for (Index t = 0; t < mesh.num_triangles(); ++t) {
    const int o = orientation(t);
    if (o == 0) continue;  // zero area: the cutter names it
    if (first == 0) first = o;
    if (o != first) {
      throw Error(ErrorKind::kInvalidInput, triangle_name(t) + " is oriented against the triangles before it: a planar mesh's "
                                                               "triangles must all turn the same way");
    }
  }
  if (first < 0) {
    std::swap(p.u, p.v);
    mesh.rest = to_plane(surface.vertices, p);
  }
  *plane = p;
  return mesh;
}

Points2 to_plane(const Points& points, const RestPlane& plane) {
  Points2 out(points.rows(), 2);
  out.col(0) = points.col(plane.u);
  out.col(1) = points.col(plane.v);
  return out;
}

Points to_space(const Points2& points, const RestPlane& plane) {
  Points out(points.rows(), 3);
  out.col(plane.u) = points.col(0);
  out.col(plane.v) = points.col(1);
  out.col(plane.normal).setConstant(plane.offset);
  return out;
}

std::vector<double> PlanarCutMesh::material_fractions() const {
  std::vector<double> fractions(triangle_material_area.size());
  for (std::size_t c = 0; c < fractions.size(); ++c) {
    const Index a = mesh.triangles(static_cast<Index>(c), 0), b = mesh.triangles(static_cast<Index>(c), 1),
                d = mesh.triangles(static_cast<Index>(c), 2);
    const Eigen::Vector2d u = mesh.rest.row(b) - mesh.rest.row(a), w = mesh.rest.row(d) - mesh.rest.row(a);
    fractions[c] = triangle_material_area[c] / (0.5 * (u.x() * w.y() - u.y() * w.x()));
  }
  return fractions;
}

Points PlanarMaterial::positions(const PlanarCutMesh& mesh, const Points& nodes) const {
  Points out(num_vertices(), 3);
  for (Index v = 0; v < num_vertices(); ++v) {
    const Index c = vertex_copy[v];
    out.row(v).setZero();
    for (int k = 0; k < 3; ++k) out.row(v) += vertex_weights(v, k) * nodes.row(mesh.mesh.triangles(c, k));
  }
  return out;
}

}  // namespace tetcut
