// Inserting one triangle (paper 3.2): into each cell it may cut, a split by its plane and the
// covering of the section's part inside its walls; or the covering of facets already on its plane.

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

}  // namespace tetcut::cells
