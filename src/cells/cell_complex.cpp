#include "cells/cell_complex.hpp"

#include "mesh/local_index.hpp"
#include "util/broken.hpp"

#include <tetcut/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace tetcut::cells {

using geometry::Plane;
using registry::OrientedPlane;

CellComplex::CellComplex(const TetMesh& mesh, registry::IntersectionRegistry& registry)
    : mesh_(&mesh),
      registry_(&registry),
      first_cell_(static_cast<std::size_t>(mesh.num_tets()), -1),
      tet_material_(static_cast<std::size_t>(mesh.num_tets()), 1),
      face_first_facet_(static_cast<std::size_t>(mesh.adjacency().num_faces()), -1),
      face_plane_(static_cast<std::size_t>(mesh.adjacency().num_faces()), -1),
      mesh_edge_first_(static_cast<std::size_t>(mesh.adjacency().num_edges()), -1),
      node_vertex_(static_cast<std::size_t>(mesh.num_nodes()), -1),
      tet_label_(static_cast<std::size_t>(mesh.num_tets()), -1),
      tet_touch_stamp_(static_cast<std::size_t>(mesh.num_tets()), -1) {}

Index CellComplex::tet_of(Side s) const {
  if (is_cell(s)) return cells_[s].tet;
  if (is_unrefined(s)) return unrefined_tet(s);
  return -1;
}

bool CellComplex::side_is_material(Side s) const {
  if (is_cell(s)) return cells_[s].material;
  if (is_unrefined(s)) return tet_material(unrefined_tet(s));
  return false;
}

void CellComplex::set_tet_material(Index tet, bool material) {
  tet_material_[tet] = material ? 1 : 0;
  for (CellId c = first_cell_[tet]; c >= 0; c = cells_[c].next_in_tet) cells_[c].material = material;
}

// ---- Lazy refinement ---------------------------------------------------------------------------

PlaneId CellComplex::face_plane(Index face) {
  if (face_plane_[face] < 0) {
    // Faces are stored with ascending node ids; the plane through them in that order fixes the
    // orientation of every facet on the face.
    const auto& faces = mesh_->adjacency().faces;
    const Points& p = mesh_->rest();
    face_plane_[face] = registry_->add_plane(Plane::through(p.row(faces(face, 0)).transpose(),
                                                            p.row(faces(face, 1)).transpose(),
                                                            p.row(faces(face, 2)).transpose()));
  }
  return face_plane_[face];
}

VertexId CellComplex::node_vertex(Index node, Index tet) {
  if (node_vertex_[node] < 0) {
    // A mesh node is the meeting of the three faces of `tet` through it.
    const int i = local_index(mesh_->tets(), tet, node);
    PlaneId planes[3];
    for (int k = 0, m = 0; k < 4; ++k) {
      if (k != i) planes[m++] = face_plane(mesh_->adjacency().tet_faces(tet, k));
    }
    node_vertex_[node] = registry_->add_node(node, planes[0], planes[1], planes[2]);
  }
  return node_vertex_[node];
}

EdgeId CellComplex::add_edge(VertexId a, VertexId b, std::array<PlaneId, 2> line, Index mesh_edge) {
  Edge edge;
  edge.a = a;
  edge.b = b;
  edge.line = line;
  edge.mesh_edge = mesh_edge;
  if (mesh_edge >= 0) edge.next_on_mesh_edge = mesh_edge_first_[mesh_edge];
  const EdgeId id = static_cast<EdgeId>(edges_.push_back(std::move(edge)) - edges_.begin());
  if (mesh_edge >= 0) mesh_edge_first_[mesh_edge] = id;
  return id;
}

template <typename Visit>
void CellComplex::walk_mesh_edge(Index mesh_edge, VertexId start, VertexId target, Visit&& visit) const {
  // The edge records on a mesh edge form a path between its nodes: at each vertex, take the record
  // that does not lead back. O(records on the edge) per step.
  VertexId previous = -1, current = start;
  while (current != target) {
    EdgeId next = -1;
    for (EdgeId e = mesh_edge_first_[mesh_edge]; e >= 0; e = edges_[e].next_on_mesh_edge) {
      const Edge& edge = edges_[e];
      const VertexId other = edge.a == current ? edge.b : (edge.b == current ? edge.a : -1);
      if (other >= 0 && other != previous) {
        next = e;
        break;
      }
    }
    if (next < 0) broken("cell complex", "the edge records on a mesh edge do not form a path");
    visit(current, next);
    previous = current;
    current = edges_[next].a == current ? edges_[next].b : edges_[next].a;
  }
}

void CellComplex::append_mesh_edge_chain(Index mesh_edge, Index from, Index to, Index tet, FacetId facet,
                                         std::vector<Corner>* corners) {
  const VertexId start = node_vertex(from, tet);
  const VertexId target = node_vertex(to, tet);
  if (mesh_edge_first_[mesh_edge] < 0) {
    // The two faces of `tet` through the edge are those opposite its two other nodes.
    PlaneId line[2];
    for (int k = 0, m = 0; k < 4; ++k) {
      const Index node = mesh_->tets()(tet, k);
      if (node != from && node != to) line[m++] = face_plane(mesh_->adjacency().tet_faces(tet, k));
    }
    add_edge(start, target, {line[0], line[1]}, mesh_edge);
  }
  walk_mesh_edge(mesh_edge, start, target, [&](VertexId from_vertex, EdgeId edge) {
    corners->push_back({from_vertex, edge});
    edges_[edge].facets.push_back(facet);
  });
}

void CellComplex::mesh_edge_points(Index mesh_edge, Index from, Index to, std::vector<VertexId>* out) const {
  if (mesh_edge_first_[mesh_edge] < 0) return;
  const VertexId start = node_vertex_[from];
  walk_mesh_edge(mesh_edge, start, node_vertex_[to], [&](VertexId vertex, EdgeId) {
    if (vertex != start) out->push_back(vertex);
  });
}

