#pragma once
// The state behind a Cutter, shared by the cutter and the embedding (internal).

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>

#include <algorithm>
#include <deque>
#include <map>
#include <unordered_map>

#include "cells/cell_complex.hpp"
#include "components/material_components.hpp"
#include "connectivity/tet_copies.hpp"
#include "registry/intersection_registry.hpp"
#include "spatial/box_tree.hpp"
#include "surface/material_surface.hpp"

namespace tetcut {

// The distinct planes of the cuts so far. Triangles on one plane (a straight blade sweeps a flat
// strip, batch after batch) share one plane, and in world space one pulled-back plane per copy, so
// that what one triangle leaves on the plane the next recognises by plane id instead of by exact
// arithmetic. Each plane gets a key unique over all batches (from the cut id of the first triangle
// on it), which names it to the registry's symbolic test of where two copies' pull-backs agree.
class PlaneBook {
 public:
  struct Found {
    std::int64_t key;
    int sign;  // +1 when the stored plane has the orientation asked for
    const geometry::Plane* plane;
  };

  // The triangle plane `plane`, or an equal one seen before. O(1) expected: a hash of the rounded,
  // normalised coefficients proposes candidates, and equality is decided exactly.
  Found triangle_plane(const geometry::Plane& plane, std::int64_t fresh_key) {
    const std::array<std::int64_t, 4> cell = grid_cell(plane);
    auto& bucket = planes_[cell];
    for (const std::size_t index : bucket) {
      const Entry& e = entries_[index];
      const int alignment = geometry::plane_alignment(e.plane, plane);
      if (alignment != 0) return {e.key, alignment, &e.plane};
    }
    bucket.push_back(entries_.size());
    entries_.push_back({plane, fresh_key});
    return {fresh_key, 1, &entries_.back().plane};
  }

  // The wall through edge (p, q) along `axis`, oriented towards `inner`; one per edge and axis.
  Found wall(const Vec3& p, const Vec3& q, int axis, const Vec3& inner, std::int64_t fresh_key) {
    std::array<double, 7> key;
    const bool swap = std::lexicographical_compare(q.data(), q.data() + 3, p.data(), p.data() + 3);
    const Vec3& a = swap ? q : p;
    const Vec3& b = swap ? p : q;
    for (int k = 0; k < 3; ++k) {
      key[k] = a[k] + 0.0;  // + 0.0 folds -0.0 into 0.0
      key[3 + k] = b[k] + 0.0;
    }
    key[6] = axis;
    auto it = walls_.find(key);
    if (it == walls_.end()) it = walls_.emplace(key, Entry{geometry::Plane::wall(a, b, axis), fresh_key}).first;
    return {it->second.key, geometry::side_of_point(it->second.plane, inner), &it->second.plane};
  }

  // A registry plane per key and copy (copy -1: rest space), made once by `make`.
  template <typename Make>
  registry::PlaneId per_copy(std::int64_t key, Index copy, Make&& make) {
    const auto [it, inserted] = per_copy_.try_emplace({key, copy}, -1);
    if (inserted) it->second = make();
    return it->second;
  }
  // Pulled-back planes depend on the current positions: forget them when those change.
  void forget_pulled_back() {
    std::erase_if(per_copy_, [](const auto& entry) { return entry.first.second >= 0; });
  }

 private:
  // Normalised coefficients rounded to a grid of 2^-30: representations of one plane fall in one
  // cell unless they straddle a grid line, which costs a missed sharing, never correctness.
  static std::array<std::int64_t, 4> grid_cell(const geometry::Plane& plane) {
    Eigen::Vector4d c = plane.rounded();
    const double n = c.head<3>().norm();
    if (n > 0) c /= n;
    // One orientation for both: the first clearly non-zero coefficient positive.
    for (int k = 0; k < 4; ++k) {
      if (std::abs(c[k]) > 1e-6) {
        if (c[k] < 0) c = -c;
        break;
      }
    }
    std::array<std::int64_t, 4> cell;
    for (int k = 0; k < 4; ++k) cell[k] = std::llround(std::ldexp(c[k], 30));
    return cell;
  }
  struct Entry {
    geometry::Plane plane;
    std::int64_t key;
  };
  struct CellHash {
    std::size_t operator()(const std::array<std::int64_t, 4>& c) const {
      std::uint64_t h = 0x9e3779b97f4a7c15ULL;
      for (const std::int64_t x : c) h = (h ^ static_cast<std::uint64_t>(x)) * 0xbf58476d1ce4e5b9ULL;
      return static_cast<std::size_t>(h ^ (h >> 31));
    }
  };
  std::deque<Entry> entries_;  // a deque keeps the planes in place for the pointers handed out
  std::unordered_map<std::array<std::int64_t, 4>, std::vector<std::size_t>, CellHash> planes_;
  std::map<std::array<double, 7>, Entry> walls_;
  std::map<std::pair<std::int64_t, Index>, registry::PlaneId> per_copy_;
};

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

  // Recomputes the touched tets' components and updates copies and nodes; fills the report.
  void finish_batch(std::vector<Index> touched, CutBatchReport* report) {
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    components::update_components(complex, touched, &components);
    connectivity::TetCopies::Update update = copies.update(complex, components, touched);
    // The surface patches that can change: those of the touched tets and their neighbours (cells,
    // facets on shared faces, points on shared edges), and of copies whose nodes changed.
    surface.mark_around(touched);
    std::vector<Index> renumbered;
    for (const Index copy : update.changed_copies) renumbered.push_back(copies.copy_tet()[copy]);
    surface.mark(renumbered);
    // New nodes start where the nodes they were split from are.
    for (const Index source : update.new_node_source) current.push_back(current[source]);
    for (Index c = update.first_new_copy; c < copies.num_copies(); ++c) copies_since_set.push_back(c);
    report->tets_touched = static_cast<Index>(touched.size());
    report->touched = std::move(touched);
    report->first_new_node = update.first_new_node;
    report->new_node_source = std::move(update.new_node_source);
    report->first_new_tet = update.first_new_copy;
    report->new_tet_source = std::move(update.new_copy_source);
    report->changed_tets = std::move(update.changed_copies);
  }

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

}  // namespace tetcut
