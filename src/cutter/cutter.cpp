// The Cutter: the paper's pipeline, batch by batch. Reading Cutter::cut (rest space),
// Cutter::cut_deformed (world space) and State::finish_batch below is reading the algorithm;
// docs/algorithm.md maps each stage to its folder.
//
//  1. Planes and points (Appendix A; registry/): each triangle's plane and the walls through its
//     edges (the paper's virtual triangles), stored once; every point is three of them.
//     In: the batch's corners. Out: a PreparedTriangle per triangle.
//  2. The tets a triangle may touch (Appendix A; spatial/): a box tree of the input tets in rest
//     space; in world space, of the copies' current shapes, each copy pulling the triangle back
//     into its rest space. In: the triangle's box. Out: candidate tets (copies).
//  3. Resolve into polygons (3.1, 3.2; cells/): each candidate tet refined into cells when first
//     cut, its cells split by the triangle's plane and the part inside its walls covered, exactly.
//     In: prepared triangles and candidates. Out: the tets whose cells changed (touched).
//  4. Material components (3.3; components/): the cells of each touched tet connected through
//     uncovered facets. In: the complex. Out: each cell's component.
//  5. Copies, joins and nodes (3.3, 3.4; connectivity/): a copy of the tet per component, copies
//     sharing face polygons with material joined, nodes collapsed; ids once given stay.
//     In: the components. Out: new and changed copies and nodes (the batch's report).
//  6. The material surface (4; surface/): the patches of the touched tets and their neighbours
//     marked, rebuilt when the surface is next asked for. In: the complex and the copies.
//  A result (result()) adds the pieces (connectivity/) and the simulation mesh.

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "cutter/cutter_state.hpp"
#include "mesh/surface_checks.hpp"
#include "cells/cell_complex.hpp"
#include "components/material_components.hpp"
#include "connectivity/tet_copies.hpp"
#include "geometry/predicates.hpp"
#include "registry/intersection_registry.hpp"
#include "spatial/box_tree.hpp"
#include "surface/material_surface.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "util/stopwatch.hpp"

namespace tetcut {
namespace {

void check_batch(const TriangleSurface& batch) { check_triangles(batch, "cut"); }

spatial::Aabb box_of(const std::array<Vec3, 3>& corners) {
  spatial::Aabb box;
  for (const Vec3& p : corners) box.extend(p);
  return box;
}

}  // namespace

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
std::span<const Index> Cutter::copies_of(Index tet) const {
  if (tet < 0 || tet >= state_->mesh.num_tets()) throw Error(ErrorKind::kInvalidArgument, "copies_of: no such input tet");
  return state_->copies.copies_of(tet);
}

void Cutter::State::insert_rest(const TriangleSurface& batch, CutBatchReport* report, std::vector<Index>* touched) {
  check_batch(batch);
  report->triangles = batch.num_triangles();
  // 1. Each triangle's plane and walls.
  std::vector<cells::PreparedTriangle> prepared;
  for (Index i = 0; i < batch.num_triangles(); ++i) {
    const std::array<Vec3, 3> x = triangle_corners(batch, i);
    const std::int32_t id = next_id(batch.num_triangles() - i);
    if (geometry::collinear(x[0], x[1], x[2])) {
      report->degenerate.push_back(i);
      continue;
    }
    cells::PreparedTriangle t;
    t.cut_id = id;
    t.corners_are_inputs = true;
    t.corners = x;
    const PlaneBook::Found plane = planes.triangle_plane(geometry::Plane::through(x[0], x[1], x[2]), 4 * std::int64_t{id});
    t.plane = {planes.per_copy(plane.key, -1, [&] { return registry.add_plane(*plane.plane); }), plane.sign};
    const int axis = geometry::wall_axis(*plane.plane);
    for (int e = 0; e < 3; ++e) {
      // Rest-space walls come from the registry, which keeps one per edge and axis across batches.
      t.walls[e] = registry.wall(x[e], x[(e + 1) % 3], axis, x[(e + 2) % 3]);
    }
    prepared.push_back(t);
  }
  // 2 and 3. The tets each may touch, and the insertion. Large batches (an embedded surface) go
  // to the block-scheduled insertion, on one thread too (it takes each tet's triangles while the
  // tet's cells are in cache: a third faster than one triangle at a time); a progressive cut's
  // few triangles would not repay sorting them by block (measured 2026-12-03, the scalpel bench's
  // 10-triangle batches through the block schedule: 1.74, 1.43 and 5.0 ms a batch on the 10k,
  // 100k and 1M lattices against 1.63, 1.22 and 3.6 ms). Both take insert_into_tet per tet.
  constexpr std::size_t kParallelFrom = 256;
  if (prepared.size() < kParallelFrom) {
    std::vector<Index> candidates;
    for (std::size_t i = 0; i < prepared.size(); ++i) {
      candidates.clear();
      rest_tets.query(box_of(prepared[i].corners), &candidates);
      complex.insert_triangle(prepared[i], candidates, -1, touched);
    }
    return;
  }
  std::vector<std::vector<Index>> candidates(prepared.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, prepared.size(), 1024), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) rest_tets.query(box_of(prepared[i].corners), &candidates[i]);
  });
  complex.insert_triangles(prepared, candidates, touched);
}

