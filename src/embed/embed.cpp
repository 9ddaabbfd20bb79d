// Embedding: cut the mesh by the surface, decide the material, then build copies and nodes once,
// from scratch, over the kept material only.

#include <tetcut/embed.hpp>
#include <tetcut/error.hpp>

#include <chrono>
#include <string>

#include "cutter/cutter_state.hpp"
#include "embed/material_classification.hpp"
#include "util/stopwatch.hpp"

namespace tetcut {
namespace {

// Keeps only the material of piece `piece` (pieces of the copies as rebuilt); the rest is void.
void keep_piece(cells::CellComplex& complex, const connectivity::TetCopies& copies,
                const connectivity::Pieces& pieces, Index piece) {
  for (Index t = 0; t < complex.mesh().num_tets(); ++t) {
    if (!complex.refined(t)) {
      if (complex.tet_material(t)) complex.set_tet_material(t, pieces.copy_piece[copies.copy_of(t, 0)] == piece);
      continue;
    }
    for (cells::CellId c = complex.first_cell(t); c >= 0; c = complex.cells()[c].next_in_tet) {
      const cells::Cell& cell = complex.cells()[c];
      if (cell.material && pieces.copy_piece[cell.label] != piece) complex.set_cell_material(c, false);
    }
  }
}

}  // namespace

namespace {

struct KeepName {
  KeepMaterial keep;
  std::string_view name;
};
constexpr KeepName kKeepNames[] = {
    {KeepMaterial::kInside, "inside"}, {KeepMaterial::kLargest, "largest"}, {KeepMaterial::kPoint, "point"}};

}  // namespace

std::string_view keep_material_name(KeepMaterial keep) {
  for (const KeepName& k : kKeepNames) {
    if (k.keep == keep) return k.name;
  }
  return "unknown";
}

std::optional<KeepMaterial> keep_material_from_name(std::string_view name) {
  for (const KeepName& k : kKeepNames) {
    if (k.name == name) return k.keep;
  }
  return std::nullopt;
}

Cutter embed(TetMesh mesh, const TriangleSurface& surface, const EmbedOptions& options, EmbedReport* report) {
  EmbedReport local;
  EmbedReport& r = report != nullptr ? *report : local;
  r = EmbedReport{};
  auto start = Clock::now();
  r.check = check_surface(surface);
  if (options.keep == KeepMaterial::kInside && !r.check.balanced()) {
    std::string message = "the surface is not closed: " + std::to_string(r.check.unbalanced_edges) +
                          " edges are used more often in one direction than the other";
    if (r.check.misoriented_edges > 0) {
      message += " (" + std::to_string(r.check.misoriented_edges) + " of them where neighbouring triangles disagree on orientation)";
    }
    message += ", so it has no inside; an open surface needs another choice of material (keep the largest piece, or the piece at a point)";
    throw Error(ErrorKind::kInvalidInput, message);
  }
  if (options.keep == KeepMaterial::kPoint && !options.point.allFinite()) {
    throw Error(ErrorKind::kInvalidArgument, "the point chosen to keep material is not finite");
  }
  r.tets_in = mesh.num_tets();
  r.seconds_check = seconds_since(start);

  start = Clock::now();
  Cutter cutter(std::move(mesh));
  CutterAccess::State& s = CutterAccess::state(cutter);
  CutBatchReport batch;
  std::vector<Index> touched;
  s.insert_rest(surface, &batch, &touched);
  r.seconds_insert = seconds_since(start);

  start = Clock::now();
  if (options.keep == KeepMaterial::kInside) {
    const embedding::Windings windings = embedding::winding_numbers(s.complex);
    r.tets_with_material = embedding::keep_nonzero_winding(s.complex, windings);
    r.covered_facets_joined = embedding::join_overlaps(s.complex);
  } else {
    // Pieces of the whole cut block first; then keep one.
    s.rebuild_copies();
    const connectivity::Pieces pieces = connectivity::find_pieces(s.complex, s.components, s.copies);
    Index piece = 0;  // pieces come largest first
    if (options.keep == KeepMaterial::kPoint) {
      spatial::Aabb box;
      box.extend(options.point);
      std::vector<Index> tets;
      s.rest_tets.query(box, &tets);
      const cells::Side side = embedding::side_holding(s.complex, tets, options.point);
      piece = pieces.copy_piece[s.copies.copy_on(s.complex, side)];
    }
    keep_piece(s.complex, s.copies, pieces, piece);
  }
  r.seconds_classify = seconds_since(start);

  start = Clock::now();
  s.rebuild_copies();
  if (s.copies.num_copies() == 0) {
    throw Error(ErrorKind::kInvalidInput, "no material is left: the surface encloses nothing inside the mesh");
  }
  r.tets_with_material = 0;
  for (Index t = 0; t < s.mesh.num_tets(); ++t) {
    const std::int32_t count = s.components.count[t];
    r.tets_with_material += count > 0 ? 1 : 0;
    r.tets_duplicated += count > 1 ? 1 : 0;
  }
  r.seconds_copies = seconds_since(start);
  return cutter;
}

}  // namespace tetcut
