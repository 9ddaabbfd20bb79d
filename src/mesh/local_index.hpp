#pragma once
// A node's place in a tet's row, for the stages that walk from a node to its tets (cells,
// connectivity).

#include <tetcut/types.hpp>

namespace tetcut {

/// Local index (0-3) of `node` in row `tet` of `tets` (#T by 4), or -1 when the tet does not use it.
inline int local_index(const Tets& tets, Index tet, Index node) {
  for (int k = 0; k < 4; ++k) {
    if (tets(tet, k) == node) return k;
  }
  return -1;
}

}  // namespace tetcut
