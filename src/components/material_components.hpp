#pragma once
// Material components of each tet (paper, section 3.3): the cells of a tet that hold material,
// joined through the uncovered facets between them. Each component will become one copy of the tet.
// Convex cells make this a union-find instead of the paper's boundary tracking: a component is a
// union of cells, so a component floating inside the tet, or one bounded by a partial cut that does
// not separate it, needs no special case.

#include <cstdint>
#include <span>
#include <vector>

#include "cells/cell_complex.hpp"

namespace tetcut::components {

struct MaterialComponents {
  /// Per cell of the complex: its component's index within its tet, or -1 for a cell without
  /// material.
  std::vector<std::int32_t> cell_component;
  /// Per cell holding material: six times its volume, from rounded positions relative to its tet's
  /// first node (see CellComplex::cell_volume6), so that the cells of a tet add up to the tet;
  /// zero for a cell without material.
  std::vector<double> cell_volume6;
  /// Per tet: number of components. An unrefined tet has one when it holds material, else none.
  std::vector<std::int32_t> count;
};

/// Components of every tet, computed in parallel over tets. O(size of the refined cells + tets).
MaterialComponents find_components(const cells::CellComplex& complex);

/// Recomputes the components of the given tets only (their cells may have changed); the other
/// tets' entries are kept. O(size of the given tets' cells).
void update_components(const cells::CellComplex& complex, std::span<const Index> tets, MaterialComponents* result);

}  // namespace tetcut::components
