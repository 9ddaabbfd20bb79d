#pragma once
// Which parts of a cut mesh are material, for embedding: the inside of a closed surface (its
// winding number, carried exactly across the cut polygons), or one piece.

#include <cstdint>
#include <vector>

#include "cells/cell_complex.hpp"

namespace tetcut::embedding {

/// Winding numbers of the cut surface on every side of the complex, starting from zero outside the
/// mesh and changing by each covered facet's winding jump: per cell, and per tet (used for
/// unrefined tets). Throws Error(kInvalidInput) when two paths disagree, which happens only when
/// the cut surface is not closed inside the mesh (it leaves through the mesh boundary).
/// O(cells + facets + tets).
struct Windings {
  std::vector<std::int32_t> cell;
  std::vector<std::int32_t> tet;
};
Windings winding_numbers(const cells::CellComplex& complex);

/// Keeps the material where the winding number is not zero; returns how many tets keep some.
Index keep_nonzero_winding(cells::CellComplex& complex, const Windings& windings);

/// Uncovers the covered facets that have material on both sides and a non-zero winding jump
/// (where a self-intersecting surface passes through its own inside), so the union of what the
/// surface encloses is one material. Facets where two surface parts lie face to face with opposite
/// orientation (jump zero) stay cuts. Returns the number uncovered.
Index join_overlaps(cells::CellComplex& complex);

/// The cell holding input point x, or unrefined_side(tet) when x is in an unrefined tet, among
/// `tets` (candidates from a box query). Throws Error(kInvalidInput) when x is in no tet, or on the
/// plane of a covered facet of its cell (it would be on the cut surface).
cells::Side side_holding(const cells::CellComplex& complex, std::span<const Index> tets, const Vec3& x);

}  // namespace tetcut::embedding