void CellComplex::add_face_facet(Index face, Index tet, CellId cell) {
  const TetAdjacency& adj = mesh_->adjacency();
  const Tets& tets = mesh_->tets();
  const PlaneId plane = face_plane(face);
  int local_face = 0;
  while (adj.tet_faces(tet, local_face) != face) ++local_face;
  // Face k of a tet is opposite its local node k: that node tells which side the tet is on.
  const int tet_side = geometry::side_of_point(registry_->plane(plane), mesh_->rest().row(tets(tet, local_face)).transpose());
  Side other = kOutside;
  for (const Index t : adj.tets_of_face(face)) {
    if (t != tet) other = unrefined_side(t);
  }
  Facet facet;
  facet.plane = plane;
  facet.mesh_face = face;
  facet.front = tet_side > 0 ? cell : other;
  facet.back = tet_side > 0 ? other : cell;
  const FacetId id = static_cast<FacetId>(facets_.push_back(std::move(facet)) - facets_.begin());

  // The cycle n0 -> n1 -> n2 (ascending ids) is counter-clockwise seen from the plane's front.
  const Index n[3] = {adj.faces(face, 0), adj.faces(face, 1), adj.faces(face, 2)};
  std::vector<Corner> corners;
  for (int k = 0; k < 3; ++k) {
    const Index from = n[k], to = n[(k + 1) % 3];
    Index mesh_edge = -1;
    for (int e = 0; e < 6; ++e) {
      const Index a = tets(tet, kTetEdges[e][0]), b = tets(tet, kTetEdges[e][1]);
      if ((a == from && b == to) || (a == to && b == from)) mesh_edge = adj.tet_edges(tet, e);
    }
    append_mesh_edge_chain(mesh_edge, from, to, tet, id, &corners);
  }
  facets_[id].corners = std::move(corners);
  facets_[id].next_on_mesh_face = face_first_facet_[face];
  face_first_facet_[face] = id;
  cells_[cell].facets.push_back(id);
}

CellId CellComplex::refine(Index tet) {
  if (first_cell_[tet] >= 0) return first_cell_[tet];
  Cell c;
  c.tet = tet;
  c.material = tet_material_[tet] != 0;
  c.label = tet_label_[tet];
  const CellId cell = static_cast<CellId>(cells_.push_back(std::move(c)) - cells_.begin());
  first_cell_[tet] = cell;
  const Side marker = unrefined_side(tet);
  for (int k = 0; k < 4; ++k) {
    const Index face = mesh_->adjacency().tet_faces(tet, k);
    if (face_first_facet_[face] < 0) {
      add_face_facet(face, tet, cell);
      continue;
    }
    // A refined neighbour already made this face's facets; they refer to this tet by its marker.
    for (FacetId f = face_first_facet_[face]; f >= 0; f = facets_[f].next_on_mesh_face) {
      Facet& facet = facets_[f];
      if (facet.front == marker) {
        facet.front = cell;
      } else if (facet.back == marker) {
        facet.back = cell;
      } else {
        broken("cell complex", "a facet on a face of an unrefined tet does not refer to it");
      }
      cells_[cell].facets.push_back(f);
    }
  }
  return cell;
}

// ---- Predicates on cells and facets ------------------------------------------------------------

namespace {

// Sides seen so far of a set of vertices relative to a plane, and what they say together.
struct SidesSeen {
  bool positive = false, negative = false;
  void add(int side) {
    positive = positive || side > 0;
    negative = negative || side < 0;
  }
  bool both() const { return positive && negative; }
  // -1 all <= 0, 0 both sides, +1 all >= 0, 2 all on the plane.
  int classification() const { return both() ? 0 : positive ? 1 : negative ? -1 : 2; }
};

}  // namespace

int CellComplex::classify(CellId cell, PlaneId plane, registry::IntersectionRegistry::SideMemo* memo) const {
  SidesSeen seen;
  for (const FacetId f : cells_[cell].facets) {
    for (const Corner& corner : facets_[f].corners) {
      seen.add(registry_->side(corner.vertex, plane, memo));
      if (seen.both()) return 0;
    }
  }
  return seen.classification();
}

bool CellComplex::facet_on_plane(FacetId facet, PlaneId plane, registry::IntersectionRegistry::SideMemo* memo) const {
  if (facets_[facet].plane == plane) return true;
  for (const Corner& corner : facets_[facet].corners) {
    if (registry_->side(corner.vertex, plane, memo) != 0) return false;
  }
  return true;
}

int CellComplex::classify_facet(FacetId facet, PlaneId plane, registry::IntersectionRegistry::SideMemo* memo) const {
  SidesSeen seen;
  for (const Corner& corner : facets_[facet].corners) seen.add(registry_->side(corner.vertex, plane, memo));
  return seen.classification();
}

bool CellComplex::section_overlaps_triangle(const Insertion& in, CellId cell) const {
  // The section S of the cell by the triangle's plane and the triangle T are convex polygons in
  // that plane; their interiors meet unless a line through an edge of one separates them.
  // Edges of S lie on the cell's facet planes: T wholly outside one of them (touching allowed).
  for (const FacetId f : cells_[cell].facets) {
    const PlaneId plane = facets_[f].plane;
    const int outward = facets_[f].back == cell ? 1 : -1;
    if (corner_side(in, 0, plane) * outward >= 0 && corner_side(in, 1, plane) * outward >= 0 &&
        corner_side(in, 2, plane) * outward >= 0) {
      return false;
    }
  }
  // Edges of T lie on the walls: S wholly outside one of them. The corners of S are the cell's
  // vertices on the plane and the points where its edges cross it (not registered: most cells
  // tested here are not split).
  const PlaneId plane = in.triangle->plane.id;
  for (const OrientedPlane& wall : in.triangle->walls) {
    bool outside = true;
    for (const FacetId f : cells_[cell].facets) {
      const auto& corners = facets_[f].corners;
      const std::size_t n = corners.size();
      for (std::size_t i = 0; i < n && outside; ++i) {
        const VertexId u = corners[i].vertex, v = corners[(i + 1) % n].vertex;
        const int su = registry_->side(u, plane, in.memo);
        if (su == 0) {
          outside = registry_->side(u, wall.id, in.memo) * wall.sign <= 0;
        } else if (su * registry_->side(v, plane, in.memo) < 0) {
          const Edge& edge = edges_[corners[i].edge];
          outside = registry_->side_of_meet(edge.line[0], edge.line[1], plane, wall.id) * wall.sign <= 0;
        }
      }
      if (!outside) break;
    }
    if (outside) return false;
  }
  return true;
}

