#pragma once
// Duplication and connectivity (paper, section 3.4). Every material component of a tet gets its
// own copy of the tet, with the tet's rest positions, so no copy is smaller than the original
// element. Two copies of neighbouring tets are joined when their shared face holds a common
// uncovered polygon (a facet of the complex with their components on its two sides), and joined
// copies share the nodes of that face (the virtual node collapse). Pieces are the classes of copies
// joined through faces.

#include <cstdint>
#include <vector>

#include "cells/cell_complex.hpp"
#include "components/material_components.hpp"

namespace tetcut::connectivity {

struct TetCopies {
  /// Per input tet: id of its first copy (component 0), or -1 when it holds no material. First
  /// copies are numbered in tet order, so when every tet holds material tet t's first copy is t.
  std::vector<Index> first_copy;
  /// Per input tet: id of its second copy; further copies follow it. Numbered after all first copies.
  std::vector<Index> extra_copies;
  std::vector<Index> copy_tet;                ///< per copy: the input tet
  std::vector<std::int32_t> copy_component;   ///< per copy: the component within its tet
  Tets copy_nodes;                            ///< |C| x 4 node ids, in the input tet's order
  /// Per node: the input node it copies. Input node n keeps id n (standing for its copy in the
  /// first copy that uses it); duplicates follow.
  std::vector<Index> node_parent;
  std::vector<Index> copy_piece;              ///< per copy: piece id, pieces by volume, largest first
  std::vector<double> copy_volume;            ///< per copy: the material volume it holds
  std::vector<double> piece_volume;           ///< per piece, largest first

  Index num_copies() const { return static_cast<Index>(copy_tet.size()); }
  Index copy_of(Index tet, std::int32_t component) const {
    return component == 0 ? first_copy[tet] : extra_copies[tet] + component - 1;
  }
};

/// Builds the copies, joins and nodes. O(tets + faces + facets on faces + nodes), near-linear
/// union-find.
TetCopies build_copies(const cells::CellComplex& complex, const components::MaterialComponents& components);

}  // namespace tetcut::connectivity
