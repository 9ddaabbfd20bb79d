// The Cutter: the public face of the pipeline. A batch goes triangle by triangle through the box
// tree (which tets may it touch) into the cell complex (split and cover, exactly); a result is
// components per tet, then copies and joins, then the material surface.

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

namespace tetcut {

struct Cutter::State {
  explicit State(TetMesh m) : mesh(std::move(m)), registry(mesh.rest()), complex(mesh, registry) {
    std::vector<spatial::Aabb> boxes(static_cast<std::size_t>(mesh.num_tets()));
    for (Index t = 0; t < mesh.num_tets(); ++t) {
      for (int k = 0; k < 4; ++k) boxes[t].extend(mesh.rest().row(mesh.tets()(t, k)).transpose());
    }
    tets = spatial::BoxTree(std::move(boxes));
  }

  // The complex points into `mesh` and `registry`, so the state never moves (it lives behind a
  // unique_ptr).
  TetMesh mesh;
  registry::IntersectionRegistry registry;
  cells::CellComplex complex;
  spatial::BoxTree tets;
  std::int64_t next_cut_id = 0;
};

Cutter::Cutter(TetMesh mesh) : state_(std::make_unique<State>(std::move(mesh))) {}
Cutter::~Cutter() = default;
Cutter::Cutter(Cutter&&) noexcept = default;
Cutter& Cutter::operator=(Cutter&&) noexcept = default;

const TetMesh& Cutter::input() const { return state_->mesh; }
std::int64_t Cutter::num_cut_triangles() const { return state_->next_cut_id; }

CutBatchReport Cutter::cut(const TriangleSurface& batch) {
  State& s = *state_;
  CutBatchReport report;
  report.triangles = batch.num_triangles();
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
  if (s.next_cut_id + batch.num_triangles() > std::numeric_limits<std::int32_t>::max()) {
    throw Error(ErrorKind::kInvalidInput, "too many cut triangles: ids must fit in 32 bits");
  }
  std::vector<Index> candidates, touched;
  for (Index i = 0; i < batch.num_triangles(); ++i) {
    cells::CutTriangle triangle;
    triangle.a = batch.vertices.row(batch.triangles(i, 0)).transpose();
    triangle.b = batch.vertices.row(batch.triangles(i, 1)).transpose();
    triangle.c = batch.vertices.row(batch.triangles(i, 2)).transpose();
    triangle.id = static_cast<std::int32_t>(s.next_cut_id++);
    if (geometry::collinear(triangle.a, triangle.b, triangle.c)) {
      report.degenerate.push_back(i);
      continue;
    }
    spatial::Aabb box;
    box.extend(triangle.a);
    box.extend(triangle.b);
    box.extend(triangle.c);
    candidates.clear();
    s.tets.query(box, &candidates);
    s.complex.insert_triangle(triangle, candidates, &touched);
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  report.tets_touched = static_cast<Index>(touched.size());
  report.touched = std::move(touched);
  return report;
}

CutResult Cutter::result() const {
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); };
  const State& s = *state_;
  auto start = Clock::now();
  const components::MaterialComponents components = components::find_components(s.complex);
  connectivity::TetCopies copies = connectivity::build_copies(s.complex, components);
  CutResult result;
  result.seconds_mesh = seconds_since(start);
  start = Clock::now();
  result.surface = surface::extract_material_surface(s.complex, components, copies);
  result.seconds_surface = seconds_since(start);
  start = Clock::now();

  CutMesh& out = result.mesh;
  const Index num_nodes = static_cast<Index>(copies.node_parent.size());
  Points rest(num_nodes, 3), current(num_nodes, 3);
  for (Index n = 0; n < num_nodes; ++n) {
    rest.row(n) = s.mesh.rest().row(copies.node_parent[n]);
    current.row(n) = s.mesh.current().row(copies.node_parent[n]);
  }
  out.mesh = TetMesh(std::move(rest), std::move(copies.copy_nodes));
  out.mesh.set_current(std::move(current));
  out.node_parent = std::move(copies.node_parent);
  out.tet_parent = std::move(copies.copy_tet);
  out.tet_piece = std::move(copies.copy_piece);
  out.tet_material_volume = std::move(copies.copy_volume);
  out.piece_volumes = std::move(copies.piece_volume);
  result.seconds_mesh += seconds_since(start);
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