int CellComplex::corner_side(const Insertion& in, int k, PlaneId plane) const {
  const PreparedTriangle& t = *in.triangle;
  if (t.corners_are_inputs) return registry_->side_of_input(plane, t.corners[k]);
  return registry_->side_of_meet(t.plane.id, t.walls[k].id, t.walls[(k + 2) % 3].id, plane);
}

bool tet_may_meet_triangle(const std::array<Vec3, 4>& x, const geometry::Plane& plane,
                           const std::array<std::pair<const geometry::Plane*, int>, 3>& walls,
                           const std::function<int(int, const geometry::Plane&)>& corner_side) {
  int side[4], positive = 0, negative = 0;
  for (int k = 0; k < 4; ++k) {
    side[k] = geometry::side_of_point(plane, x[k]);
    positive += side[k] > 0;
    negative += side[k] < 0;
  }
  if (positive == 0 || negative == 0) return positive + negative == 1;  // only a face on the plane matters
  // The section and the triangle, two convex polygons in the plane: separated by a face of the tet
  // (the triangle's corners all outside it), or by a wall (the section's corners all outside it).
  for (int f = 0; f < 4; ++f) {
    const auto& local = kTetFaces[f];
    const geometry::Plane face = geometry::Plane::through(x[local[0]], x[local[1]], x[local[2]]);  // outward
    if (corner_side(0, face) >= 0 && corner_side(1, face) >= 0 && corner_side(2, face) >= 0) return false;
  }
  for (const auto& [wall, sign] : walls) {
    bool outside = true;
    for (int k = 0; k < 4 && outside; ++k) {
      if (side[k] == 0) outside = geometry::side_of_point(*wall, x[k]) * sign <= 0;
      for (int j = k + 1; j < 4 && outside; ++j) {
        if (side[k] * side[j] < 0) outside = geometry::side_of_segment_meet(x[k], x[j], plane, *wall) * sign <= 0;
      }
    }
    if (outside) return false;
  }
  return true;
}

bool CellComplex::tet_may_be_cut(const Insertion& in, Index tet) const {
  const PreparedTriangle& t = *in.triangle;
  std::array<Vec3, 4> x;
  for (int k = 0; k < 4; ++k) x[k] = mesh_->rest().row(mesh_->tets()(tet, k)).transpose();
  const geometry::Plane& plane = registry_->plane(t.plane.id);
  std::array<std::pair<const geometry::Plane*, int>, 3> walls;
  for (int e = 0; e < 3; ++e) walls[e] = {&registry_->plane(t.walls[e].id), t.walls[e].sign};
  return tet_may_meet_triangle(x, plane, walls, [&](int k, const geometry::Plane& face) {
    if (t.corners_are_inputs) return geometry::side_of_point(face, t.corners[k]);
    const geometry::Plane& b = registry_->plane(t.walls[k].id);
    const geometry::Plane& c = registry_->plane(t.walls[(k + 2) % 3].id);
    return geometry::side_of_tpi(plane, b, c, geometry::tpi_homogeneous(plane, b, c),
                                 geometry::normal_determinant_sign(plane, b, c), face);
  });
}

// ---- Splitting ---------------------------------------------------------------------------------

void CellComplex::touch(const Insertion& in, Index tet) {
  if (tet_touch_stamp_[tet] == in.stamp) return;
  tet_touch_stamp_[tet] = in.stamp;
  if (in.touched != nullptr) in.touched->push_back(tet);
}

void CellComplex::touch_side(const Insertion& in, Side s) {
  const Index tet = tet_of(s);
  if (tet >= 0) touch(in, tet);
}

void CellComplex::insert_on_edge(Insertion& in, EdgeId e, VertexId w) {
  const VertexId a = edges_[e].a, b = edges_[e].b;
  const EdgeId second = add_edge(w, b, edges_[e].line, edges_[e].mesh_edge);
  edges_[e].b = w;
  edges_[second].facets = edges_[e].facets;
  for (const FacetId f : edges_[e].facets) {
    auto& corners = facets_[f].corners;
    std::size_t i = 0;
    while (i < corners.size() && corners[i].edge != e) ++i;
    if (i == corners.size()) broken("cell complex", "an edge lists a facet that does not use it");
    if (corners[i].vertex == a) {
      corners.insert(corners.begin() + static_cast<std::ptrdiff_t>(i + 1), Corner{w, second});
    } else {
      // The facet runs b -> a along this edge: b -> w is now the second record, w -> a the first.
      corners[i].edge = second;
      corners.insert(corners.begin() + static_cast<std::ptrdiff_t>(i + 1), Corner{w, e});
    }
    touch_side(in, facets_[f].front);
    touch_side(in, facets_[f].back);
  }
}