void Cutter::State::rebuild_copies() {
  components = components::find_components(complex);
  copies.rebuild(complex, components);
  current.resize(static_cast<std::size_t>(copies.num_nodes()));
  for (Index n = 0; n < copies.num_nodes(); ++n) current[n] = mesh.current().row(copies.node_parent()[n]).transpose();
  current_copies = spatial::BoxTree();
  copies_since_set.clear();
  surface = surface::SurfacePatches(mesh);
}

CutBatchReport Cutter::cut(const TriangleSurface& batch) {
  State& s = *state_;
  CutBatchReport report;
  std::vector<Index> touched;
  s.insert_rest(batch, &report, &touched);      // stages 1-3
  s.finish_batch(std::move(touched), &report);  // stages 4-6
  return report;
}

void Cutter::State::finish_batch(std::vector<Index> touched, CutBatchReport* report) {
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  // 4. Material components of the touched tets.
  components::update_components(complex, touched, &components);
  // 5. Their copies, joins and nodes, updated in place.
  connectivity::TetCopies::Update update = copies.update(complex, components, touched);
  // 6. The surface patches that can change: those of the touched tets and their neighbours (cells,
  //    facets on shared faces, points on shared edges), and of copies whose nodes changed.
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

void Cutter::set_current(const Points& nodes) {
  State& s = *state_;
  if (nodes.rows() != num_nodes()) {
    throw Error(ErrorKind::kInvalidInput, "deformed positions: " + std::to_string(nodes.rows()) + " rows for " +
                                              std::to_string(num_nodes()) + " nodes of the cut mesh");
  }
  if (!nodes.allFinite()) throw Error(ErrorKind::kInvalidInput, "deformed positions: a coordinate is not finite");
  for (Index n = 0; n < num_nodes(); ++n) s.current[n] = nodes.row(n).transpose();
  s.planes.forget_pulled_back();
  // Refit while the tree covers most copies (in place: a live session calls this every frame);
  // rebuild when many were made since it was built.
  const Index in_tree = s.current_copies.size();
  if (in_tree > 0 && s.copies_since_set.size() * 16 < static_cast<std::size_t>(in_tree)) {
    std::vector<spatial::Aabb>& boxes = s.current_copies.mutable_boxes();
    tbb::parallel_for(tbb::blocked_range<Index>(0, in_tree, 4096), [&](const auto& range) {
      for (Index c = range.begin(); c != range.end(); ++c) boxes[c] = s.current_box(c);
    });
    s.current_copies.refit();
    s.copies_since_set.erase(std::remove_if(s.copies_since_set.begin(), s.copies_since_set.end(), [&](Index c) { return c < in_tree; }),
                             s.copies_since_set.end());
  } else {
    std::vector<spatial::Aabb> boxes(static_cast<std::size_t>(s.copies.num_copies()));
    tbb::parallel_for(tbb::blocked_range<Index>(0, s.copies.num_copies(), 4096), [&](const auto& range) {
      for (Index c = range.begin(); c != range.end(); ++c) boxes[c] = s.current_box(c);
    });
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
      // Grow the box: by the size of the mesh's boxes nearby, doubling. The first reach is a
      // thousandth of the point's magnitude (of 1 near the origin): under the size of any tet a
      // mesh at that place would be cut into, and 64 doublings reach past any mesh.
      constexpr double kFirstReach = 1e-3;
      reach = reach == 0 ? kFirstReach * (1 + p.cwiseAbs().maxCoeff()) : 2 * reach;
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
    const std::array<Vec3, 3> corners = triangle_corners(batch, i);
    const std::int32_t id = s.next_id(batch.num_triangles() - i);
    if (geometry::collinear(corners[0], corners[1], corners[2])) {
      report.degenerate.push_back(i);
      continue;
    }
    // 1. The triangle in world space: its plane, and walls oriented towards the opposite corner
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
    // 2. The copies it may touch in their current shapes.
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
      // 3. Into this copy's cells only (those labelled with it).
      const Index tet = s.copies.copy_tet()[copy];
      s.complex.insert_triangle(t, std::span<const Index>(&tet, 1), static_cast<std::int32_t>(copy), &touched);
    }
  }
  std::sort(report.skipped_inverted.begin(), report.skipped_inverted.end());
  report.skipped_inverted.erase(std::unique(report.skipped_inverted.begin(), report.skipped_inverted.end()),
                                report.skipped_inverted.end());
  s.finish_batch(std::move(touched), &report);  // stages 4-6
  return report;
}

