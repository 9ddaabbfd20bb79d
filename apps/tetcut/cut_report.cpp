#include "cut_report.hpp"

#include <tetcut/quality.hpp>

#include <fmt/core.h>

#include <sys/resource.h>

#include <cstdint>
#include <cstdio>

namespace tetcut::cli {

namespace {

// Per-copy data a viewer can colour by: the input tet, the piece, and the material it holds.
TetMeshWriteOptions cut_mesh_write_options(const CutMesh& cut, TetMeshWriteOptions options) {
  const Index n = cut.mesh.num_tets();
  CellField original{"original_tet", {}, true}, piece{"piece", {}, true}, volume{"material_volume", {}, false},
      fraction{"material_fraction", {}, false};
  fraction.values = cut.material_fractions();
  for (Index c = 0; c < n; ++c) {
    original.values.push_back(cut.tet_parent[c]);
    piece.values.push_back(cut.tet_piece[c]);
    volume.values.push_back(cut.tet_material_volume[c]);
  }
  options.cell_fields = {std::move(original), std::move(piece), std::move(volume), std::move(fraction)};
  options.tet_labels = cut.tet_piece;
  return options;
}

// Peak resident memory of this process so far, in bytes (Linux reports kilobytes).
std::int64_t peak_memory_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::int64_t>(usage.ru_maxrss) * 1024;
}

}  // namespace

void CutOutputs::add(CLI::App* command, const std::string& report_keys) {
  command->add_option("--out-mesh", mesh,
                      "Write the simulation mesh; .vtu carries original_tet, piece, material_volume and "
                      "material_fraction per tet, .mesh and .msh the piece as a label");
  command->add_option("--out-surface", surface, "Write the material surface (" + supported_surface_extensions() + ")");
  command->add_option("--report", report, "Write a JSON report: " + report_keys);
  command->add_flag("--binary", binary, "Binary PLY or STL surface output");
}

void CutOutputs::check(const std::vector<fs::path>& inputs) const {
  for (const fs::path* output : {&mesh, &surface, &report}) {
    for (const fs::path& input : inputs) {
      if (!output->empty()) check_not_input(*output, input);
    }
  }
  if (!mesh.empty()) check_tet_mesh_output(mesh);
  if (!surface.empty()) check_surface_output(surface);
}

void write_and_report(const TetMesh& mesh, const CutResult& result, const CutOutputs& outputs, const RunSummary& run) {
  auto start = Clock::now();
  if (!outputs.mesh.empty()) {
    TetMeshWriteOptions options = cut_mesh_write_options(result.mesh, outputs.mesh_options);
    options.current_positions = outputs.deformed;
    write_tet_mesh(outputs.mesh, result.mesh.mesh, options);
  }
  if (!outputs.surface.empty()) {
    TriangleSurface surface = result.surface.surface;
    if (outputs.deformed) surface.vertices = result.surface.positions(result.mesh, result.mesh.mesh.current());
    write_surface(outputs.surface, surface, SurfaceWriteOptions{outputs.binary});
  }
  const double write_seconds = seconds_since(start);
  Json timings = run.timings;
  timings["surface"] = result.seconds_surface;
  timings["write"] = write_seconds;

  const SurfaceStats surface = measure_surface(result.surface.surface);
  double volume = 0;
  for (const double v : result.mesh.piece_volumes) volume += v;
  fmt::print("{}\n", run.headline);
  fmt::print("  tets             {} -> {}\n", mesh.num_tets(), result.mesh.mesh.num_tets());
  fmt::print("  nodes            {} -> {}\n", mesh.num_nodes(), result.mesh.mesh.num_nodes());
  fmt::print("  pieces           {}\n", result.mesh.num_pieces());
  fmt::print("  volume           {:.17g}\n", volume);
  fmt::print("  surface          {} triangles, area {:.17g}, {}\n", result.surface.surface.num_triangles(), surface.area,
             surface.balanced ? "balanced" : "NOT balanced");
  std::string times;
  for (const auto& [stage, seconds] : timings.items()) {
    times += fmt::format("{}{} {:.3f} s", times.empty() ? "" : ", ", stage, seconds.get<double>());
  }
  fmt::print("  time             {}\n", times);
  std::int64_t peak = 0;
  if (run.peak_memory) {
    peak = peak_memory_bytes();
    fmt::print("  peak memory      {:.1f} MiB\n", static_cast<double>(peak) / (1 << 20));
  }
  for (const fs::path* path : {&outputs.mesh, &outputs.surface, &outputs.report}) {
    if (!path->empty()) fmt::print("  wrote            {}\n", path->string());
  }

  if (!outputs.report.empty()) {
    Json report = run.report;
    report.update(Json{
        {"nodes_in", mesh.num_nodes()},
        {"tets_in", mesh.num_tets()},
        {"nodes_out", result.mesh.mesh.num_nodes()},
        {"tets_out", result.mesh.mesh.num_tets()},
        {"triangles", run.triangles},
        {"zero_area_triangles_skipped", run.skipped},
        {"world_space", run.world_space},
        {"inverted_tets_skipped", run.inverted},
        {"pieces", result.mesh.num_pieces()},
        {"piece_volumes", result.mesh.piece_volumes},
        {"volume", volume},
        {"surface",
         {{"triangles", result.surface.surface.num_triangles()},
          {"vertices", result.surface.surface.num_vertices()},
          {"area", surface.area},
          {"balanced", surface.balanced},
          {"two_manifold", surface.two_manifold},
          {"enclosed_volume", surface.enclosed_volume}}},
        {"timings", timings},
    });
    if (!run.extra.is_null()) report.update(run.extra);
    if (run.peak_memory) report["peak_memory_bytes"] = peak;
    write_text_file(outputs.report, report.dump(2) + "\n");
  }
}

