#pragma once
// Disjoint sets over 0 .. n-1 with path halving; a join keeps the smaller id as the root, so roots
// (and anything numbered by first root) do not depend on the order of joins.

#include <tetcut/types.hpp>

#include <algorithm>
#include <numeric>
#include <vector>

namespace tetcut {

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), Index{0}); }
  Index find(Index x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void join(Index a, Index b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<Index> parent_;
};

}  // namespace tetcut
