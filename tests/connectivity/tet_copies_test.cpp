// The incremental copies and nodes against a from-scratch computation: after any sequence of
// batches, the nodes must be exactly the classes of copy corners joined through faces, computed
// globally, and the copies exactly the components.

#include <gtest/gtest.h>

#include <tetcut/generators.hpp>

#include <map>
#include <numeric>
#include <random>

#include "cells/cell_complex.hpp"
#include "components/material_components.hpp"
#include "connectivity/tet_copies.hpp"

namespace tetcut::connectivity {
namespace {

class Reference {
 public:
  explicit Reference(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), std::size_t{0}); }
  std::size_t find(std::size_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void join(std::size_t a, std::size_t b) { parent_[find(a)] = find(b); }

 private:
  std::vector<std::size_t> parent_;
};

// Empty when the copies' nodes are the global classes of corners joined through faces.
std::string check_against_global(const cells::CellComplex& complex, const TetCopies& copies) {
  const TetMesh& mesh = complex.mesh();
  const Index count = copies.num_copies();
  Reference classes(static_cast<std::size_t>(count) * 4);
  const auto local = [&](Index tet, Index node) {
    for (int k = 0; k < 4; ++k) {
      if (mesh.tets()(tet, k) == node) return k;
    }
    return -1;
  };
  const TetAdjacency& adj = mesh.adjacency();
  for (Index face = 0; face < adj.num_faces(); ++face) {
    const auto around = adj.tets_of_face(face);
    if (around.size() != 2) continue;
    std::vector<std::pair<Index, Index>> joined;
    if (complex.first_facet_on_face(face) < 0) {
      joined.emplace_back(copies.copy_of(around[0], 0), copies.copy_of(around[1], 0));
    } else {
      for (cells::FacetId f = complex.first_facet_on_face(face); f >= 0; f = complex.facets()[f].next_on_mesh_face) {
        const cells::Facet& facet = complex.facets()[f];
        if (facet.covered()) continue;
        joined.emplace_back(copies.copy_on(complex, facet.front), copies.copy_on(complex, facet.back));
      }
    }
    for (const auto& [a, b] : joined) {
      for (int k = 0; k < 3; ++k) {
        const Index node = adj.faces(face, k);
        const Index ta = copies.copy_tet()[a], tb = copies.copy_tet()[b];
        classes.join(4 * static_cast<std::size_t>(a) + local(ta, node), 4 * static_cast<std::size_t>(b) + local(tb, node));
      }
    }
  }
  // Same partition: corners in one class share one node id, and one node id means one class.
  std::map<std::size_t, Index> id_of_class;
  std::map<Index, std::size_t> class_of_id;
  for (Index c = 0; c < count; ++c) {
    for (int k = 0; k < 4; ++k) {
      const std::size_t root = classes.find(4 * static_cast<std::size_t>(c) + k);
      const Index id = copies.copy_nodes()[c][k];
      const auto [a, inserted_a] = id_of_class.try_emplace(root, id);
      const auto [b, inserted_b] = class_of_id.try_emplace(id, root);
      if (a->second != id) return "joined corners have different nodes (copy " + std::to_string(c) + ")";
      if (b->second != root) return "unjoined corners share node " + std::to_string(id);
      if (copies.node_parent()[id] != mesh.tets()(copies.copy_tet()[c], k)) return "a node copies the wrong input node";
    }
  }
  if (static_cast<Index>(class_of_id.size()) != copies.num_nodes()) return "a node is not used by any copy";
  return {};
}

TEST(TetCopies, IncrementalNodesEqualTheGlobalClasses) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> coordinate(-0.2, 1.2);
  for (int trial = 0; trial < 60; ++trial) {
    const TetMesh mesh = make_grid(Box{}, {2, 2, 2}, trial % 2 ? 5 : 6);
    registry::IntersectionRegistry registry(mesh.rest());
    cells::CellComplex complex(mesh, registry);
    TetCopies copies(mesh, complex);
    components::MaterialComponents components;
    components.count.assign(static_cast<std::size_t>(mesh.num_tets()), 1);
    std::vector<Index> all(static_cast<std::size_t>(mesh.num_tets()));
    std::iota(all.begin(), all.end(), Index{0});
    std::int32_t id = 0;
    for (int batch = 0; batch < 4; ++batch) {
      std::vector<Index> touched;
      for (int i = 0; i < 2; ++i) {
        const auto point = [&] { return Vec3(coordinate(rng), coordinate(rng), coordinate(rng)); };
        complex.insert_triangle(cells::CutTriangle{point(), point(), point(), id++}, all, &touched);
      }
      std::sort(touched.begin(), touched.end());
      touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
      components::update_components(complex, touched, &components);
      const Index nodes_before = copies.num_nodes();
      const TetCopies::Update update = copies.update(complex, components, touched);
      ASSERT_EQ(update.first_new_node, nodes_before);
      ASSERT_EQ(copies.num_nodes(), nodes_before + static_cast<Index>(update.new_node_source.size()));
      for (std::size_t i = 0; i < update.new_node_source.size(); ++i) {
        // A new node copies the same input node as the node it was split from.
        ASSERT_EQ(copies.node_parent()[update.first_new_node + static_cast<Index>(i)],
                  copies.node_parent()[update.new_node_source[i]]);
      }
      ASSERT_EQ(check_against_global(complex, copies), "") << "trial " << trial << " batch " << batch;
      // Copies are the components, one each.
      Index expected = 0;
      for (Index t = 0; t < mesh.num_tets(); ++t) expected += components.count[t];
      ASSERT_EQ(copies.num_copies(), expected);
    }
  }
}

}  // namespace
}  // namespace tetcut::connectivity
