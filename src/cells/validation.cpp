// The complex's invariants, checked exactly (tests and debugging; see validate()).

#include "cells/cell_complex.hpp"

#include "mesh/local_index.hpp"
#include "util/broken.hpp"

#include <tetcut/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tetcut::cells {

using geometry::Plane;
using registry::OrientedPlane;

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
