#pragma once
// Duplication and connectivity (paper, section 3.4), kept up to date batch by batch.
//
// Every material component of a tet has its own copy of the tet, with the tet's rest positions,
// so no copy is smaller than the original element. Two copies of neighbouring tets are joined when
// their shared face holds a common uncovered polygon (a facet of the complex with their components
// on its two sides), and joined copies share the nodes of that face (the virtual node collapse).
//
// Ids are stable: a cut only ever splits material, so each new component lies in one old copy.
// The first new component in an old copy keeps its id, the others become new copies appended
// after all existing ones; likewise the first class of node slots keeps a node's id and the others
// become new nodes. Cells carry their copy as their label in the cell complex.

#include <array>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "cells/cell_complex.hpp"
#include "components/material_components.hpp"

namespace tetcut::connectivity {

class TetCopies {
 public:
  /// One copy per input tet (copy t is tet t) over the input nodes, and each tet of `complex`
  /// labelled with it. No tet of `complex` may be refined yet.
  TetCopies(const TetMesh& mesh, cells::CellComplex& complex);

  /// Replaces every copy and node: one copy per material component of every tet (none for a tet
  /// without material), numbered densely in tet order, and one node per class of node slots joined
  /// across faces, numbered in order of first use by the copies; labels the cells. For an
  /// embedding, after material was removed. O(T + refined cells + faces).
  void rebuild(cells::CellComplex& complex, const components::MaterialComponents& components);

  /// What a batch changed, for a simulator to carry its state over.
  struct Update {
    /// Nodes from this id on are new; new_node_source[i] is the node (an id from before the
    /// batch) that node first_new_node + i was split from.
    Index first_new_node = 0;
    std::vector<Index> new_node_source;
    /// Copies from this id on are new; new_copy_source[i] is the copy they were split from.
    Index first_new_copy = 0;
    std::vector<Index> new_copy_source;
    /// Copies that existed before whose nodes changed, ascending.
    std::vector<Index> changed_copies;
  };

  /// After the cells of the `touched` tets changed and their components were recomputed: splits
  /// the copies whose material fell apart, relabels those tets' cells, and re-collapses the nodes
  /// of the touched tets. O(tets around the touched tets' nodes and their facets on faces).
  Update update(cells::CellComplex& complex, const components::MaterialComponents& components,
                std::span<const Index> touched);

  Index num_copies() const { return static_cast<Index>(copy_tet_.size()); }
  Index num_nodes() const { return static_cast<Index>(node_parent_.size()); }
  const std::vector<Index>& copy_tet() const { return copy_tet_; }
  /// Per copy, its four nodes in the input tet's order.
  const std::vector<std::array<Index, 4>>& copy_nodes() const { return copy_nodes_; }
  /// Per node, the input node it copies.
  const std::vector<Index>& node_parent() const { return node_parent_; }
  /// The copy holding component `component` of `tet`.
  Index copy_of(Index tet, std::int32_t component) const;
  /// The copy on side `s` of a facet (a cell, or an unrefined tet); -1 for the outside.
  Index copy_on(const cells::CellComplex& complex, cells::Side s) const;
  /// Copies of a tet, by component (none when it holds no material).
  std::span<const Index> copies_of(Index tet) const;

 private:
  void recollapse(const cells::CellComplex& complex, Index node, Update* update);

  const TetMesh* mesh_;
  std::vector<Index> copy_tet_;
  std::vector<std::array<Index, 4>> copy_nodes_;
  std::vector<Index> node_parent_;
  // Copies by component: a tet with one copy keeps it in single_copy_; a tet with more has them
  // all in several_copies_; a tet with none has -1.
  std::vector<Index> single_copy_;
  std::unordered_map<Index, std::vector<Index>> several_copies_;
  // Tets around each input node (CSR), fixed.
  std::vector<Index> node_tets_begin_, node_tets_;
};

/// Pieces: classes of copies joined through faces, by volume, largest first. O(tets + facets on
/// faces).
struct Pieces {
  std::vector<Index> copy_piece;       ///< per copy
  std::vector<double> copy_volume;     ///< per copy: the material volume it holds
  std::vector<double> piece_volume;    ///< per piece
};
Pieces find_pieces(const cells::CellComplex& complex, const components::MaterialComponents& components,
                   const TetCopies& copies);

}  // namespace tetcut::connectivity
