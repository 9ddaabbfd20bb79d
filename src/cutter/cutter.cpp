// The Cutter: the public face of the pipeline. A batch goes triangle by triangle into the cell
// complex (split and cover, exactly): in rest space through the box tree of the input tets; in
// world space through a box tree of the copies' current shapes, pulled back per copy. After the
// batch, the touched tets' components are recomputed and the copies and nodes updated in place.
// A result is then the pieces, the simulation mesh and the material surface.

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>

#include <algorithm>
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

// The axis on which a plane's normal is largest (chosen on rounded values, checked non-zero
// exactly): walls along it are never parallel to the plane.
int wall_axis(const geometry::Plane& plane) {
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(plane.approx()[k].value) > std::abs(plane.approx()[axis].value)) axis = k;
  }
  if (geometry::normal_component_sign(plane, axis) == 0) {
    for (int k = 0; k < 3; ++k) {
      if (geometry::normal_component_sign(plane, k) != 0) axis = k;
    }
  }
  return axis;
}

}  // namespace

struct Cutter::State {
  explicit State(TetMesh m) : mesh(std::move(m)), registry(mesh.rest()), complex(mesh, registry), copies(mesh, complex) {
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
  spatial::BoxTree current_copies;             // copies in their current shapes, as of set_current
  std::vector<Index> copies_since_set;         // copies made since set_current
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
    candidates.clear();
    s.rest_tets.query(box_of(corners), &candidates);
    s.complex.insert_triangle(cells::CutTriangle{corners[0], corners[1], corners[2], id}, candidates, &touched);
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
    // The triangle in world space: its plane, and walls oriented towards the opposite corner.
    const geometry::Plane world = geometry::Plane::through(corners[0], corners[1], corners[2]);
    const int axis = wall_axis(world);
    std::array<geometry::Plane, 3> world_walls;
    for (int e = 0; e < 3; ++e) {
      world_walls[e] = geometry::Plane::wall(corners[e], corners[(e + 1) % 3], axis);
      if (geometry::side_of_point(world_walls[e], corners[(e + 2) % 3]) < 0) world_walls[e] = world_walls[e].flipped();
    }
    std::array<std::pair<const geometry::Plane*, int>, 3> walls_with_signs;
    for (int e = 0; e < 3; ++e) walls_with_signs[e] = {&world_walls[e], 1};
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
      // Pull the triangle back into this copy's rest space, for this copy's cells only.
      cells::PreparedTriangle t;
      t.cut_id = id;
      t.plane = {s.registry.add_plane(geometry::Plane::pulled_back(world, rest, now)), 1};
      for (int e = 0; e < 3; ++e) t.walls[e] = {s.registry.add_plane(geometry::Plane::pulled_back(world_walls[e], rest, now)), 1};
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

CutResult Cutter::result() const {
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); };
  const State& s = *state_;
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
  result.surface = surface::extract_material_surface(s.complex, s.copies);
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
