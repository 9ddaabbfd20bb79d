#pragma once
// The state behind a Cutter, shared by the cutter and, through CutterAccess, the embedding
// (internal).

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>

#include <algorithm>

#include "cells/cell_complex.hpp"
#include "components/material_components.hpp"
#include "connectivity/tet_copies.hpp"
#include "registry/intersection_registry.hpp"
#include "registry/plane_book.hpp"
#include "spatial/box_tree.hpp"
#include "surface/material_surface.hpp"

namespace tetcut {

using registry::PlaneBook;

struct Cutter::State {
  explicit State(TetMesh m)
      : mesh(std::move(m)), registry(mesh.rest()), complex(mesh, registry), copies(mesh, complex), surface(mesh) {
    std::vector<spatial::Aabb> boxes(static_cast<std::size_t>(mesh.num_tets()));
    for (Index t = 0; t < mesh.num_tets(); ++t) {
      for (int k = 0; k < 4; ++k) boxes[t].extend(mesh.rest().row(mesh.tets()(t, k)).transpose());
    }
    rest_tets = spatial::BoxTree(std::move(boxes));
    components.count.assign(static_cast<std::size_t>(mesh.num_tets()), 1);
    current.resize(static_cast<std::size_t>(mesh.num_nodes()));
    for (Index n = 0; n < mesh.num_nodes(); ++n) current[n] = mesh.current().row(n).transpose();
  }

  // Inserts a rest-space batch into the cells (no components or copies yet): reports degenerate
  // triangles, appends the touched tets.
  void insert_rest(const TriangleSurface& batch, CutBatchReport* report, std::vector<Index>* touched);

  // Components, copies and nodes of every tet from scratch, with dense ids over the copies that
  // hold material (after embedding changed which material there is); current positions from the
  // input's, every surface patch out of date. O(T log T + refined cells).
  void rebuild_copies();

  spatial::Aabb current_box(Index copy) const {
    spatial::Aabb box;
    for (const Index n : copies.copy_nodes()[copy]) box.extend(current[n]);
    return box;
  }

  // Copies whose current boxes may meet `box`: the tree of the copies as of the last
  // set_current, and the copies made since. A copy made since has the box of its source until
  // then, since new nodes start where their sources are.
  void query_current(const spatial::Aabb& box, std::vector<Index>* out) const {
    if (current_copies.size() != 0) current_copies.query(box, out);
    for (const Index copy : copies_since_set) {
      if (current_box(copy).meets(box)) out->push_back(copy);
    }
  }

  // After the insertion of a batch, the stages that follow it for the tets it touched (see
  // cutter.cpp, "The pipeline"): components, copies and nodes, the surface patches to rebuild.
  // Fills the report.
  void finish_batch(std::vector<Index> touched, CutBatchReport* report);

  std::int32_t next_id(Index batch_size) {
    if (next_cut_id + batch_size > std::numeric_limits<std::int32_t>::max()) {
      throw Error(ErrorKind::kInvalidInput, "too many cut triangles: ids must fit in 32 bits");
    }
    return static_cast<std::int32_t>(next_cut_id++);
  }

  // The complex points into `mesh` and `registry`, so the state never moves (it lives behind a
  // unique_ptr).
  TetMesh mesh;
  registry::IntersectionRegistry registry;
  cells::CellComplex complex;
  connectivity::TetCopies copies;
  components::MaterialComponents components;  // of refined tets; unrefined ones have one
  std::vector<Vec3> current;                   // per node of the cut mesh
  spatial::BoxTree rest_tets;
  PlaneBook planes;
  spatial::BoxTree current_copies;             // copies in their current shapes, as of set_current
  std::vector<Index> copies_since_set;         // copies made since set_current
  surface::SurfacePatches surface;             // the material surface, rebuilt where batches changed it
  std::int64_t next_cut_id = 0;
};

// The way into a Cutter's state for the stages built on the cutter: the embedding cuts the mesh,
// decides which material to keep, and builds the copies over it, all on the state. Cutter's one
// friend; not part of the API, since the state is not.
struct CutterAccess {
  using State = Cutter::State;
  static State& state(Cutter& cutter) { return *cutter.state_; }
};

}  // namespace tetcut
