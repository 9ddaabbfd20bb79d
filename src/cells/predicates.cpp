// Exact predicates on cells and facets against a plane and against the triangle being inserted:
// which side, whether a section overlaps the triangle, whether a tet may be cut at all.

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

}  // namespace tetcut::cells
