#include "connectivity/tet_copies.hpp"

#include <algorithm>
#include <numeric>
#include <span>

namespace tetcut::connectivity {
namespace {

using cells::CellComplex;
using cells::Side;

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
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);  // the smaller id stays the root
  }

 private:
  std::vector<Index> parent_;
};

int local_index(const Tets& tets, Index tet, Index node) {
  for (int k = 0; k < 4; ++k) {
    if (tets(tet, k) == node) return k;
  }
  return -1;
}

}  // namespace

TetCopies build_copies(const CellComplex& complex, const components::MaterialComponents& components) {
  const TetMesh& mesh = complex.mesh();
  const Tets& tets = mesh.tets();
  const TetAdjacency& adj = mesh.adjacency();
  const Index num_tets = mesh.num_tets();
  TetCopies result;

  // Copies: first copies in tet order, then the others.
  result.first_copy.assign(static_cast<std::size_t>(num_tets), -1);
  result.extra_copies.assign(static_cast<std::size_t>(num_tets), -1);
  Index count = 0;
  for (Index t = 0; t < num_tets; ++t) {
    if (components.count[t] > 0) result.first_copy[t] = count++;
  }
  for (Index t = 0; t < num_tets; ++t) {
    result.extra_copies[t] = count;
    count += std::max(0, components.count[t] - 1);
  }
  result.copy_tet.resize(static_cast<std::size_t>(count));
  result.copy_component.resize(static_cast<std::size_t>(count));
  result.copy_volume.assign(static_cast<std::size_t>(count), 0.0);
  for (Index t = 0; t < num_tets; ++t) {
    for (std::int32_t k = 0; k < components.count[t]; ++k) {
      const Index c = result.copy_of(t, k);
      result.copy_tet[c] = t;
      result.copy_component[c] = k;
    }
  }

  // Material volumes: a whole tet, or the sum of its component's cells.
  const auto& cells = complex.cells();
  const Points& rest = mesh.rest();
  for (Index t = 0; t < num_tets; ++t) {
    if (components.count[t] == 0) continue;
    if (!complex.refined(t)) {
      result.copy_volume[result.first_copy[t]] =
          signed_volume(rest.row(tets(t, 0)), rest.row(tets(t, 1)), rest.row(tets(t, 2)), rest.row(tets(t, 3)));
      continue;
    }
    for (cells::CellId c = complex.first_cell(t); c >= 0; c = cells[c].next_in_tet) {
      const std::int32_t k = components.cell_component[c];
      if (k >= 0) result.copy_volume[result.copy_of(t, k)] += components.cell_volume6[c] / 6;
    }
  }

  // Joins: copies on the two sides of an uncovered facet on a mesh face (or of a whole face between
  // two unrefined tets) share that face's nodes.
  UnionFind pieces(static_cast<std::size_t>(count));
  UnionFind slots(static_cast<std::size_t>(count) * 4);
  const auto copy_on = [&](Side s) -> Index {
    if (cells::is_cell(s)) return result.copy_of(cells[s].tet, components.cell_component[s]);
    return result.first_copy[cells::unrefined_tet(s)];
  };
  const auto join = [&](Index a, Index b, Index face) {
    pieces.join(a, b);
    const Index ta = result.copy_tet[a], tb = result.copy_tet[b];
    for (int k = 0; k < 3; ++k) {
      const Index node = adj.faces(face, k);
      slots.join(4 * a + local_index(tets, ta, node), 4 * b + local_index(tets, tb, node));
    }
  };
  for (Index face = 0; face < adj.num_faces(); ++face) {
    const std::span<const Index> around = adj.tets_of_face(face);
    if (around.size() != 2) continue;
    if (complex.first_facet_on_face(face) < 0) {
      // No facets: both tets are unrefined, and the face is whole.
      if (complex.tet_material(around[0]) && complex.tet_material(around[1])) {
        join(result.first_copy[around[0]], result.first_copy[around[1]], face);
      }
      continue;
    }
    for (cells::FacetId f = complex.first_facet_on_face(face); f >= 0; f = complex.facets()[f].next_on_mesh_face) {
      const cells::Facet& facet = complex.facets()[f];
      if (facet.covered() || !complex.side_is_material(facet.front) || !complex.side_is_material(facet.back)) continue;
      join(copy_on(facet.front), copy_on(facet.back), face);
    }
  }

  // Nodes. Input node n keeps id n in the first copy (by id) that uses it; every other class of
  // slots of n becomes a new node, numbered in order of first use.
  const Index num_nodes = mesh.num_nodes();
  result.node_parent.resize(static_cast<std::size_t>(num_nodes));
  std::iota(result.node_parent.begin(), result.node_parent.end(), Index{0});
  std::vector<std::uint8_t> taken(static_cast<std::size_t>(num_nodes), 0);
  std::vector<Index> class_node(static_cast<std::size_t>(count) * 4, -1);
  result.copy_nodes.resize(count, 4);
  for (Index c = 0; c < count; ++c) {
    for (int k = 0; k < 4; ++k) {
      const Index root = slots.find(4 * c + k);
      if (class_node[root] < 0) {
        const Index node = tets(result.copy_tet[c], k);
        if (!taken[node]) {
          taken[node] = 1;
          class_node[root] = node;
        } else {
          class_node[root] = static_cast<Index>(result.node_parent.size());
          result.node_parent.push_back(node);
        }
      }
      result.copy_nodes(c, k) = class_node[root];
    }
  }

  // Pieces by volume, largest first; ties keep the order of their lowest copy.
  std::vector<Index> root_piece(static_cast<std::size_t>(count), -1);
  std::vector<double> volume;
  std::vector<Index> piece_of_copy(static_cast<std::size_t>(count));
  for (Index c = 0; c < count; ++c) {
    const Index root = pieces.find(c);
    if (root_piece[root] < 0) {
      root_piece[root] = static_cast<Index>(volume.size());
      volume.push_back(0.0);
    }
    piece_of_copy[c] = root_piece[root];
    volume[piece_of_copy[c]] += result.copy_volume[c];
  }
  std::vector<Index> order(volume.size());
  std::iota(order.begin(), order.end(), Index{0});
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) { return volume[a] > volume[b]; });
  std::vector<Index> rank(volume.size());
  result.piece_volume.resize(volume.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<Index>(i);
    result.piece_volume[i] = volume[order[i]];
  }
  result.copy_piece.resize(static_cast<std::size_t>(count));
  for (Index c = 0; c < count; ++c) result.copy_piece[c] = rank[piece_of_copy[c]];
  return result;
}

}  // namespace tetcut::connectivity