FacetId CellComplex::split_facet(Insertion& in, FacetId f, PlaneId plane, CellId cell, CellId negative_cell) {
  // The corners are moved out (the facet gets its positive part back below), so that neither they
  // nor the copy of the facet for its negative part cost an allocation.
  const std::vector<Corner> corners = std::move(facets_[f].corners);
  facets_[f].corners.clear();
  const std::size_t n = corners.size();
  // A convex polygon crossed by a line meets it in exactly two boundary points, both vertices by
  // now: `rise` is followed by the positive run, `fall` by the negative run.
  std::size_t rise = n, fall = n;
  for (std::size_t i = 0; i < n; ++i) {
    if (registry_->side(corners[i].vertex, plane, in.memo) != 0) continue;
    const int next = registry_->side(corners[(i + 1) % n].vertex, plane, in.memo);
    if (next > 0) rise = (rise == n) ? i : n + 1;
    if (next < 0) fall = (fall == n) ? i : n + 1;
  }
  if (rise >= n || fall >= n) broken("cell complex", "a crossing facet does not meet the plane in exactly two vertices");
  const VertexId a = corners[rise].vertex, b = corners[fall].vertex;
  const EdgeId chord = add_edge(a, b, {facets_[f].plane, plane}, -1);

  std::vector<Corner> positive, negative;
  for (std::size_t i = rise; i != fall; i = (i + 1) % n) positive.push_back(corners[i]);
  positive.push_back({b, chord});
  for (std::size_t i = fall; i != rise; i = (i + 1) % n) negative.push_back(corners[i]);
  negative.push_back({a, chord});

  Facet part = facets_[f];
  part.corners = std::move(negative);
  if (cell >= 0) {
    if (part.front == cell) part.front = negative_cell;
    if (part.back == cell) part.back = negative_cell;
  }
  part.next_on_mesh_face = -1;
  const FacetId g = static_cast<FacetId>(facets_.push_back(std::move(part)) - facets_.begin());
  const auto& moved = facets_[g].corners;
  for (std::size_t k = 0; k + 1 < moved.size(); ++k) {
    auto& list = edges_[moved[k].edge].facets;
    std::replace(list.begin(), list.end(), f, g);
  }
  edges_[chord].facets = {f, g};
  facets_[f].corners = std::move(positive);
  if (facets_[g].mesh_face >= 0) {
    facets_[g].next_on_mesh_face = face_first_facet_[facets_[g].mesh_face];
    face_first_facet_[facets_[g].mesh_face] = g;
  }
  // The new part's cells list it: in a split of `cell`, the caller adds it to the negative cell.
  for (const Side side : {facets_[g].front, facets_[g].back}) {
    if (cell >= 0 && side == negative_cell) continue;
    if (is_cell(side)) cells_[side].facets.push_back(g);
    touch_side(in, side);
  }
  return g;
}

void CellComplex::mark_crossings(Insertion& in, FacetId f, PlaneId plane) {
  for (std::size_t i = 0; i < facets_[f].corners.size(); ++i) {
    const std::size_t n = facets_[f].corners.size();
    const Corner corner = facets_[f].corners[i];
    const VertexId next = facets_[f].corners[(i + 1) % n].vertex;
    if (registry_->side(corner.vertex, plane, in.memo) * registry_->side(next, plane, in.memo) < 0) {
      const Edge& edge = edges_[corner.edge];
      insert_on_edge(in, corner.edge, registry_->add_point(edge.line[0], edge.line[1], plane));
    }
  }
}

FacetId CellComplex::split_facet_in_plane(Insertion& in, FacetId f, PlaneId plane) {
  mark_crossings(in, f, plane);
  return split_facet(in, f, plane, -1, -1);
}

CellId CellComplex::split(Insertion& in, CellId cell, PlaneId plane, FacetId* section) {
  if (classify(cell, plane, in.memo) != 0) return -1;
  // Moved out: the cell gets its positive facets back at the end, and nothing reads its list
  // meanwhile (split_facet adds new parts to the other side's list only).
  const std::vector<FacetId> old_facets = std::move(cells_[cell].facets);
  cells_[cell].facets.clear();

  // 1. A vertex on every edge of the cell that crosses the plane, in every facet around that edge.
  for (const FacetId f : old_facets) mark_crossings(in, f, plane);

  // 2. The negative part, linked after the cell in its tet's list.
  CellId negative_cell = -1;
  {
    Cell part;
    part.tet = cells_[cell].tet;
    part.material = cells_[cell].material;
    part.label = cells_[cell].label;
    part.next_in_tet = cells_[cell].next_in_tet;
    negative_cell = static_cast<CellId>(cells_.push_back(std::move(part)) - cells_.begin());
    cells_[cell].next_in_tet = negative_cell;
    cells_[cell].box_min = {1, 1, 1};  // the positive part is smaller now: recompute when asked
    cells_[cell].box_max = {0, 0, 0};
  }
  touch(in, cells_[cell].tet);

  // 3. Distribute the facets, splitting those that cross. Collect the section's edges, directed
  //    as the positive cell's outward facets run along them (that is the section's own
  //    counter-clockwise order seen from the positive side, where its normal points).
  struct Directed {
    VertexId from, to;
    EdgeId edge;
  };
  std::vector<Directed> section_edges;
  std::vector<FacetId> positive_facets, negative_facets;
  for (const FacetId f : old_facets) {
    const bool cell_is_back = facets_[f].back == cell;
    SidesSeen seen;
    for (const Corner& corner : facets_[f].corners) seen.add(registry_->side(corner.vertex, plane, in.memo));
    const bool negative = seen.negative;
    if (seen.both()) {
      negative_facets.push_back(split_facet(in, f, plane, cell, negative_cell));
      positive_facets.push_back(f);
      // The chord closes the positive part: stored from its last corner to its first.
      const auto& corners = facets_[f].corners;
      const VertexId last = corners.back().vertex, first = corners.front().vertex;
      section_edges.push_back(cell_is_back ? Directed{last, first, corners.back().edge}
                                           : Directed{first, last, corners.back().edge});
      continue;
    }
    if (negative) {
      Facet& facet = facets_[f];
      (cell_is_back ? facet.back : facet.front) = negative_cell;
      negative_facets.push_back(f);
    } else {
      positive_facets.push_back(f);
    }
    // Edges on the plane: the positive cell runs them in its outward direction; for a negative
    // facet that is the reverse of the negative cell's outward direction.
    const auto& corners = facets_[f].corners;
    const std::size_t n = corners.size();
    for (std::size_t i = 0; i < n; ++i) {
      const VertexId u = corners[i].vertex, v = corners[(i + 1) % n].vertex;
      if (registry_->side(u, plane, in.memo) != 0 || registry_->side(v, plane, in.memo) != 0) continue;
      const bool stored_direction = cell_is_back != negative;
      section_edges.push_back(stored_direction ? Directed{u, v, corners[i].edge} : Directed{v, u, corners[i].edge});
    }
  }

  // 4. Chain the section's edges into its cycle, from the first edge found (so that the cap's
  //    first corner follows the cell's facet order, not the numbering of points). Edges on the
  //    plane were seen from both of their facets, in the same direction; keep one copy.
  if (section_edges.empty()) broken("cell complex", "the section of a split cell is empty");
  const VertexId start = section_edges.front().from;
  std::sort(section_edges.begin(), section_edges.end(),
            [](const Directed& x, const Directed& y) { return x.from < y.from || (x.from == y.from && x.edge < y.edge); });
  section_edges.erase(std::unique(section_edges.begin(), section_edges.end(),
                                  [](const Directed& x, const Directed& y) { return x.from == y.from && x.edge == y.edge; }),
                      section_edges.end());
  for (std::size_t i = 1; i < section_edges.size(); ++i) {
    if (section_edges[i].from == section_edges[i - 1].from) broken("cell complex", "the section of a split cell branches");
  }
  Facet cap;
  cap.plane = plane;
  cap.front = cell;
  cap.back = negative_cell;
  VertexId v = start;
  do {
    const auto it = std::lower_bound(section_edges.begin(), section_edges.end(), v,
                                     [](const Directed& x, VertexId key) { return x.from < key; });
    if (it == section_edges.end() || it->from != v || cap.corners.size() >= section_edges.size()) {
      broken("cell complex", "the section of a split cell is not one closed polygon");
    }
    cap.corners.push_back({v, it->edge});
    v = it->to;
  } while (v != start);
  if (cap.corners.size() != section_edges.size() || cap.corners.size() < 3) {
    broken("cell complex", "the section of a split cell is not one closed polygon");
  }
  const FacetId cap_id = static_cast<FacetId>(facets_.push_back(std::move(cap)) - facets_.begin());
  for (const Corner& corner : facets_[cap_id].corners) edges_[corner.edge].facets.push_back(cap_id);
  positive_facets.push_back(cap_id);
  negative_facets.push_back(cap_id);
  cells_[cell].facets = std::move(positive_facets);
  cells_[negative_cell].facets = std::move(negative_facets);
  if (section != nullptr) *section = cap_id;
  return negative_cell;
}

