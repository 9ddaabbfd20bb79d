#include "connectivity/tet_copies.hpp"

#include "mesh/local_index.hpp"
#include "util/broken.hpp"
#include "util/union_find.hpp"

#include <algorithm>
#include <numeric>

namespace tetcut::connectivity {
namespace {

using cells::CellComplex;
using cells::Side;

// Calls join(copy_a, copy_b) for each pair of copies that face `face` joins: through each uncovered
// facet with material on both sides, or through the whole face between two unrefined tets.
template <typename Join>
void joins_across(const CellComplex& complex, const TetCopies& copies, Index face, Join&& join) {
  const auto around = complex.mesh().adjacency().tets_of_face(face);
  if (around.size() != 2) return;
  if (complex.first_facet_on_face(face) < 0) {
    if (complex.tet_material(around[0]) && complex.tet_material(around[1])) {
      join(copies.copy_of(around[0], 0), copies.copy_of(around[1], 0));
    }
    return;
  }
  for (cells::FacetId f = complex.first_facet_on_face(face); f >= 0; f = complex.facets()[f].next_on_mesh_face) {
    const cells::Facet& facet = complex.facets()[f];
    if (facet.covered() || !complex.side_is_material(facet.front) || !complex.side_is_material(facet.back)) continue;
    join(copies.copy_on(complex, facet.front), copies.copy_on(complex, facet.back));
  }
}

}  // namespace

TetCopies::TetCopies(const TetMesh& mesh, cells::CellComplex& complex) : mesh_(&mesh) {
  const Index num_tets = mesh.num_tets();
  copy_tet_.resize(static_cast<std::size_t>(num_tets));
  std::iota(copy_tet_.begin(), copy_tet_.end(), Index{0});
  single_copy_ = copy_tet_;
  copy_nodes_.resize(static_cast<std::size_t>(num_tets));
  for (Index t = 0; t < num_tets; ++t) {
    for (int k = 0; k < 4; ++k) copy_nodes_[t][k] = mesh.tets()(t, k);
    complex.set_tet_label(t, t);
  }
  node_parent_.resize(static_cast<std::size_t>(mesh.num_nodes()));
  std::iota(node_parent_.begin(), node_parent_.end(), Index{0});
  // Tets around each node, as a counting sort.
  node_tets_begin_.assign(static_cast<std::size_t>(mesh.num_nodes()) + 1, 0);
  for (Index t = 0; t < num_tets; ++t) {
    for (int k = 0; k < 4; ++k) ++node_tets_begin_[mesh.tets()(t, k) + 1];
  }
  for (std::size_t n = 0; n + 1 < node_tets_begin_.size(); ++n) node_tets_begin_[n + 1] += node_tets_begin_[n];
  node_tets_.resize(static_cast<std::size_t>(node_tets_begin_.back()));
  std::vector<Index> fill(node_tets_begin_.begin(), node_tets_begin_.end() - 1);
  for (Index t = 0; t < num_tets; ++t) {
    for (int k = 0; k < 4; ++k) node_tets_[fill[mesh.tets()(t, k)]++] = t;
  }
}

Index TetCopies::copy_of(Index tet, std::int32_t component) const {
  if (component == 0) return single_copy_[tet];
  return several_copies_.at(tet)[component];
}

std::span<const Index> TetCopies::copies_of(Index tet) const {
  const auto it = several_copies_.find(tet);
  if (it != several_copies_.end()) return it->second;
  if (single_copy_[tet] < 0) return {};
  return {&single_copy_[tet], 1};
}

Index TetCopies::copy_on(const CellComplex& complex, Side s) const {
  if (cells::is_cell(s)) return complex.cells()[s].label;
  if (cells::is_unrefined(s)) return single_copy_[cells::unrefined_tet(s)];
  return -1;
}

void TetCopies::rebuild(CellComplex& complex, const components::MaterialComponents& components) {
  const Index num_tets = mesh_->num_tets();
  const Tets& tets = mesh_->tets();
  copy_tet_.clear();
  copy_nodes_.clear();
  node_parent_.clear();
  several_copies_.clear();
  single_copy_.assign(static_cast<std::size_t>(num_tets), -1);
  for (Index t = 0; t < num_tets; ++t) {
    const std::int32_t count = components.count[t];
    if (count == 0) continue;
    const Index first = num_copies();
    for (std::int32_t k = 0; k < count; ++k) {
      copy_tet_.push_back(t);
      copy_nodes_.push_back({-1, -1, -1, -1});
    }
    single_copy_[t] = first;
    if (count > 1) {
      std::vector<Index> ids(static_cast<std::size_t>(count));
      std::iota(ids.begin(), ids.end(), first);
      several_copies_[t] = std::move(ids);
    }
    if (!complex.refined(t)) {
      complex.set_tet_label(t, first);
      continue;
    }
    for (cells::CellId c = complex.first_cell(t); c >= 0; c = complex.cells()[c].next_in_tet) {
      const std::int32_t k = components.cell_component[c];
      if (k >= 0) complex.set_cell_label(c, first + k);
    }
  }
  // Node slots (copy, local corner) joined across the faces that join copies.
  UnionFind slots(4 * copy_tet_.size());
  const TetAdjacency& adjacency = mesh_->adjacency();
  for (Index face = 0; face < adjacency.num_faces(); ++face) {
    joins_across(complex, *this, face, [&](Index a, Index b) {
      for (int k = 0; k < 3; ++k) {
        const Index node = adjacency.faces(face, k);
        slots.join(4 * a + local_index(tets, copy_tet_[a], node), 4 * b + local_index(tets, copy_tet_[b], node));
      }
    });
  }
  std::vector<Index> id_of_root(4 * copy_tet_.size(), -1);
  for (Index c = 0; c < num_copies(); ++c) {
    for (int k = 0; k < 4; ++k) {
      Index& id = id_of_root[slots.find(4 * c + k)];
      if (id < 0) {
        id = num_nodes();
        node_parent_.push_back(tets(copy_tet_[c], k));
      }
      copy_nodes_[c][k] = id;
    }
  }
}

TetCopies::Update TetCopies::update(CellComplex& complex, const components::MaterialComponents& components,
                                    std::span<const Index> touched) {
  Update update;
  update.first_new_node = num_nodes();
  update.first_new_copy = num_copies();

  // 1. Copies. Each new component lies in one old copy (cells keep their copy as label when
  //    split); the first component in it keeps the copy, the others get new ones.
  for (const Index tet : touched) {
    if (!complex.refined(tet)) continue;  // an unrefined tet keeps its one copy
    const std::int32_t count = components.count[tet];
    std::vector<Index> label_of(static_cast<std::size_t>(count), -1);
    for (cells::CellId c = complex.first_cell(tet); c >= 0; c = complex.cells()[c].next_in_tet) {
      const std::int32_t k = components.cell_component[c];
      if (k < 0) continue;
      Index& label = label_of[k];
      if (label < 0) label = complex.cells()[c].label;
      if (label != complex.cells()[c].label) broken("tet copies", "a component holds material of two copies");
    }
    std::vector<Index> copy_of_component(static_cast<std::size_t>(count));
    std::vector<Index> kept;
    for (std::int32_t k = 0; k < count; ++k) {
      const Index old = label_of[k];
      if (std::find(kept.begin(), kept.end(), old) == kept.end()) {
        kept.push_back(old);
        copy_of_component[k] = old;
        continue;
      }
      const Index fresh = num_copies();
      copy_tet_.push_back(tet);
      copy_nodes_.push_back(copy_nodes_[old]);
      update.new_copy_source.push_back(old);
      copy_of_component[k] = fresh;
    }
    if (kept.size() != copies_of(tet).size()) broken("tet copies", "a copy lost all its material");
    for (cells::CellId c = complex.first_cell(tet); c >= 0; c = complex.cells()[c].next_in_tet) {
      const std::int32_t k = components.cell_component[c];
      if (k >= 0) complex.set_cell_label(c, static_cast<std::int32_t>(copy_of_component[k]));
    }
    single_copy_[tet] = copy_of_component.empty() ? -1 : copy_of_component.front();
    if (count > 1) {
      several_copies_[tet] = std::move(copy_of_component);
    } else {
      several_copies_.erase(tet);
    }
  }

  // 2. Nodes around the touched tets.
  std::vector<Index> nodes;
  for (const Index tet : touched) {
    for (int k = 0; k < 4; ++k) nodes.push_back(mesh_->tets()(tet, k));
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  for (const Index node : nodes) recollapse(complex, node, &update);
  std::sort(update.changed_copies.begin(), update.changed_copies.end());
  update.changed_copies.erase(std::unique(update.changed_copies.begin(), update.changed_copies.end()),
                              update.changed_copies.end());
  return update;
}

void TetCopies::recollapse(const CellComplex& complex, Index node, Update* update) {
  const Tets& tets = mesh_->tets();
  const TetAdjacency& adj = mesh_->adjacency();
  // The slots of this input node: (copy, local index) for every copy of every tet around it.
  struct Slot {
    Index copy;
    int local;
  };
  std::vector<Slot> slots;
  for (Index i = node_tets_begin_[node]; i < node_tets_begin_[node + 1]; ++i) {
    const Index tet = node_tets_[i];
    const int local = local_index(tets, tet, node);
    for (const Index copy : copies_of(tet)) slots.push_back({copy, local});
  }
  const auto slot_of = [&](Index copy) {
    for (std::size_t s = 0; s < slots.size(); ++s) {
      if (slots[s].copy == copy) return static_cast<Index>(s);
    }
    broken("tet copies", "a joined copy is not around the node");
  };
  UnionFind classes(slots.size());
  std::vector<Index> faces;
  for (Index i = node_tets_begin_[node]; i < node_tets_begin_[node + 1]; ++i) {
    const Index tet = node_tets_[i];
    for (int k = 0; k < 4; ++k) {
      if (tets(tet, k) != node) faces.push_back(adj.tet_faces(tet, k));  // the faces through the node
    }
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  for (const Index face : faces) {
    joins_across(complex, *this, face, [&](Index a, Index b) { classes.join(slot_of(a), slot_of(b)); });
  }
  // Each class keeps the node id its slots share, unless an earlier class took it: then it is a
  // new node, split from that one.
  std::vector<Index> id_of_root(slots.size(), -1), claimed;
  for (std::size_t s = 0; s < slots.size(); ++s) {
    const Index root = classes.find(static_cast<Index>(s));
    Index& id = id_of_root[root];
    const Index old = copy_nodes_[slots[s].copy][slots[s].local];
    if (id < 0) {
      if (std::find(claimed.begin(), claimed.end(), old) == claimed.end()) {
        claimed.push_back(old);
        id = old;
      } else {
        id = num_nodes();
        node_parent_.push_back(node);
        update->new_node_source.push_back(old);
      }
    }
    if (copy_nodes_[slots[s].copy][slots[s].local] != id) {
      copy_nodes_[slots[s].copy][slots[s].local] = id;
      if (slots[s].copy < update->first_new_copy) update->changed_copies.push_back(slots[s].copy);
    }
  }
}

Pieces find_pieces(const CellComplex& complex, const components::MaterialComponents& components,
                   const TetCopies& copies) {
  const TetMesh& mesh = complex.mesh();
  const Index count = copies.num_copies();
  Pieces result;
  result.copy_volume.assign(static_cast<std::size_t>(count), 0.0);
  const Points& rest = mesh.rest();
  const Tets& tets = mesh.tets();
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    if (!complex.refined(t)) {
      if (complex.tet_material(t)) {
        result.copy_volume[copies.copy_of(t, 0)] =
            signed_volume(rest.row(tets(t, 0)), rest.row(tets(t, 1)), rest.row(tets(t, 2)), rest.row(tets(t, 3)));
      }
      continue;
    }
    for (cells::CellId c = complex.first_cell(t); c >= 0; c = complex.cells()[c].next_in_tet) {
      if (components.cell_component[c] >= 0) result.copy_volume[complex.cells()[c].label] += components.cell_volume6[c] / 6;
    }
  }
  UnionFind pieces(static_cast<std::size_t>(count));
  for (Index face = 0; face < mesh.adjacency().num_faces(); ++face) {
    joins_across(complex, copies, face, [&](Index a, Index b) { pieces.join(a, b); });
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