double Cutter::material_fraction(Index copy) const {
  const State& s = *state_;
  if (copy < 0 || copy >= num_tets()) throw Error(ErrorKind::kInvalidArgument, "material_fraction: no such tet copy");
  const Index t = s.copies.copy_tet()[copy];
  const Points& rest = s.mesh.rest();
  const Tets& tets = s.mesh.tets();
  const double volume = signed_volume(rest.row(tets(t, 0)), rest.row(tets(t, 1)), rest.row(tets(t, 2)), rest.row(tets(t, 3)));
  if (!s.complex.refined(t)) return s.complex.tet_material(t) ? 1.0 : 0.0;
  // Summed as connectivity::find_pieces sums a copy's material volume: cell by cell, in order.
  double material = 0;
  for (cells::CellId c = s.complex.first_cell(t); c >= 0; c = s.complex.cells()[c].next_in_tet) {
    if (s.components.cell_component[c] >= 0 && s.complex.cells()[c].label == copy) material += s.components.cell_volume6[c] / 6;
  }
  return material / volume;
}

MaterialSurface Cutter::surface() {
  State& s = *state_;
  return s.surface.assemble(s.complex, s.copies);
}

CutResult Cutter::result() {
  State& s = *state_;
  auto start = Clock::now();
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

std::vector<double> CutMesh::material_fractions() const {
  std::vector<double> fraction(static_cast<std::size_t>(mesh.num_tets()));
  const Points& p = mesh.rest();
  const Tets& t = mesh.tets();
  for (Index c = 0; c < mesh.num_tets(); ++c) {
    fraction[c] = tet_material_volume[c] / signed_volume(p.row(t(c, 0)), p.row(t(c, 1)), p.row(t(c, 2)), p.row(t(c, 3)));
  }
  return fraction;
}

namespace {

// Each vertex placed by its weights in its copy's nodes, `corner(copy, k)` naming node k.
template <typename Corner>
Points place_vertices(const MaterialSurface& s, const Points& nodes, Corner corner) {
  Points p(s.surface.num_vertices(), 3);
  for (Index v = 0; v < s.surface.num_vertices(); ++v) {
    Vec3 x = Vec3::Zero();
    for (int k = 0; k < 4; ++k) x += s.vertex_weights(v, k) * nodes.row(corner(s.vertex_tet[v], k)).transpose();
    p.row(v) = x.transpose();
  }
  return p;
}

}  // namespace

Points MaterialSurface::positions(const CutMesh& mesh, const Points& nodes) const {
  const Tets& tets = mesh.mesh.tets();
  return place_vertices(*this, nodes, [&](Index copy, int k) { return tets(copy, k); });
}

Points MaterialSurface::positions(std::span<const std::array<Index, 4>> copy_nodes, const Points& nodes) const {
  return place_vertices(*this, nodes, [&](Index copy, int k) { return copy_nodes[static_cast<std::size_t>(copy)][static_cast<std::size_t>(k)]; });
}

}  // namespace tetcut
