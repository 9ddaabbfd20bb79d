#include "components/material_components.hpp"

#include <tbb/parallel_for.h>

#include <numeric>

#include "util/union_find.hpp"

namespace tetcut::components {
namespace {

// Below this many tets the work is done on the calling thread.
constexpr std::size_t kParallelFrom = 512;

using cells::CellComplex;
using cells::CellId;

// Components of one tet. Writes its cells' entries only, so tets can run in parallel.
void tet_components(const CellComplex& complex, Index tet, MaterialComponents* result) {
  if (!complex.refined(tet)) {
    result->count[tet] = complex.tet_material(tet) ? 1 : 0;
    return;
  }
  const auto& cells = complex.cells();
  const auto& facets = complex.facets();
  std::vector<CellId> members;
  for (CellId c = complex.first_cell(tet); c >= 0; c = cells[c].next_in_tet) members.push_back(c);
  // Disjoint sets over the tet's cells, by their local index (which cell_component holds meanwhile).
  UnionFind classes(members.size());
  for (std::size_t i = 0; i < members.size(); ++i) result->cell_component[members[i]] = static_cast<std::int32_t>(i);
  for (const CellId c : members) {
    if (!cells[c].material) continue;
    for (const cells::FacetId f : cells[c].facets) {
      const cells::Facet& facet = facets[f];
      if (facet.covered() || facet.front != c) continue;  // each facet once, from its front cell
      const cells::Side other = facet.back;
      if (!cells::is_cell(other) || cells[other].tet != tet || !cells[other].material) continue;
      classes.join(result->cell_component[c], result->cell_component[other]);
    }
  }
  const Vec3 origin = complex.mesh().rest().row(complex.mesh().tets()(tet, 0)).transpose();
  std::vector<std::int32_t> label(members.size(), -1);
  std::int32_t count = 0;
  for (std::size_t i = 0; i < members.size(); ++i) {
    const CellId c = members[i];
    if (!cells[c].material) {
      // Only material volumes are asked for (copies, pieces); a void cell's would cost as much.
      result->cell_volume6[c] = 0;
      result->cell_component[c] = -1;
      continue;
    }
    result->cell_volume6[c] = complex.cell_volume6(c, origin);
    const Index root = classes.find(static_cast<Index>(i));
    if (label[root] < 0) label[root] = count++;
    result->cell_component[c] = label[root];
  }
  result->count[tet] = count;
}

}  // namespace

MaterialComponents find_components(const CellComplex& complex) {
  MaterialComponents result;
  const Index num_tets = complex.mesh().num_tets();
  result.count.assign(static_cast<std::size_t>(num_tets), 0);
  result.cell_component.assign(complex.cells().size(), -1);
  result.cell_volume6.assign(complex.cells().size(), 0.0);
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_tets, 256), [&](const auto& range) {
    for (Index t = range.begin(); t != range.end(); ++t) tet_components(complex, t, &result);
  });
  return result;
}

void update_components(const CellComplex& complex, std::span<const Index> tets, MaterialComponents* result) {
  result->count.resize(static_cast<std::size_t>(complex.mesh().num_tets()), 0);
  result->cell_component.resize(complex.cells().size(), -1);
  result->cell_volume6.resize(complex.cells().size(), 0.0);
  // A batch touches tens of tets: waking threads would cost more than the work.
  if (tets.size() < kParallelFrom) {
    for (const Index t : tets) tet_components(complex, t, result);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tets.size(), 16), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) tet_components(complex, tets[i], result);
  });
}

}  // namespace tetcut::components