// ---- Insertion ---------------------------------------------------------------------------------

void CellComplex::cover(Insertion& in, FacetId f) {
  Facet& facet = facets_[f];
  if (facet.stamp == in.stamp) return;
  facet.stamp = in.stamp;
  if (facet.covering < 0) facet.covering = in.stamp;
  const OrientedPlane& plane = in.triangle->plane;
  // The facet lies on the plane (its corners do, exactly); only the orientation is left, the sign
  // of the two normals' dot product, which is far from zero for equal planes.
  const int alignment = facet.plane == plane.id ? 1 : registry_->normal_alignment(facet.plane, plane.id);
  if (alignment == 0) broken("cell complex", "a covered facet is not on the cut plane");
  facet.winding += alignment * plane.sign;
  touch_side(in, facet.front);
  touch_side(in, facet.back);
}

bool CellComplex::cover_inside(Insertion& in, FacetId f, CellId cell) {
  // The facet lies on the triangle's plane; the triangle there is the part inside its three walls.
  if (facets_[f].stamp == in.stamp) return false;
  if (in.front_covers_faces && facets_[f].mesh_face >= 0 && facets_[f].back == cell &&
      side_is_material(facets_[f].front)) {
    return false;  // the front side's tet covers it, before or after this one
  }
  bool changed = false;
  FacetId inside = f;
  for (const OrientedPlane& wall : in.triangle->walls) {
    const int position = classify_facet(inside, wall.id, in.memo) * wall.sign;
    if (position == -1) return changed;  // outside the triangle, or touching its edge
    if (position != 0) continue;
    const FacetId negative = split_facet_in_plane(in, inside, wall.id);
    changed = true;
    if (wall.sign < 0) inside = negative;
  }
  cover(in, inside);
  return true;
}

bool CellComplex::process_cell(Insertion& in, CellId cell) {
  const PlaneId plane = in.triangle->plane.id;
  if (classify(cell, plane, in.memo) == 0) {
    // The plane crosses the cell: split it there when the triangle covers part of the section.
    if (!section_overlaps_triangle(in, cell)) return false;
    FacetId section = -1;
    split(in, cell, plane, &section);
    cover_inside(in, section, cell);
    return true;
  }
  // The cell only touches the plane: what matters is a facet on it (a cut along an earlier cut
  // or along a tet face).
  std::vector<FacetId> on_plane;
  for (const FacetId f : cells_[cell].facets) {
    if (facets_[f].stamp != in.stamp && facet_on_plane(f, plane, in.memo)) on_plane.push_back(f);
  }
  bool changed = false;
  for (const FacetId f : on_plane) changed = cover_inside(in, f, cell) || changed;
  return changed;
}

PreparedTriangle CellComplex::prepare(const CutTriangle& triangle) {
  PreparedTriangle t;
  t.cut_id = triangle.id;
  t.corners_are_inputs = true;
  t.corners = {triangle.a, triangle.b, triangle.c};
  t.plane = registry_->triangle_plane(triangle.a, triangle.b, triangle.c);
  const int axis = geometry::wall_axis(registry_->plane(t.plane.id));
  for (int e = 0; e < 3; ++e) {
    t.walls[e] = registry_->wall(t.corners[e], t.corners[(e + 1) % 3], axis, t.corners[(e + 2) % 3]);
  }
  return t;
}

