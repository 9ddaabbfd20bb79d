// Splitting cells and facets by a plane (paper 3.2): points where the plane crosses edges are put
// into every facet around the edge, so that the complex stays conforming.

#include "cells/cell_complex.hpp"

#include "mesh/local_index.hpp"
#include "cells/sides_seen.hpp"
#include "util/broken.hpp"

#include <tetcut/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tetcut::cells {

using geometry::Plane;
using registry::OrientedPlane;

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

}  // namespace tetcut::cells