CutResult cut_and_report(const std::string& name, const TetMesh& mesh, const std::vector<NamedBatch>& batches,
                         const CutOutputs& outputs, double read_seconds, const Points* deformed) {
  auto start = Clock::now();
  Cutter cutter(mesh);
  if (deformed != nullptr) cutter.set_current(*deformed);
  Index triangles = 0, skipped = 0, inverted = 0;
  for (const NamedBatch& batch : batches) {
    const CutBatchReport report = deformed != nullptr ? cutter.cut_deformed(batch.triangles) : cutter.cut(batch.triangles);
    triangles += report.triangles;
    skipped += static_cast<Index>(report.degenerate.size());
    inverted += static_cast<Index>(report.skipped_inverted.size());
    if (!report.skipped_inverted.empty()) {
      fmt::print(stderr, "tetcut: warning: {}: {} tet(s) inverted or flat in the deformed positions were not cut there\n",
                 batch.name, report.skipped_inverted.size());
    }
    if (!report.degenerate.empty()) {
      fmt::print(stderr, "tetcut: warning: {}: skipped {} zero-area triangle(s), the first is triangle {}\n", batch.name,
                 report.degenerate.size(), report.degenerate.front());
    }
    if (report.tets_touched == 0) fmt::print(stderr, "tetcut: warning: {}: the cut does not reach into the mesh\n", batch.name);
  }
  const double insert_seconds = seconds_since(start);
  CutResult result = cutter.result();
  Json cut_names = Json::array();
  for (const NamedBatch& batch : batches) cut_names.push_back(batch.name);
  RunSummary summary;
  summary.headline = fmt::format("cut {} by {} batch(es): {} triangles{}", name, batches.size(), triangles,
                                 deformed != nullptr ? " placed on the deformed mesh" : "");
  if (skipped > 0) summary.headline += fmt::format(" ({} zero-area, skipped)", skipped);
  summary.report = Json{{"mesh", name}, {"cuts", cut_names}};
  summary.triangles = triangles;
  summary.skipped = skipped;
  summary.inverted = inverted;
  summary.world_space = deformed != nullptr;
  summary.timings = Json{{"read", read_seconds}, {"cut", insert_seconds + result.seconds_mesh}};
  write_and_report(mesh, result, outputs, summary);
  return result;
}

}  // namespace tetcut::cli