bool CellComplex::cell_misses_triangle_box(const Insertion& in, CellId cell) {
  Cell& c = cells_[cell];
  if (c.box_min[0] > c.box_max[0]) {
    // Rounded corners are within kCoordinateTolerance of the largest coordinate of each point
    // (certified: see geometry::tpi_coordinates), and float rounding goes outward.
    std::array<double, 3> lo{}, hi{};
    lo.fill(std::numeric_limits<double>::infinity());
    hi.fill(-std::numeric_limits<double>::infinity());
    double largest = 0;
    for (const FacetId f : c.facets) {
      for (const Corner& corner : facets_[f].corners) {
        const Vec3& x = registry_->position(corner.vertex);
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min(lo[k], x[k]);
          hi[k] = std::max(hi[k], x[k]);
        }
        largest = std::max(largest, x.cwiseAbs().maxCoeff());
      }
    }
    const double margin = 2 * geometry::kCoordinateTolerance * largest;
    constexpr float kInf = std::numeric_limits<float>::infinity();
    for (int k = 0; k < 3; ++k) {
      c.box_min[k] = std::nextafter(static_cast<float>(lo[k] - margin), -kInf);
      c.box_max[k] = std::nextafter(static_cast<float>(hi[k] + margin), kInf);
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (c.box_max[k] < in.box_min[k] || c.box_min[k] > in.box_max[k]) return true;
  }
  return false;
}

CellComplex::Insertion CellComplex::begin_insertion(const PreparedTriangle& triangle, std::int32_t stamp, std::vector<Index>* touched,
                                                     bool front_covers_faces, registry::IntersectionRegistry::SideMemo* memo) const {
  Insertion in;
  in.stamp = stamp;
  in.triangle = &triangle;
  in.touched = touched;
  in.front_covers_faces = front_covers_faces;
  if (triangle.corners_are_inputs) {
    in.has_box = true;
    for (int k = 0; k < 3; ++k) {
      in.box_min[k] = std::min({triangle.corners[0][k], triangle.corners[1][k], triangle.corners[2][k]});
      in.box_max[k] = std::max({triangle.corners[0][k], triangle.corners[1][k], triangle.corners[2][k]});
    }
  }
  memo->begin(*registry_, {triangle.plane.id, triangle.walls[0].id, triangle.walls[1].id, triangle.walls[2].id});
  in.memo = memo;
  return in;
}

void CellComplex::insert_into_tet(Insertion& in, Index tet, std::int32_t label, std::vector<CellId>* scratch) {
  if (!refined(tet)) {
    if (!tet_material(tet) || (label >= 0 && tet_label_[tet] != label) || !tet_may_be_cut(in, tet)) return;
    refine(tet);
    touch(in, tet);  // its cells are new, even if the triangle then leaves them whole
  }
  scratch->clear();
  for (CellId c = first_cell_[tet]; c >= 0; c = cells_[c].next_in_tet) scratch->push_back(c);
  for (const CellId c : *scratch) {
    if (!cells_[c].material || (label >= 0 && cells_[c].label != label)) continue;
    if (in.has_box && cell_misses_triangle_box(in, c)) continue;
    process_cell(in, c);
  }
}

void CellComplex::insert_triangle(const PreparedTriangle& triangle, std::span<const Index> tets, std::int32_t label,
                                  std::vector<Index>* touched) {
  const auto stamp = static_cast<std::int32_t>(inserted_.size());
  inserted_.push_back({triangle.plane, triangle.walls, triangle.cut_id});
  Insertion in = begin_insertion(triangle, stamp, touched, false, &side_memos_.local());
  std::vector<CellId> scratch;
  for (const Index tet : tets) insert_into_tet(in, tet, label, &scratch);
}

void CellComplex::insert_triangles(std::span<const PreparedTriangle> triangles, std::span<const std::vector<Index>> tets,
                                   std::vector<Index>* touched) {
  if (triangles.size() != tets.size()) throw Error(ErrorKind::kInvalidArgument, "insert_triangles: one list of tets per triangle");
  const auto first_stamp = static_cast<std::int32_t>(inserted_.size());
  for (const PreparedTriangle& t : triangles) inserted_.push_back({t.plane, t.walls, t.cut_id});

  // Blocks of side 5 L, where L bounds every edge (see the header for why 5).
  const Points& x = mesh_->rest();
  const Tets& elements = mesh_->tets();
  if (longest_edge_ < 0) {
    longest_edge_ = 0;
    for (Index t = 0; t < mesh_->num_tets(); ++t) {
      for (const auto& e : kTetEdges) {
        longest_edge_ = std::max(longest_edge_, (x.row(elements(t, e[0])) - x.row(elements(t, e[1]))).norm());
      }
    }
  }
  // A hair over 5 L: L is a computed norm, perhaps a rounding under the longest edge, and the
  // header's argument holds for blocks of at least 5 true L.
  constexpr double kBlockSideSlack = 1 + 1e-9;
  const double side = 5 * longest_edge_ * kBlockSideSlack;
  const Vec3 origin = x.colwise().minCoeff().transpose();
  struct Pair {
    std::int32_t triangle;
    Index tet;
  };
  std::unordered_map<std::uint64_t, std::size_t> block_of_key;
  std::vector<std::vector<Pair>> blocks;
  std::array<std::vector<std::size_t>, 8> blocks_of_colour;
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (const Index tet : tets[i]) {
      Vec3 centroid = Vec3::Zero();
      for (int k = 0; k < 4; ++k) centroid += x.row(elements(tet, k)).transpose();
      std::uint64_t key = 0;
      int colour = 0;
      for (int k = 0; k < 3; ++k) {
        const auto b = static_cast<std::uint64_t>(std::floor((centroid[k] / 4 - origin[k]) / side));
        key = (key << 21) | (b & 0x1fffff);
        colour |= static_cast<int>(b & 1) << k;
      }
      const auto [it, added] = block_of_key.try_emplace(key, blocks.size());
      if (added) {
        blocks.emplace_back();
        blocks_of_colour[colour].push_back(it->second);
      }
      blocks[it->second].push_back({static_cast<std::int32_t>(i), tet});
    }
  }

  // Each block takes its tets one at a time, inserting each one's triangles in order: a tet's
  // cells stay in cache while it is cut (a third faster than taking each triangle across the
  // block's tets). The order in which neighbouring tets insert a triangle does not matter (see
  // the header), and the cells of a tet depend only on the order of its own triangles.
  tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t b) {
    std::stable_sort(blocks[b].begin(), blocks[b].end(), [](const Pair& p, const Pair& q) { return p.tet < q.tet; });
  });
  // The blocks of one colour at once.
  std::vector<std::vector<Index>> block_touched(blocks.size());
  for (const std::vector<std::size_t>& colour : blocks_of_colour) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, colour.size(), 1), [&](const auto& range) {
      std::vector<CellId> scratch;
      registry::IntersectionRegistry::SideMemo& memo = side_memos_.local();
      for (std::size_t b = range.begin(); b != range.end(); ++b) {
        for (const Pair& pair : blocks[colour[b]]) {
          Insertion in = begin_insertion(triangles[pair.triangle], first_stamp + pair.triangle, &block_touched[colour[b]], true, &memo);
          insert_into_tet(in, pair.tet, -1, &scratch);
        }
      }
    });
  }
  if (touched != nullptr) {
    for (const std::vector<Index>& list : block_touched) touched->insert(touched->end(), list.begin(), list.end());
  }
}

