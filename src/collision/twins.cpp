// Twins by rest position (see twins.hpp): a hash grid of rest positions and a union-find.

#include "collision/twins.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "util/hash.hpp"
#include "util/union_find.hpp"

namespace tetcut::collision {

std::vector<Index> twin_ids(const Points& rest, const Points& now, double rest_tolerance, double tolerance) {
  const double cell = 4 * rest_tolerance;
  using Key = std::array<std::int64_t, 3>;
  const auto key_of = [&](Index v) {
    Key k;
    for (int i = 0; i < 3; ++i) k[static_cast<std::size_t>(i)] = static_cast<std::int64_t>(std::floor(rest(v, i) / cell));
    return k;
  };
  // Vertices by cell: a chain through each cell's vertices.
  std::unordered_map<Key, Index, WordsHash> first;
  first.reserve(static_cast<std::size_t>(rest.rows()));
  std::vector<Index> next(static_cast<std::size_t>(rest.rows()), -1);
  UnionFind same(static_cast<std::size_t>(rest.rows()));
  for (Index v = 0; v < rest.rows(); ++v) {
    const Key k = key_of(v);
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = first.find(Key{k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == first.end()) continue;
          for (Index u = it->second; u >= 0; u = next[static_cast<std::size_t>(u)]) {
            if ((rest.row(u) - rest.row(v)).cwiseAbs().maxCoeff() <= rest_tolerance &&
                (now.row(u) - now.row(v)).cwiseAbs().maxCoeff() <= tolerance) {
              same.join(u, v);
            }
          }
        }
      }
    }
    const auto [it, inserted] = first.try_emplace(k, v);
    if (!inserted) {
      next[static_cast<std::size_t>(v)] = it->second;
      it->second = v;
    }
  }
  std::vector<Index> out(static_cast<std::size_t>(rest.rows()));
  for (Index v = 0; v < rest.rows(); ++v) out[static_cast<std::size_t>(v)] = same.find(v);
  return out;
}

}  // namespace tetcut::collision
