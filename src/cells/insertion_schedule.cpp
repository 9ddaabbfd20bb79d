// The parallel insertion of a batch: tets grouped into coloured blocks so that blocks of one
// colour can be cut at once (the argument is in cell_complex.hpp, at insert_triangles).

#include "cells/cell_complex.hpp"

#include "mesh/local_index.hpp"
#include "util/broken.hpp"

#include <tetcut/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace tetcut::cells {

using geometry::Plane;
using registry::OrientedPlane;

void CellComplex::insert_triangles(std::span<const PreparedTriangle> triangles, std::span<const std::vector<Index>> tets,
                                   std::vector<Index>* touched) {
  if (triangles.size() != tets.size()) throw Error(ErrorKind::kInvalidArgument, "insert_triangles: one list of tets per triangle");
  const auto first_stamp = static_cast<std::int32_t>(inserted_.size());
  for (const PreparedTriangle& t : triangles) inserted_.push_back({t.plane, t.walls, t.cut_id});

  // Blocks of side 5 L, where L bounds every edge (see the header for why 5).
  const Points& x = mesh_->rest();
  const Tets& elements = mesh_->tets();
  if (longest_edge_ < 0) {
    longest_edge_ = 0;
    for (Index t = 0; t < mesh_->num_tets(); ++t) {
      for (const auto& e : kTetEdges) {
        longest_edge_ = std::max(longest_edge_, (x.row(elements(t, e[0])) - x.row(elements(t, e[1]))).norm());
      }
    }
  }
  // A hair over 5 L: L is a computed norm, perhaps a rounding under the longest edge, and the
  // header's argument holds for blocks of at least 5 true L.
  constexpr double kBlockSideSlack = 1 + 1e-9;
  const double side = 5 * longest_edge_ * kBlockSideSlack;
  const Vec3 origin = x.colwise().minCoeff().transpose();
  struct Pair {
    std::int32_t triangle;
    Index tet;
  };
  std::unordered_map<std::uint64_t, std::size_t> block_of_key;
  std::vector<std::vector<Pair>> blocks;
  std::array<std::vector<std::size_t>, 8> blocks_of_colour;
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (const Index tet : tets[i]) {
      Vec3 centroid = Vec3::Zero();
      for (int k = 0; k < 4; ++k) centroid += x.row(elements(tet, k)).transpose();
      std::uint64_t key = 0;
      int colour = 0;
      for (int k = 0; k < 3; ++k) {
        const auto b = static_cast<std::uint64_t>(std::floor((centroid[k] / 4 - origin[k]) / side));
        key = (key << 21) | (b & 0x1fffff);
        colour |= static_cast<int>(b & 1) << k;
      }
      const auto [it, added] = block_of_key.try_emplace(key, blocks.size());
      if (added) {
        blocks.emplace_back();
        blocks_of_colour[colour].push_back(it->second);
      }
      blocks[it->second].push_back({static_cast<std::int32_t>(i), tet});
    }
  }

  // Each block takes its tets one at a time, inserting each one's triangles in order: a tet's
  // cells stay in cache while it is cut (a third faster than taking each triangle across the
  // block's tets). The order in which neighbouring tets insert a triangle does not matter (see
  // the header), and the cells of a tet depend only on the order of its own triangles.
  tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t b) {
    std::stable_sort(blocks[b].begin(), blocks[b].end(), [](const Pair& p, const Pair& q) { return p.tet < q.tet; });
  });
  // The blocks of one colour at once.
  std::vector<std::vector<Index>> block_touched(blocks.size());
  for (const std::vector<std::size_t>& colour : blocks_of_colour) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, colour.size(), 1), [&](const auto& range) {
      std::vector<CellId> scratch;
      registry::IntersectionRegistry::SideMemo& memo = side_memos_.local();
      for (std::size_t b = range.begin(); b != range.end(); ++b) {
        for (const Pair& pair : blocks[colour[b]]) {
          Insertion in = begin_insertion(triangles[pair.triangle], first_stamp + pair.triangle, &block_touched[colour[b]], true, &memo);
          insert_into_tet(in, pair.tet, -1, &scratch);
        }
      }
    });
  }
  if (touched != nullptr) {
    for (const std::vector<Index>& list : block_touched) touched->insert(touched->end(), list.begin(), list.end());
  }
}

}  // namespace tetcut::cells