// ---- Measures and checks -----------------------------------------------------------------------

double CellComplex::cell_volume6(CellId cell, const Vec3& origin) const {
  // Floating-point sum with a bound on its error: rounded corners are off by at most `delta`
  // each, and every product rounds. A cell far smaller than that rounding (it happens: input
  // planes at 0.3 and 0.55 meet a mesh edge y = x + 0.25 in three points 1e-17 apart) would come
  // out with an arbitrary sign, so then the volume is summed exactly in rationals.
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  double sum = 0, bound = 0, largest = origin.cwiseAbs().maxCoeff();
  for (const FacetId f : cells_[cell].facets) {
    for (const Corner& corner : facets_[f].corners) largest = std::max(largest, registry_->position(corner.vertex).cwiseAbs().maxCoeff());
  }
  const double delta = 2 * registry::IntersectionRegistry::position_tolerance() * largest;
  for (const FacetId f : cells_[cell].facets) {
    const Facet& facet = facets_[f];
    const auto& corners = facet.corners;
    const double sign = facet.back == cell ? 1 : -1;  // stored order is outward for the back cell
    const Vec3 a = registry_->position(corners[0].vertex) - origin;
    for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
      const Vec3 b = registry_->position(corners[i].vertex) - origin;
      const Vec3 c = registry_->position(corners[i + 1].vertex) - origin;
      sum += sign * a.dot(b.cross(c));
      const double na = a.norm(), nb = b.norm(), nc = c.norm();
      bound += delta * (nb * nc + na * nc + na * nb) + 8 * kEps * (na * nb * nc + largest * (nb * nc + na * nc + na * nb));
    }
  }
  if (std::abs(sum) > bound) return sum;
  return exact_cell_volume6(cell);
}

double CellComplex::exact_cell_volume6(CellId cell) const {
  // With exact points the fan volumes add up to the cell's volume from any origin, so take the
  // coordinate origin: the fan triangle (a, b, c) gives det(Xa, Xb, Xc) / (Wa Wb Wc) over the
  // points' exact homogeneous coordinates. Summing those fractions as rationals costs a gcd per
  // operation; instead each is divided out in 2048-bit floating point (relative error below
  // 2^-2000 per term and per addition), which settles the sign unless the sum is within
  // 2^-1900 of the terms' magnitudes, and only then are the rationals summed.

  // The cell's distinct points, each converted once (no growth afterwards, so references hold).
  std::vector<VertexId> ids;
  for (const FacetId f : cells_[cell].facets) {
    for (const Corner& corner : facets_[f].corners) ids.push_back(corner.vertex);
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<geometry::ExactPoint> points;
  points.reserve(ids.size());
  for (const VertexId v : ids) points.push_back(registry_->exact_homogeneous(v));
  const auto exact = [&](VertexId v) -> const geometry::ExactPoint& {
    return points[static_cast<std::size_t>(std::lower_bound(ids.begin(), ids.end(), v) - ids.begin())];
  };
  struct Term {
    mpz_class numerator, denominator;
  };
  std::vector<Term> terms;
  for (const FacetId f : cells_[cell].facets) {
    const Facet& facet = facets_[f];
    const auto& corners = facet.corners;
    for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
      const geometry::ExactPoint& a = exact(corners[0].vertex);
      const geometry::ExactPoint& b = exact(corners[i].vertex);
      const geometry::ExactPoint& c = exact(corners[i + 1].vertex);
      Term t;
      t.numerator = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
      if (facet.back != cell) t.numerator = -t.numerator;  // stored order is outward for the back cell
      t.denominator = a[3] * b[3] * c[3];
      terms.push_back(std::move(t));
    }
  }
  constexpr mp_bitcnt_t kBits = 2048;
  mpf_class sum(0, kBits), magnitude(0, kBits);
  for (const Term& t : terms) {
    mpf_class term(t.numerator, kBits);
    term /= mpf_class(t.denominator, kBits);
    sum += term;
    magnitude += abs(term);
  }
  mpf_class margin(magnitude, kBits);
  mpf_div_2exp(margin.get_mpf_t(), margin.get_mpf_t(), 1900);
  if (abs(sum) > margin) return sum.get_d();
  mpq_class rational = 0;
  for (const Term& t : terms) rational += mpq_class(t.numerator, t.denominator);  // canonicalised
  return rational.get_d();
}

