#pragma once
// The material surface (paper, section 4): the polygons incident on material on exactly one side
// — both sides of every covered facet, and facets between material and the outside or void —
// triangulated and oriented outward, each vertex embedded in the tet copy whose material it bounds.
//
// The complex is conforming, so the surface needs no T-junction repair: surface vertices are the
// complex's points, keyed by the point and by the copy's nodes that carry weight there. Two
// polygons share a vertex exactly when the vertex moves identically in both (same point, same
// nodes with non-zero weights), which keeps the surface closed and consistently oriented.

#include <tetcut/cutter.hpp>

#include <span>
#include <vector>

#include "cells/cell_complex.hpp"
#include "connectivity/tet_copies.hpp"

namespace tetcut::surface {

MaterialSurface extract_material_surface(const cells::CellComplex& complex, const connectivity::TetCopies& copies);

/// Triangulates a convex polygon whose consecutive corners may be collinear, with no zero-area
/// triangle: ear clipping at strict corners (where the boundary turns). `strict[i]` says whether
/// corner i is one. Emits corner index triples in the polygon's orientation, or reversed.
void triangulate_convex_polygon(std::vector<std::uint8_t> strict, bool reverse, std::vector<std::array<int, 3>>* triangles);

/// The same for a facet, deciding its strict corners exactly through the lines of its edges.
void triangulate_facet(const cells::CellComplex& complex, const cells::Facet& facet, bool reverse,
                       std::vector<std::array<int, 3>>* triangles);

}  // namespace tetcut::surface
