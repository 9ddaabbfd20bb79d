// The Cutter: the public face of the pipeline. A batch goes triangle by triangle into the cell
// complex (split and cover, exactly): in rest space through the box tree of the input tets; in
// world space through a box tree of the copies' current shapes, pulled back per copy. After the
// batch, the touched tets' components are recomputed and the copies and nodes updated in place.
// A result is then the pieces, the simulation mesh and the material surface.

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>

#include <algorithm>
#include <deque>
#include <map>
#include <unordered_map>
#include <chrono>
#include <cmath>
#include <string>

#include "cells/cell_complex.hpp"
#include "components/material_components.hpp"
#include "connectivity/tet_copies.hpp"
#include "geometry/predicates.hpp"
#include "registry/intersection_registry.hpp"
#include "spatial/box_tree.hpp"
#include "surface/material_surface.hpp"

#include <tbb/parallel_for.h>

namespace tetcut {
namespace {

void check_batch(const TriangleSurface& batch) {
  for (Index i = 0; i < batch.num_triangles(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const Index v = batch.triangles(i, k);
      if (v < 0 || v >= batch.num_vertices()) {
        throw Error(ErrorKind::kInvalidInput, "cut triangle " + std::to_string(i) + " refers to vertex " +
                                                  std::to_string(v) + ", which does not exist");
      }
      if (!batch.vertices.row(v).allFinite()) {
        throw Error(ErrorKind::kInvalidInput, "cut triangle " + std::to_string(i) + " has a corner that is not finite");
      }
    }
  }
}

std::array<Vec3, 3> corners_of(const TriangleSurface& batch, Index i) {
  return {batch.vertices.row(batch.triangles(i, 0)).transpose(), batch.vertices.row(batch.triangles(i, 1)).transpose(),
          batch.vertices.row(batch.triangles(i, 2)).transpose()};
}

spatial::Aabb box_of(const std::array<Vec3, 3>& corners) {
  spatial::Aabb box;
  for (const Vec3& p : corners) box.extend(p);
  return box;
}

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

}  // namespace

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

Cutter::Cutter(TetMesh mesh) : state_(std::make_unique<State>(std::move(mesh))) {}
Cutter::~Cutter() = default;
Cutter::Cutter(Cutter&&) noexcept = default;
Cutter& Cutter::operator=(Cutter&&) noexcept = default;

const TetMesh& Cutter::input() const { return state_->mesh; }
std::int64_t Cutter::num_cut_triangles() const { return state_->next_cut_id; }
Index Cutter::num_nodes() const { return state_->copies.num_nodes(); }
Index Cutter::num_tets() const { return state_->copies.num_copies(); }
const std::vector<std::array<Index, 4>>& Cutter::tet_nodes() const { return state_->copies.copy_nodes(); }
const std::vector<Index>& Cutter::node_parent() const { return state_->copies.node_parent(); }
const std::vector<Index>& Cutter::tet_parent() const { return state_->copies.copy_tet(); }

CutBatchReport Cutter::cut(const TriangleSurface& batch) {
  State& s = *state_;
  check_batch(batch);
  CutBatchReport report;
  report.triangles = batch.num_triangles();
  std::vector<Index> candidates, touched;
  for (Index i = 0; i < batch.num_triangles(); ++i) {
    const std::array<Vec3, 3> corners = corners_of(batch, i);
    const std::int32_t id = s.next_id(batch.num_triangles() - i);
    if (geometry::collinear(corners[0], corners[1], corners[2])) {
      report.degenerate.push_back(i);
      continue;
    }
    cells::PreparedTriangle t;
    t.cut_id = id;
    t.corners_are_inputs = true;
    t.corners = corners;
    const PlaneBook::Found plane = s.planes.triangle_plane(geometry::Plane::through(corners[0], corners[1], corners[2]), 4 * std::int64_t{id});
    t.plane = {s.planes.per_copy(plane.key, -1, [&] { return s.registry.add_plane(*plane.plane); }), plane.sign};
    const int axis = geometry::wall_axis(*plane.plane);
    for (int e = 0; e < 3; ++e) {
      // Rest-space walls come from the registry, which keeps one per edge and axis across batches.
      t.walls[e] = s.registry.wall(corners[e], corners[(e + 1) % 3], axis, corners[(e + 2) % 3]);
    }
    candidates.clear();
    s.rest_tets.query(box_of(corners), &candidates);
    s.complex.insert_triangle(t, candidates, -1, &touched);
  }
  s.finish_batch(std::move(touched), &report);
  return report;
}

void Cutter::set_current(const Points& nodes) {
  State& s = *state_;
  if (nodes.rows() != num_nodes()) {
    throw Error(ErrorKind::kInvalidInput, "deformed positions: " + std::to_string(nodes.rows()) + " rows for " +
                                              std::to_string(num_nodes()) + " nodes of the cut mesh");
  }
  if (!nodes.allFinite()) throw Error(ErrorKind::kInvalidInput, "deformed positions: a coordinate is not finite");
  for (Index n = 0; n < num_nodes(); ++n) s.current[n] = nodes.row(n).transpose();
  s.planes.forget_pulled_back();
  std::vector<spatial::Aabb> boxes(static_cast<std::size_t>(s.copies.num_copies()));
  tbb::parallel_for(tbb::blocked_range<Index>(0, s.copies.num_copies(), 4096), [&](const auto& range) {
    for (Index c = range.begin(); c != range.end(); ++c) boxes[c] = s.current_box(c);
  });
  // Refit while the tree covers most copies; rebuild when many were made since it was built.
  if (s.current_copies.size() > 0 && s.copies_since_set.size() * 16 < static_cast<std::size_t>(s.current_copies.size())) {
    std::vector<spatial::Aabb> fitted(boxes.begin(), boxes.begin() + s.current_copies.size());
    s.current_copies.refit(std::move(fitted));
    s.copies_since_set.erase(std::remove_if(s.copies_since_set.begin(), s.copies_since_set.end(),
                                            [&](Index c) { return c < s.current_copies.size(); }),
                             s.copies_since_set.end());
  } else {
    s.current_copies = spatial::BoxTree(std::move(boxes));
    s.copies_since_set.clear();
  }
}

Points Cutter::current() const {
  Points p(num_nodes(), 3);
  for (Index n = 0; n < num_nodes(); ++n) p.row(n) = state_->current[n].transpose();
  return p;
}

CutBatchReport Cutter::cut_deformed(const TriangleSurface& batch, const Points& nodes) {
  set_current(nodes);
  return cut_deformed(batch);
}

Points Cutter::to_rest(const Points& world) const {
  const State& s = *state_;
  if (s.current_copies.size() == 0 && s.copies_since_set.empty()) {
    throw Error(ErrorKind::kInvalidArgument, "to_rest needs the current positions: call set_current first");
  }
  Points rest(world.rows(), 3);
  std::vector<Index> candidates;
  for (Eigen::Index i = 0; i < world.rows(); ++i) {
    const Vec3 p = world.row(i).transpose();
    // Look in a box around the point, growing until some copies are near.
    spatial::Aabb box;
    box.extend(p);
    double reach = 0;
    Index best = -1;
    double best_depth = -std::numeric_limits<double>::infinity();
    Eigen::Vector4d best_weights;
    for (int attempt = 0; attempt < 64 && best < 0; ++attempt) {
      candidates.clear();
      s.query_current(box, &candidates);
      for (const Index copy : candidates) {
        const auto& nodes = s.copies.copy_nodes()[copy];
        Eigen::Matrix3d edges;
        for (int k = 0; k < 3; ++k) edges.col(k) = s.current[nodes[k + 1]] - s.current[nodes[0]];
        if (!(edges.determinant() > 0)) continue;  // inverted or flat
        const Vec3 w = edges.partialPivLu().solve(p - s.current[nodes[0]]);
        const Eigen::Vector4d weights(1 - w.sum(), w[0], w[1], w[2]);
        // Depth: the smallest weight; positive inside, and least negative for the nearest outside.
        if (weights.minCoeff() > best_depth) {
          best_depth = weights.minCoeff();
          best = copy;
          best_weights = weights;
        }
      }
      // Grow the box: by the size of the mesh's boxes nearby, doubling.
      reach = reach == 0 ? 1e-3 * (1 + p.cwiseAbs().maxCoeff()) : 2 * reach;
      box.min = p - Vec3::Constant(reach);
      box.max = p + Vec3::Constant(reach);
    }
    if (best < 0) throw Error(ErrorKind::kInvalidArgument, "to_rest: no tet copy near point " + std::to_string(i));
    const Index tet = s.copies.copy_tet()[best];
    Vec3 x = Vec3::Zero();
    for (int k = 0; k < 4; ++k) x += best_weights[k] * s.mesh.rest().row(s.mesh.tets()(tet, k)).transpose();
    rest.row(i) = x.transpose();
  }
  return rest;
}

CutBatchReport Cutter::cut_deformed(const TriangleSurface& batch) {
  State& s = *state_;
  check_batch(batch);
  if (s.current_copies.size() == 0 && s.copies_since_set.empty()) set_current(current());
  const auto& copy_nodes = s.copies.copy_nodes();
  CutBatchReport report;
  report.triangles = batch.num_triangles();
  std::vector<Index> candidates, touched;
  for (Index i = 0; i < batch.num_triangles(); ++i) {
    const std::array<Vec3, 3> corners = corners_of(batch, i);
    const std::int32_t id = s.next_id(batch.num_triangles() - i);
    if (geometry::collinear(corners[0], corners[1], corners[2])) {
      report.degenerate.push_back(i);
      continue;
    }
    // The triangle in world space: its plane, and walls oriented towards the opposite corner
    // (shared with earlier triangles of the batch on the same plane or edge).
    const PlaneBook::Found plane = s.planes.triangle_plane(geometry::Plane::through(corners[0], corners[1], corners[2]), 4 * std::int64_t{id});
    const geometry::Plane world = plane.sign > 0 ? *plane.plane : plane.plane->flipped();
    const int axis = geometry::wall_axis(*plane.plane);
    std::array<PlaneBook::Found, 3> walls;
    std::array<geometry::Plane, 3> world_walls;
    std::array<std::pair<const geometry::Plane*, int>, 3> walls_with_signs;
    for (int e = 0; e < 3; ++e) {
      walls[e] = s.planes.wall(corners[e], corners[(e + 1) % 3], axis, corners[(e + 2) % 3], 4 * std::int64_t{id} + 1 + e);
      world_walls[e] = walls[e].sign > 0 ? *walls[e].plane : walls[e].plane->flipped();
      walls_with_signs[e] = {&world_walls[e], 1};
    }
    candidates.clear();
    s.query_current(box_of(corners), &candidates);
    for (const Index copy : candidates) {
      std::array<Vec3, 4> now, rest;
      for (int k = 0; k < 4; ++k) {
        now[k] = s.current[copy_nodes[copy][k]];
        rest[k] = s.mesh.rest().row(s.mesh.tets()(s.copies.copy_tet()[copy], k)).transpose();
      }
      // In world space first, on the copy's current corners: does the triangle cover part of it?
      const auto corner_side = [&](int k, const geometry::Plane& face) { return geometry::side_of_point(face, corners[k]); };
      const int orientation = geometry::orient3d(now[0], now[1], now[2], now[3]);
      if (orientation <= 0) {
        // Inverted or flat: the material there is folded, and the cut is not applied (documented
        // rule). Report the copy when the triangle does reach its current shape.
        std::array<Vec3, 4> reordered = {now[1], now[0], now[2], now[3]};
        if (orientation == 0 || cells::tet_may_meet_triangle(reordered, world, walls_with_signs, corner_side)) {
          report.skipped_inverted.push_back(copy);
        }
        continue;
      }
      if (!cells::tet_may_meet_triangle(now, world, walls_with_signs, corner_side)) continue;
      // Pull the triangle back into this copy's rest space, for this copy's cells only. The keys
      // name the world planes, so that the registry can tell where two copies' pull-backs agree.
      cells::PreparedTriangle t;
      t.cut_id = id;
      const auto pulled = [&](const PlaneBook::Found& found) -> registry::OrientedPlane {
        return {s.planes.per_copy(found.key, copy,
                                [&] {
                                  return s.registry.add_plane(geometry::Plane::pulled_back(*found.plane, rest, now, found.key));
                                }),
                found.sign};
      };
      t.plane = pulled(plane);
      for (int e = 0; e < 3; ++e) t.walls[e] = pulled(walls[e]);
      const Index tet = s.copies.copy_tet()[copy];
      s.complex.insert_triangle(t, std::span<const Index>(&tet, 1), static_cast<std::int32_t>(copy), &touched);
    }
  }
  std::sort(report.skipped_inverted.begin(), report.skipped_inverted.end());
  report.skipped_inverted.erase(std::unique(report.skipped_inverted.begin(), report.skipped_inverted.end()),
                                report.skipped_inverted.end());
  s.finish_batch(std::move(touched), &report);
  return report;
}

MaterialSurface Cutter::surface() {
  State& s = *state_;
  return s.surface.assemble(s.complex, s.copies);
}

CutResult Cutter::result() {
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); };
  State& s = *state_;
  auto start = Clock::now();
  s.registry.update_positions();
  const connectivity::Pieces pieces = connectivity::find_pieces(s.complex, s.components, s.copies);
  CutResult result;
  CutMesh& out = result.mesh;
  const Index num_nodes = s.copies.num_nodes();
  Points rest(num_nodes, 3);
  for (Index n = 0; n < num_nodes; ++n) rest.row(n) = s.mesh.rest().row(s.copies.node_parent()[n]);
  Tets tets(s.copies.num_copies(), 4);
  for (Index c = 0; c < s.copies.num_copies(); ++c) {
    for (int k = 0; k < 4; ++k) tets(c, k) = s.copies.copy_nodes()[c][k];
  }
  out.mesh = TetMesh(std::move(rest), std::move(tets));
  out.mesh.set_current(current());
  out.node_parent = s.copies.node_parent();
  out.tet_parent = s.copies.copy_tet();
  out.tet_piece = pieces.copy_piece;
  out.tet_material_volume = pieces.copy_volume;
  out.piece_volumes = pieces.piece_volume;
  result.seconds_mesh = seconds_since(start);
  start = Clock::now();
  result.surface = s.surface.assemble(s.complex, s.copies);
  result.seconds_surface = seconds_since(start);
  return result;
}

Points MaterialSurface::positions(const CutMesh& mesh, const Points& nodes) const {
  Points p(surface.num_vertices(), 3);
  const Tets& tets = mesh.mesh.tets();
  for (Index v = 0; v < surface.num_vertices(); ++v) {
    Vec3 x = Vec3::Zero();
    for (int k = 0; k < 4; ++k) x += vertex_weights(v, k) * nodes.row(tets(vertex_tet[v], k)).transpose();
    p.row(v) = x.transpose();
  }
  return p;
}

}  // namespace tetcut