std::string CellComplex::validate() const {
  const auto fail = [](const std::string& what, std::int64_t id) { return what + " " + std::to_string(id); };
  const TetAdjacency& adj = mesh_->adjacency();
  for (FacetId f = 0; f < static_cast<FacetId>(facets_.size()); ++f) {
    const Facet& facet = facets_[f];
    const auto& corners = facet.corners;
    const std::size_t n = corners.size();
    if (n < 3) return fail("fewer than three corners: facet", f);
    for (std::size_t i = 0; i < n; ++i) {
      const VertexId u = corners[i].vertex, v = corners[(i + 1) % n].vertex;
      if (registry_->side(u, facet.plane) != 0) return fail("a corner off its plane: facet", f);
      const Edge& edge = edges_[corners[i].edge];
      if (!((edge.a == u && edge.b == v) || (edge.a == v && edge.b == u))) return fail("corner and edge disagree: facet", f);
      if (std::find(edge.facets.begin(), edge.facets.end(), f) == edge.facets.end()) {
        return fail("an edge does not list its facet", f);
      }
      for (std::size_t j = i + 1; j < n; ++j) {
        if (corners[j].vertex == u) return fail("a repeated corner: facet", f);
      }
    }
    if (facet.covered()) {
      if (facet.covering >= static_cast<std::int32_t>(inserted_.size())) return fail("covered by an unknown triangle: facet", f);
      const InsertedTriangle& t = inserted_[facet.covering];
      for (const Corner& corner : corners) {
        if (registry_->side(corner.vertex, t.plane.id) != 0) return fail("covered but off its triangle's plane: facet", f);
        for (const OrientedPlane& wall : t.walls) {
          if (registry_->side(corner.vertex, wall.id) * wall.sign < 0) return fail("covered but outside its triangle: facet", f);
        }
      }
    }
    for (const Side s : {facet.front, facet.back}) {
      if (is_cell(s)) {
        const auto& list = cells_[s].facets;
        if (std::find(list.begin(), list.end(), f) == list.end()) return fail("missing from its cell's list: facet", f);
        if (facet.mesh_face < 0 && cells_[s].tet != tet_of(facet.front == s ? facet.back : facet.front)) {
          return fail("an interior facet between two tets: facet", f);
        }
      } else if (is_unrefined(s)) {
        const Index tet = unrefined_tet(s);
        if (refined(tet)) return fail("refers to a refined tet by its marker: facet", f);
        if (facet.mesh_face < 0) return fail("an unrefined tet on an interior facet: facet", f);
        bool on_tet = false;
        for (int k = 0; k < 4; ++k) on_tet = on_tet || adj.tet_faces(tet, k) == facet.mesh_face;
        if (!on_tet) return fail("an unrefined tet that does not have the facet's face: facet", f);
      } else if (facet.mesh_face < 0 || adj.tets_of_face(facet.mesh_face).size() != 1) {
        return fail("outside on a facet that is not on the mesh boundary: facet", f);
      }
    }
  }
  for (EdgeId e = 0; e < static_cast<EdgeId>(edges_.size()); ++e) {
    const Edge& edge = edges_[e];
    if (edge.a == edge.b) return fail("a zero-length edge", e);
    for (const PlaneId p : edge.line) {
      if (registry_->side(edge.a, p) != 0 || registry_->side(edge.b, p) != 0) return fail("an edge off its line", e);
    }
    for (const FacetId f : edge.facets) {
      bool used = false;
      for (const Corner& corner : facets_[f].corners) used = used || corner.edge == e;
      if (!used) return fail("an edge lists a facet that does not use it: edge", e);
    }
  }
  {
    // One record per segment: two records for one segment would let a point inserted on one miss
    // the facets of the other (a T-junction).
    std::vector<std::pair<VertexId, VertexId>> segments;
    for (const Edge& edge : edges_) segments.emplace_back(std::min(edge.a, edge.b), std::max(edge.a, edge.b));
    std::sort(segments.begin(), segments.end());
    if (std::adjacent_find(segments.begin(), segments.end()) != segments.end()) return "two records for one edge";
  }
  {
    // No point is registered twice: candidates are pairs whose rounded positions are close, and a
    // pair is the same point when one lies on all three planes of the other.
    std::vector<VertexId> order;
    for (const Edge& edge : edges_) order.push_back(edge.a);
    std::sort(order.begin(), order.end());
    order.erase(std::unique(order.begin(), order.end()), order.end());
    std::sort(order.begin(), order.end(), [&](VertexId u, VertexId v) {
      return registry_->position(u)[0] < registry_->position(v)[0];
    });
    constexpr double kNear = 1e-9;  // far above rounding, far below any feature of a test mesh
    for (std::size_t i = 0; i < order.size(); ++i) {
      const Vec3& p = registry_->position(order[i]);
      for (std::size_t j = i + 1; j < order.size() && registry_->position(order[j])[0] - p[0] <= kNear; ++j) {
        if ((registry_->position(order[j]) - p).norm() > kNear) continue;
        bool same = true;
        for (const PlaneId plane : registry_->vertex(order[j]).planes) same = same && registry_->side(order[i], plane) == 0;
        if (same) return fail("a point registered twice: vertex", order[i]);
      }
    }
  }
  for (CellId c = 0; c < static_cast<CellId>(cells_.size()); ++c) {
    const Cell& cell = cells_[c];
    std::vector<std::pair<VertexId, VertexId>> directed;
    std::vector<VertexId> vertices;
    for (const FacetId f : cell.facets) {
      const Facet& facet = facets_[f];
      if (facet.front != c && facet.back != c) return fail("lists a facet that does not bound it: cell", c);
      const std::size_t n = facet.corners.size();
      for (std::size_t i = 0; i < n; ++i) {
        VertexId u = facet.corners[i].vertex, v = facet.corners[(i + 1) % n].vertex;
        if (facet.front == c) std::swap(u, v);
        directed.emplace_back(u, v);
        vertices.push_back(u);
      }
    }
    std::sort(directed.begin(), directed.end());
    for (std::size_t i = 0; i < directed.size(); ++i) {
      if (i > 0 && directed[i] == directed[i - 1]) return fail("uses an edge twice in one direction: cell", c);
      if (!std::binary_search(directed.begin(), directed.end(), std::make_pair(directed[i].second, directed[i].first))) {
        return fail("is not closed: cell", c);
      }
    }
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    for (const FacetId f : cell.facets) {
      const int inner = facets_[f].back == c ? -1 : 1;
      for (const VertexId v : vertices) {
        if (registry_->side(v, facets_[f].plane) * inner < 0) return fail("is not convex: cell", c);
      }
    }
    const Vec3 origin = registry_->position(vertices.front());
    if (!(cell_volume6(c, origin) > 0)) return fail("has no volume: cell", c);
    bool listed = false;
    for (CellId k = first_cell_[cell.tet]; k >= 0 && !listed; k = cells_[k].next_in_tet) listed = k == c;
    if (!listed) return fail("missing from its tet's list: cell", c);
  }
  return {};
}

}  // namespace tetcut::cells
