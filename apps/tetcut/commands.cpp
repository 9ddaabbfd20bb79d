#include "commands.hpp"

#include <tetcut/cutter.hpp>
#include <tetcut/embed.hpp>
#include <tetcut/render.hpp>
#include <tetcut/scene.hpp>
#include <tetcut/view.hpp>
#include <tetcut/error.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>
#include <tetcut/quality.hpp>

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace tetcut::cli {

void check_not_input(const std::filesystem::path& output, const std::filesystem::path& input) {
  std::error_code ec;
  if (std::filesystem::exists(output, ec) && std::filesystem::equivalent(output, input, ec)) {
    throw Error(ErrorKind::kInvalidArgument, "the output would overwrite the input file", output.string());
  }
}

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

Box box_from(const std::vector<double>& b) {
  Box box;
  box.min = Vec3(b[0], b[1], b[2]);
  box.max = Vec3(b[3], b[4], b[5]);
  return box;
}


void check_output_kind(const fs::path& path, FileKind wanted) {
  if (file_kind(path) != wanted) {
    throw Error(ErrorKind::kInvalidArgument,
                "output must be a tet mesh file (" + supported_tet_mesh_extensions() + ")", path.string());
  }
}

Json mesh_json(const TetMesh& mesh, const MeshQuality& q) {
  const TetAdjacency& adj = mesh.adjacency();
  return Json{
      {"kind", "tet_mesh"},
      {"nodes", mesh.num_nodes()},
      {"tets", mesh.num_tets()},
      {"faces", adj.num_faces()},
      {"boundary_faces", adj.num_boundary_faces()},
      {"edges", adj.num_edges()},
      {"unused_nodes", q.num_unused_nodes},
      {"bbox", {{"min", {q.bbox_min[0], q.bbox_min[1], q.bbox_min[2]}},
                {"max", {q.bbox_max[0], q.bbox_max[1], q.bbox_max[2]}}}},
      {"volume", q.volume},
      {"min_tet_volume", q.min_volume},
      {"min_dihedral_degrees", q.min_dihedral_degrees},
      {"max_dihedral_degrees", q.max_dihedral_degrees},
      {"min_altitude", q.min_altitude},
  };
}

Json surface_json(const TriangleSurface& surface, const SurfaceStats& s) {
  return Json{
      {"kind", "surface"},
      {"vertices", surface.num_vertices()},
      {"triangles", surface.num_triangles()},
      {"bbox", {{"min", {s.bbox_min[0], s.bbox_min[1], s.bbox_min[2]}},
                {"max", {s.bbox_max[0], s.bbox_max[1], s.bbox_max[2]}}}},
      {"area", s.area},
      {"closed", s.closed},
      {"boundary_edges", s.num_boundary_edges},
      {"nonmanifold_edges", s.num_nonmanifold_edges},
      {"degenerate_triangles", s.num_degenerate_triangles},
      {"enclosed_volume", s.enclosed_volume},
  };
}

void print_mesh_summary(const std::string& name, const TetMesh& mesh, const MeshQuality& q) {
  const TetAdjacency& adj = mesh.adjacency();
  fmt::print("{}\n", name);
  fmt::print("  nodes            {}\n", mesh.num_nodes());
  fmt::print("  tets             {}\n", mesh.num_tets());
  fmt::print("  faces            {} ({} on the boundary)\n", adj.num_faces(), adj.num_boundary_faces());
  fmt::print("  edges            {}\n", adj.num_edges());
  if (q.num_unused_nodes > 0) fmt::print("  unused nodes     {}\n", q.num_unused_nodes);
  fmt::print("  bounding box     ({:.6g}, {:.6g}, {:.6g}) - ({:.6g}, {:.6g}, {:.6g})\n", q.bbox_min[0], q.bbox_min[1],
             q.bbox_min[2], q.bbox_max[0], q.bbox_max[1], q.bbox_max[2]);
  fmt::print("  volume           {:.17g}\n", q.volume);
  fmt::print("  dihedral angles  {:.4f} to {:.4f} degrees\n", q.min_dihedral_degrees, q.max_dihedral_degrees);
  fmt::print("  min altitude     {:.6g}\n", q.min_altitude);
}

void print_surface_summary(const std::string& name, const TriangleSurface& surface, const SurfaceStats& s) {
  fmt::print("{}\n", name);
  fmt::print("  vertices         {}\n", surface.num_vertices());
  fmt::print("  triangles        {}\n", surface.num_triangles());
  fmt::print("  bounding box     ({:.6g}, {:.6g}, {:.6g}) - ({:.6g}, {:.6g}, {:.6g})\n", s.bbox_min[0], s.bbox_min[1],
             s.bbox_min[2], s.bbox_max[0], s.bbox_max[1], s.bbox_max[2]);
  fmt::print("  area             {:.17g}\n", s.area);
  fmt::print("  closed           {}", s.closed ? "yes" : "no");
  if (!s.closed) fmt::print(" ({} boundary edges, {} non-manifold edges)", s.num_boundary_edges, s.num_nonmanifold_edges);
  fmt::print("\n");
  if (s.closed) fmt::print("  enclosed volume  {:.17g}\n", s.enclosed_volume);
  if (s.num_degenerate_triangles > 0) fmt::print("  degenerate       {} triangles\n", s.num_degenerate_triangles);
}

struct MeshOutputOptions {
  int msh_version = 41;
  void add(CLI::App* command) {
    command->add_option("--msh-version", msh_version, "Gmsh version for .msh output: 41 or 22")
        ->check(CLI::IsMember({22, 41}));
  }
  TetMeshWriteOptions write_options() const {
    TetMeshWriteOptions options;
    options.gmsh_version = msh_version;
    return options;
  }
};

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

void check_surface_output(const fs::path& path) {
  if (file_kind(path) != FileKind::kSurface) {
    throw Error(ErrorKind::kInvalidArgument, "output must be a surface file (" + supported_surface_extensions() + ")",
                path.string());
  }
}

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

struct NamedBatch {
  std::string name;
  TriangleSurface triangles;
};

// Where a cut's results go; empty paths are not written.
struct CutOutputs {
  fs::path mesh, surface, report;
  bool binary = false;
  bool deformed = false;  // write current (deformed) positions instead of rest positions
  TetMeshWriteOptions mesh_options;

  // Registers --out-mesh, --out-surface, --report (whose contents `report_keys` names) and --binary.
  void add(CLI::App* command, const std::string& report_keys) {
    command->add_option("--out-mesh", mesh,
                        "Write the simulation mesh; .vtu carries original_tet, piece, material_volume and "
                        "material_fraction per tet, .mesh and .msh the piece as a label");
    command->add_option("--out-surface", surface, "Write the material surface (" + supported_surface_extensions() + ")");
    command->add_option("--report", report, "Write a JSON report: " + report_keys);
    command->add_flag("--binary", binary, "Binary PLY or STL surface output");
  }

  // Checks every output before any work, so a typo costs nothing and nothing is half written.
  void check(const std::vector<fs::path>& inputs) const {
    for (const fs::path* output : {&mesh, &surface, &report}) {
      for (const fs::path& input : inputs) {
        if (!output->empty()) check_not_input(*output, input);
      }
    }
    if (!mesh.empty()) check_output_kind(mesh, FileKind::kTetMesh);
    if (!surface.empty()) check_surface_output(surface);
  }
};

// Peak resident memory of this process so far, in bytes (Linux reports kilobytes).
std::int64_t peak_memory_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::int64_t>(usage.ru_maxrss) * 1024;
}

// What a run reports besides the result itself.
struct RunSummary {
  std::string headline;  // the first line printed
  Json report;           // the report's first keys (inputs)
  Index triangles = 0, skipped = 0, inverted = 0;
  bool world_space = false;
  Json timings;          // stages before the surface; surface and write follow
  Json extra;            // keys appended to the report
  bool peak_memory = false;  // report the process's peak resident memory
};

// Writes the outputs of a cut (or an embedding) of `mesh`, prints a summary and writes the report.
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
             surface.watertight ? "closed" : "NOT closed");
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
          {"closed", surface.watertight},
          {"manifold", surface.closed},
          {"enclosed_volume", surface.enclosed_volume}}},
        {"timings", timings},
    });
    if (!run.extra.is_null()) report.update(run.extra);
    if (run.peak_memory) report["peak_memory_bytes"] = peak;
    write_text_file(outputs.report, report.dump(2) + "\n");
  }
}

// Cuts `mesh` by the batches in order, prints warnings and a summary, and writes the outputs. With
// `deformed` positions, the batches are placed in world space on that configuration.
CutResult cut_and_report(const std::string& name, const TetMesh& mesh, const std::vector<NamedBatch>& batches,
                         const CutOutputs& outputs, double read_seconds, const Points* deformed = nullptr) {
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

// The material an embedding keeps, from "--keep inside|largest|point X Y Z".
EmbedOptions keep_option(const std::vector<std::string>& words) {
  EmbedOptions options;
  const std::string& mode = words.empty() ? std::string("inside") : words.front();
  const auto bad = [](const std::string& why) {
    return Error(ErrorKind::kInvalidArgument, "--keep: " + why + " (use: inside, largest, or point X Y Z)");
  };
  if (mode == "inside" || mode == "largest") {
    if (words.size() > 1) throw bad("'" + mode + "' takes no coordinates");
    options.keep = mode == "inside" ? KeepMaterial::kInside : KeepMaterial::kLargest;
    return options;
  }
  if (mode != "point") throw bad("unknown choice '" + mode + "'");
  if (words.size() != 4) throw bad("'point' needs three coordinates");
  options.keep = KeepMaterial::kPoint;
  for (int k = 0; k < 3; ++k) {
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(words[k + 1], &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != words[k + 1].size() || !std::isfinite(value)) throw bad("'" + words[k + 1] + "' is not a finite number");
    options.point[k] = value;
  }
  return options;
}

}  // namespace

void add_embed_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path surface;
    double spacing = std::nan("");  // NaN: not given
    Index cubes = 32;
    fs::path mesh;
    std::vector<std::string> keep;
    CutOutputs outputs;
    MeshOutputOptions out;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "embed", "Carve a surface out of a coarse tet mesh (a BCC lattice around it, or a given mesh): keep only the "
               "material, one tet copy per disjoint part of it, and the surface embedded in the copies");
  command->add_option("SURFACE", options->surface, "Surface to embed (" + supported_surface_extensions() + ")")->required();
  auto* spacing_option = command->add_option("--spacing", options->spacing, "Cube size of the BCC lattice built around the surface");
  auto* cubes_option = command->add_option("--cells", options->cubes,
                                    "BCC cubes along the longest side of the surface's box (default 32)");
  auto* mesh_option = command->add_option("--mesh", options->mesh, "Embed in this tet mesh instead of a lattice");
  spacing_option->excludes(cubes_option)->excludes(mesh_option);
  cubes_option->excludes(mesh_option);
  command->add_option("--keep", options->keep,
                      "What is material: 'inside' a closed surface (default; exact winding number, so a "
                      "self-intersecting surface gives the union), the 'largest' piece, or the piece at 'point X Y Z'")
      ->expected(1, 4);
  options->outputs.add(command, "the keys of 'tetcut cut', the surface check, time per stage, peak memory");
  options->out.add(command);
  command->callback([options, &action] {
    action = [options] {
      const EmbedOptions embed_options = keep_option(options->keep);
      std::vector<fs::path> inputs = {options->surface};
      if (!options->mesh.empty()) inputs.push_back(options->mesh);
      options->outputs.check(inputs);
      options->outputs.mesh_options = options->out.write_options();
      auto start = Clock::now();
      const TriangleSurface surface = read_surface(options->surface);
      if (surface.num_triangles() == 0) throw Error(ErrorKind::kInvalidInput, "the surface has no triangles", options->surface.string());
      const double read_seconds = seconds_since(start);

      start = Clock::now();
      double spacing = options->spacing;
      TetMesh mesh;
      if (!options->mesh.empty()) {
        mesh = read_tet_mesh(options->mesh);
      } else {
        if (std::isnan(spacing)) spacing = spacing_for_cubes(surface, options->cubes);
        mesh = embedding_lattice(surface, spacing);
      }
      const double mesh_seconds = seconds_since(start);

      EmbedReport report;
      Cutter cutter = [&] {
        try {
          return embed(mesh, surface, embed_options, &report);
        } catch (const Error& e) {
          if (e.kind() != ErrorKind::kInvalidInput || !e.file().empty()) throw;
          throw Error(e.kind(), e.message(), options->surface.string());
        }
      }();
      const SurfaceCheck& check = report.check;
      if (check.degenerate_triangles > 0) {
        fmt::print(stderr, "tetcut: warning: {}: skipped {} zero-area triangle(s)\n", options->surface.string(),
                   check.degenerate_triangles);
      }
      start = Clock::now();
      const CutResult result = cutter.result();
      const double result_seconds = seconds_since(start) - result.seconds_surface;

      RunSummary summary;
      const std::string into = options->mesh.empty() ? fmt::format("a BCC lattice of spacing {:.6g}", spacing) : options->mesh.string();
      summary.headline = fmt::format("embedded {} ({} triangles, {} component(s){}) in {}", options->surface.string(),
                                     check.triangles, check.components, check.closed() ? ", closed" : ", open", into);
      summary.report = Json{{"surface_in", options->surface.string()},
                            {"mesh", options->mesh.empty() ? Json(nullptr) : Json(options->mesh.string())},
                            {"lattice_spacing", options->mesh.empty() ? Json(spacing) : Json(nullptr)}};
      summary.triangles = check.triangles;
      summary.skipped = check.degenerate_triangles;
      summary.timings = Json{{"read", read_seconds},
                             {"lattice", mesh_seconds},
                             {"check", report.seconds_check},
                             {"insert", report.seconds_insert},
                             {"classify", report.seconds_classify},
                             {"copies", report.seconds_copies},
                             {"pieces", result_seconds}};
      const char* keep = embed_options.keep == KeepMaterial::kInside    ? "inside"
                         : embed_options.keep == KeepMaterial::kLargest ? "largest"
                                                                        : "point";
      summary.extra = Json{{"embed",
                            {{"keep", keep},
                             {"surface_vertices", check.vertices},
                             {"surface_components", check.components},
                             {"surface_closed", check.closed()},
                             {"boundary_edges", check.boundary_edges},
                             {"nonmanifold_edges", check.nonmanifold_edges},
                             {"tets_with_material", report.tets_with_material},
                             {"tets_duplicated", report.tets_duplicated},
                             {"overlap_polygons_joined", report.covered_facets_joined}}}};
      summary.peak_memory = true;
      write_and_report(mesh, result, options->outputs, summary);
      return 0;
    };
  });
}

namespace {

}  // namespace

void add_grid_command(CLI::App& app, Action& action) {
  struct Options {
    std::vector<Index> cells;
    std::vector<double> box{0, 0, 0, 1, 1, 1};
    int tets_per_cube = 5;
    fs::path output;
    MeshOutputOptions out;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand("grid", "Generate a box of cubes, each split into 5 or 6 tets");
  command->add_option("--cells", options->cells, "Cubes along x, y and z")->expected(3)->required()
      ->check(CLI::Range(1, 10000));
  command->add_option("--box", options->box, "Box corners: x0 y0 z0 x1 y1 z1 (default: the unit cube)")->expected(6);
  command->add_option("--tets-per-cube", options->tets_per_cube, "5 or 6")->check(CLI::IsMember({5, 6}));
  command->add_option("-o,--output", options->output, "Output tet mesh (" + supported_tet_mesh_extensions() + ")")
      ->required();
  options->out.add(command);
  command->callback([options, &action] {
    action = [options] {
      check_output_kind(options->output, FileKind::kTetMesh);
      const TetMesh mesh = make_grid(box_from(options->box), {options->cells[0], options->cells[1], options->cells[2]},
                                     options->tets_per_cube);
      write_tet_mesh(options->output, mesh, options->out.write_options());
      fmt::print("wrote {}: {} nodes, {} tets\n", options->output.string(), mesh.num_nodes(), mesh.num_tets());
      return 0;
    };
  });
}

void add_bcc_command(CLI::App& app, Action& action) {
  struct Options {
    std::vector<double> box;
    double spacing = 0;
    fs::path output;
    MeshOutputOptions out;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand("bcc", "Generate a body-centred cubic lattice of tets covering a box");
  command->add_option("--box", options->box, "Box corners: x0 y0 z0 x1 y1 z1")->expected(6)->required();
  command->add_option("--spacing", options->spacing, "Cube size of the lattice")->required()
      ->check(CLI::PositiveNumber);
  command->add_option("-o,--output", options->output, "Output tet mesh (" + supported_tet_mesh_extensions() + ")")
      ->required();
  options->out.add(command);
  command->callback([options, &action] {
    action = [options] {
      check_output_kind(options->output, FileKind::kTetMesh);
      const TetMesh mesh = make_bcc(box_from(options->box), options->spacing);
      write_tet_mesh(options->output, mesh, options->out.write_options());
      fmt::print("wrote {}: {} nodes, {} tets\n", options->output.string(), mesh.num_nodes(), mesh.num_tets());
      return 0;
    };
  });
}

void add_info_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path input;
    bool json = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand("info", "Print counts, bounding box, volume and element quality of a file");
  command->add_option("FILE", options->input, "Tet mesh or surface file")->required();
  command->add_flag("--json", options->json, "Print one JSON object instead of text");
  command->callback([options, &action] {
    action = [options] {
      const fs::path& path = options->input;
      const FileKind kind = file_kind(path);
      if (kind == FileKind::kTetMesh) {
        const TetMesh mesh = read_tet_mesh(path);
        const MeshQuality q = measure_quality(mesh);
        if (options->json) {
          Json j = mesh_json(mesh, q);
          j["file"] = path.string();
          fmt::print("{}\n", j.dump(2));
        } else {
          print_mesh_summary(path.string(), mesh, q);
        }
      } else if (kind == FileKind::kSurface) {
        const TriangleSurface surface = read_surface(path);
        const SurfaceStats s = measure_surface(surface);
        if (options->json) {
          Json j = surface_json(surface, s);
          j["file"] = path.string();
          fmt::print("{}\n", j.dump(2));
        } else {
          print_surface_summary(path.string(), surface, s);
        }
      } else {
        throw Error(ErrorKind::kInvalidArgument,
                    "unknown file type; tet meshes: " + supported_tet_mesh_extensions() +
                        "; surfaces: " + supported_surface_extensions(),
                    path.string());
      }
      return 0;
    };
  });
}

void add_convert_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path input;
    fs::path output;
    bool binary = false;
    MeshOutputOptions out;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "convert", "Convert between formats; a tet mesh written to a surface format gives its boundary surface");
  command->add_option("IN", options->input, "Input tet mesh or surface")->required();
  command->add_option("OUT", options->output, "Output file; the format follows the extension")->required();
  command->add_flag("--binary", options->binary, "Binary PLY or STL output");
  options->out.add(command);
  command->callback([options, &action] {
    action = [options] {
      check_not_input(options->output, options->input);
      const FileKind in_kind = file_kind(options->input);
      const FileKind out_kind = file_kind(options->output);
      if (out_kind == FileKind::kUnknown) {
        throw Error(ErrorKind::kInvalidArgument,
                    "unknown output format; tet meshes: " + supported_tet_mesh_extensions() +
                        "; surfaces: " + supported_surface_extensions(),
                    options->output.string());
      }
      if (in_kind == FileKind::kTetMesh) {
        const TetMesh mesh = read_tet_mesh(options->input);
        if (out_kind == FileKind::kTetMesh) {
          write_tet_mesh(options->output, mesh, options->out.write_options());
          fmt::print("wrote {}: {} nodes, {} tets\n", options->output.string(), mesh.num_nodes(), mesh.num_tets());
        } else {
          const TriangleSurface surface = boundary_surface(mesh);
          write_surface(options->output, surface, SurfaceWriteOptions{options->binary});
          fmt::print("wrote {}: boundary surface, {} vertices, {} triangles\n", options->output.string(),
                     surface.num_vertices(), surface.num_triangles());
        }
      } else if (in_kind == FileKind::kSurface) {
        if (out_kind != FileKind::kSurface) {
          throw Error(ErrorKind::kInvalidArgument, "a surface cannot be written as a tet mesh (use 'tetcut embed' when it exists)",
                      options->output.string());
        }
        const TriangleSurface surface = read_surface(options->input);
        write_surface(options->output, surface, SurfaceWriteOptions{options->binary});
        fmt::print("wrote {}: {} vertices, {} triangles\n", options->output.string(), surface.num_vertices(),
                   surface.num_triangles());
      } else {
        throw Error(ErrorKind::kInvalidArgument, "unknown input format", options->input.string());
      }
      return 0;
    };
  });
}

void add_cut_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path mesh;
    std::vector<fs::path> cuts;
    fs::path deform;
    CutOutputs outputs;
    MeshOutputOptions out;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "cut", "Cut a tet mesh by triangle soups: each CUT file is one batch of triangles, applied in order to the "
             "rest (undeformed) mesh");
  command->add_option("MESH", options->mesh, "Tet mesh to cut (" + supported_tet_mesh_extensions() + ")")->required();
  command->add_option("CUT", options->cuts, "Cut surfaces, one batch each (" + supported_surface_extensions() + ")")
      ->required()
      ->expected(1, -1);
  options->outputs.add(command, "counts, piece volumes, surface, timings");
  command->add_option("--deform", options->deform,
                      "A tet mesh with the same nodes and tets in deformed positions: the cuts are placed in world "
                      "space on that configuration (tets inverted there are not cut, with a warning)");
  command->add_flag("--write-deformed", options->outputs.deformed,
                    "Write the mesh and surface in their current (deformed) positions instead of rest positions");
  options->out.add(command);
  command->callback([options, &action] {
    action = [options] {
      std::vector<fs::path> inputs = options->cuts;
      inputs.push_back(options->mesh);
      if (!options->deform.empty()) inputs.push_back(options->deform);
      options->outputs.check(inputs);
      const auto start = Clock::now();
      const TetMesh mesh = read_tet_mesh(options->mesh);
      std::vector<NamedBatch> batches;
      for (const fs::path& path : options->cuts) {
        batches.push_back({path.string(), read_surface(path)});
        if (batches.back().triangles.num_triangles() == 0) {
          throw Error(ErrorKind::kInvalidInput, "the cut has no triangles", path.string());
        }
      }
      std::optional<Points> deformed;
      if (!options->deform.empty()) deformed = read_deformed_positions(options->deform, mesh);
      options->outputs.mesh_options = options->out.write_options();
      cut_and_report(options->mesh.string(), mesh, batches, options->outputs, seconds_since(start),
                     deformed ? &*deformed : nullptr);
      return 0;
    };
  });
}

void add_sim_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path scene;
    fs::path out;
    int frames = -1;
    bool png = false;
    fs::path animation;
    double fps = 0;
    bool check_intersections = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "sim", "Simulate a scene (JSON): FEM on the mesh, timed cuts, obstacles, springs, or a cloth cut by polylines; "
             "writes one mesh (.vtu; a cloth's triangle copies as .vtp) and one .vtp surface per output frame, ParaView "
             ".pvd series and summary.json");
  command->add_option("SCENE", options->scene, "Scene file (.json); see include/tetcut/scene.hpp for the format")->required();
  command->add_option("-o,--out", options->out, "Output directory (created)")->required();
  command->add_option("--frames", options->frames, "Stop after this many output frames (a quick look)")
      ->check(CLI::NonNegativeNumber);
  command->add_flag("--png", options->png,
                    "Also render each frame's surface to frame_NNNN.png (pieces coloured; the camera is the scene's "
                    "output.picture, by default framing the first frame grown by half)");
  command->add_option("--animation", options->animation,
                      "Also assemble the frames into an animation with ffmpeg: .mp4 or .gif (implies --png)");
  command->add_option("--fps", options->fps, "Frames per second of the animation (default: real time, 1 / output_every, "
                                             "within 1 to 60)")
      ->check(CLI::Range(0.1, 240.0));
  command->add_flag("--check-intersections", options->check_intersections,
                    "Count, at each output frame, the pairs of material-surface triangles of different tet copies that "
                    "intersect (exact tests; pairs sharing a vertex, or a point of a cut not yet opened, excluded); "
                    "summary.json gives them per frame and their maximum");
  command->callback([options, &action] {
    action = [options] {
      if (!options->animation.empty()) {
        const std::string ext = options->animation.extension().string();
        if (ext != ".mp4" && ext != ".gif") {
          throw Error(ErrorKind::kInvalidArgument, "an animation must be .mp4 or .gif", options->animation.string());
        }
        options->png = true;
      }
      const Scene scene = load_scene(options->scene);
      SceneRunOptions run;
      run.max_frames = options->frames;
      run.check_intersections = options->check_intersections;
      const bool terminal = isatty(fileno(stderr)) != 0;
      const auto start = Clock::now();
      run.progress = [&](int frame, int expected) {
        if (!terminal) return;
        const int total = options->frames >= 0 ? std::min(expected, options->frames) : expected;
        const int width = 30, filled = total > 0 ? std::min(width, width * frame / total) : width;
        const double elapsed = seconds_since(start);
        // Time left at the pace so far (frames take about equally long).
        const std::string left = frame > 0 && frame < total ? fmt::format(", about {:.0f} s left", elapsed * (total - frame) / frame) : "";
        fmt::print(stderr, "\r[{}{}] frame {}/{}  {:.1f} s{}    ", std::string(static_cast<std::size_t>(filled), '#'),
                   std::string(static_cast<std::size_t>(width - filled), ' '), frame, total, elapsed, left);
      };
      Eigen::AlignedBox3d frame_box;
      if (scene.picture_box) frame_box = Eigen::AlignedBox3d(scene.picture_box->min, scene.picture_box->max);
      if (options->png) {
        run.frame_surface = [&](int frame, const SceneFrame& shown) {
          const TriangleSurface& surface = shown.surface;
          if (frame_box.isEmpty()) {
            for (Index v = 0; v < surface.num_vertices(); ++v) frame_box.extend(surface.vertices.row(v).transpose());
            const Vec3 grow = 0.25 * frame_box.sizes();
            frame_box = Eigen::AlignedBox3d(frame_box.min() - grow, frame_box.max() + grow);
          }
          render::RenderOptions render_options;
          render_options.width = scene.picture_width;
          render_options.height = scene.picture_height;
          render_options.frame = frame_box;
          render_options.camera.azimuth_degrees = scene.picture_azimuth;
          render_options.camera.elevation_degrees = scene.picture_elevation;
          render_options.camera.zoom = scene.picture_zoom;
          render_options.line_points = shown.line_points;  // a cloth's triangle copies
          render_options.lines = shown.lines;
          render::write_png(options->out / fmt::format("frame_{:04d}.png", frame), render::render(surface, render_options));
        };
      }
      const SceneSummary summary = run_scene(scene, options->out, run);
      if (terminal) fmt::print(stderr, "\n");
      if (!options->animation.empty()) {
        const double every = scene.output_every > 0 ? scene.output_every : scene.step.dt;
        const double fps = options->fps > 0 ? options->fps : std::clamp(1 / every, 1.0, 60.0);
        render::write_animation(options->out / "frame_%04d.png", fps, options->animation);
        fmt::print("  animation        {} ({} frames at {:g} per second)\n", options->animation.string(), summary.frames, fps);
      }
      fmt::print("simulated {} ({} s in {} steps)\n", options->scene.string(), summary.simulated_seconds, summary.steps);
      fmt::print("  frames           {} in {}\n", summary.frames, options->out.string());
      fmt::print("  cuts             {}\n", summary.cuts_applied);
      if (summary.cloth) {
        fmt::print("  cloth            {} triangle copies of {} triangles, {} nodes, {} pieces\n", summary.triangle_copies,
                   summary.triangles_in, summary.nodes, summary.pieces);
      } else {
        fmt::print("  mesh             {} tets, {} nodes, {} pieces\n", summary.tets, summary.nodes, summary.pieces);
      }
      fmt::print("  time             {:.2f} s, {:.3f} s per frame, {:.2f} Newton iterations per step\n", summary.wall_seconds,
                 summary.seconds_per_frame, summary.mean_newton_iterations);
      const SceneStageSeconds& t = summary.stage_seconds;
      const double per_step = summary.steps > 0 ? 1e3 / summary.steps : 0;
      fmt::print("  ms per step      {:.2f} (cut {:.2f}, surface {:.2f}, remesh {:.2f}, step {:.2f}); median {:.2f}, max {:.2f}\n",
                 (t.cut + t.surface + t.remesh + t.step) * per_step, t.cut * per_step, t.surface * per_step, t.remesh * per_step,
                 t.step * per_step, summary.step_ms_median, summary.step_ms_max);
      if (options->check_intersections) {
        fmt::print("  intersections    at most {} pair(s) of surface triangles of different copies, over {} frames\n",
                   summary.max_intersecting_pairs, summary.intersecting_pairs.size());
      }
      if (summary.unconverged_steps > 0) {
        fmt::print(stderr, "tetcut: warning: {} step(s) stopped before Newton converged\n", summary.unconverged_steps);
      }
      return 0;
    };
  });
}

namespace {

// What `tetcut render` draws from IN: a surface, a tet mesh's boundary (with its edges), or a
// frame of a directory `tetcut sim` wrote (its surface, with its mesh's edges: a tet mesh's, or a
// cloth's triangle copies).
struct RenderInput {
  TriangleSurface surface;
  Points edge_points;  // the edges IN itself offers to --wireframe, if any
  Edges edges;
  std::string name;
};

// The edges of a mesh file: a tet mesh's, or a triangle surface's (a cloth's triangle copies).
void read_edges(const fs::path& path, Points* points, Edges* edges) {
  if (file_kind(path) == FileKind::kTetMesh) {
    const TetMesh mesh = read_tet_mesh(path);
    *points = mesh.rest();
    *edges = render::mesh_edges(mesh);
  } else {
    const TriangleSurface surface = read_surface(path);
    *points = surface.vertices;
    *edges = triangle_edges(surface.triangles);
  }
}

RenderInput render_input(const fs::path& in, int frame) {
  RenderInput r;
  r.name = in.string();
  if (fs::is_directory(in)) {
    if (!fs::exists(in / "surface.pvd")) {
      throw Error(ErrorKind::kInvalidInput, "no surface.pvd here: a directory to render is one that 'tetcut sim' wrote", in.string());
    }
    const std::vector<SeriesEntry> surfaces = read_series(in / "surface.pvd");
    const int last = static_cast<int>(surfaces.size()) - 1;
    if (frame > last) {
      throw Error(ErrorKind::kInvalidArgument, fmt::format("--frame {}: the series has frames 0 to {}", frame, last), in.string());
    }
    const std::size_t f = static_cast<std::size_t>(frame < 0 ? last : frame);
    r.surface = read_surface(surfaces[f].file);
    r.name = surfaces[f].file.string();
    if (fs::exists(in / "mesh.pvd")) {
      const std::vector<SeriesEntry> meshes = read_series(in / "mesh.pvd");
      if (meshes.size() != surfaces.size()) {
        throw Error(ErrorKind::kInvalidInput, "mesh.pvd and surface.pvd list different numbers of frames", in.string());
      }
      read_edges(meshes[f].file, &r.edge_points, &r.edges);  // a frame's mesh holds its current positions
    }
  } else if (file_kind(in) == FileKind::kTetMesh) {
    const TetMesh mesh = read_tet_mesh(in);
    r.surface = boundary_surface(mesh);
    r.edge_points = mesh.rest();
    r.edges = render::mesh_edges(mesh);
  } else {
    r.surface = read_surface(in);
  }
  return r;
}

}  // namespace

void add_render_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path input;
    fs::path out;
    std::vector<int> size{800, 600};
    render::Camera camera;
    bool pieces = false;
    std::vector<std::string> wireframe;
    bool wireframe_given = false;
    int frame = -1;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "render", "Render a surface, a tet mesh (its boundary) or a frame of a 'tetcut sim' directory to a PNG, offscreen "
                "(OpenGL ES through EGL; Mesa's software renderer needs no GPU)");
  command->add_option("IN", options->input,
                      "Surface or tet mesh file, or a directory 'tetcut sim' wrote (a tet or a cloth scene)")
      ->required();
  command->add_option("-o,--out", options->out, "PNG to write")->required();
  command->add_option("--size", options->size, "Width and height in pixels")->expected(2)->check(CLI::Range(1, 16384));
  command->add_option("--azimuth", options->camera.azimuth_degrees, "Camera angle around the z axis, degrees (default 35)");
  command->add_option("--elevation", options->camera.elevation_degrees, "Camera angle above the xy plane, degrees (default 25)");
  command->add_option("--zoom", options->camera.zoom, "1 fits the scene; 2 is twice as close")->check(CLI::PositiveNumber);
  command->add_flag("--pieces", options->pieces, "Colour each piece (connected part) in its own colour");
  command->add_option("--wireframe", options->wireframe,
                      "Draw the edges of a mesh over the surface: of IN when it is a tet mesh or a 'tetcut sim' directory "
                      "(its tets, or a cloth's triangle copies), or of the file given (a tet mesh, or a surface such as "
                      "'tetcut cut2d --copies' writes)")
      ->expected(0, 1);
  command->add_option("--frame", options->frame, "With a 'tetcut sim' directory: the frame to draw (default: the last)")
      ->check(CLI::NonNegativeNumber);
  command->callback([options, command, &action] {
    options->wireframe_given = command->count("--wireframe") > 0;
    action = [options] {
      if (options->out.extension() != ".png") throw Error(ErrorKind::kInvalidArgument, "the output must be a .png file", options->out.string());
      check_not_input(options->out, options->input);
      if (options->frame >= 0 && !fs::is_directory(options->input)) {
        throw Error(ErrorKind::kInvalidArgument, "--frame goes with a directory 'tetcut sim' wrote", options->input.string());
      }
      render::RenderOptions render_options;
      render_options.width = options->size[0];
      render_options.height = options->size[1];
      render_options.camera = options->camera;
      render_options.colour_pieces = options->pieces;
      RenderInput in = render_input(options->input, options->frame);
      if (options->wireframe_given) {
        if (!options->wireframe.empty() && !options->wireframe.front().empty()) {
          read_edges(options->wireframe.front(), &render_options.line_points, &render_options.lines);
        } else if (in.edges.rows() > 0) {
          render_options.line_points = std::move(in.edge_points);
          render_options.lines = std::move(in.edges);
        } else {
          throw Error(ErrorKind::kInvalidArgument,
                      "--wireframe without a file needs IN to be a tet mesh or a 'tetcut sim' directory with meshes",
                      options->input.string());
        }
      }
      const auto start = Clock::now();
      const render::Image image = render::render(in.surface, render_options);
      render::write_png(options->out, image);
      fmt::print("rendered {} ({} triangles{}) to {} ({} x {}) in {:.2f} s\n", in.name, in.surface.num_triangles(),
                 options->wireframe_given ? fmt::format(", {} edges", render_options.lines.rows()) : std::string(),
                 options->out.string(), image.width, image.height, seconds_since(start));
      return 0;
    };
  });
}

void add_view_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path input;
    fs::path out;
    fs::path mesh;
    std::string title;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "view", "Write a web page that shows a result in any browser, offline (three.js inlined): orbit, colour by "
              "piece, toggle the embedding tets (or a cloth's triangle copies), step through a simulation's frames");
  command->add_option("IN", options->input,
                      "A directory 'tetcut sim' wrote (its frames, with the edges of its tets or of a cloth's triangle "
                      "copies), a surface (e.g. what 'tetcut cut2d -o' writes), or a tet mesh")
      ->required();
  command->add_option("-o,--out", options->out, "The page to write (default: IN/view.html for a directory, IN.html for a file)");
  command->add_option("--mesh", options->mesh,
                      "A mesh whose edges to show with a surface file: a tet mesh, or a surface such as 'tetcut cut2d "
                      "--copies' writes (the triangle copies)");
  command->add_option("--title", options->title, "The page's title (default: IN's name)");
  command->callback([options, &action] {
    action = [options] {
      const fs::path& in = options->input;
      if (!fs::exists(in)) throw Error(ErrorKind::kIo, "no such file or directory", in.string());
      const bool directory = fs::is_directory(in);
      fs::path out = options->out;
      if (out.empty()) out = directory ? in / "view.html" : fs::path(in).replace_extension(".html");
      if (out.extension() != ".html") throw Error(ErrorKind::kInvalidArgument, "the page must be a .html file", out.string());
      if (!directory) check_not_input(out, in);
      const auto start = Clock::now();
      const std::vector<view::ViewFrame> frames = view::load_frames(in, options->mesh);
      // The title names what is shown: the file, or the directory ("out/run/" gives "run").
      fs::path named = fs::absolute(in).lexically_normal();
      if (named.filename().empty()) named = named.parent_path();
      const std::string title = !options->title.empty() ? options->title : named.filename().string();
      view::write_page(out, title.empty() ? in.string() : title, frames);
      const bool edges = std::any_of(frames.begin(), frames.end(), [](const view::ViewFrame& f) { return f.mesh_edges.rows() > 0; });
      const bool copies = std::any_of(frames.begin(), frames.end(), [](const view::ViewFrame& f) { return f.mesh_triangles; });
      fmt::print("wrote {} ({} frame{}{}, {:.1f} MB) in {:.2f} s; open it in a browser\n", out.string(), frames.size(),
                 frames.size() == 1 ? "" : "s", !edges ? "" : copies ? ", with triangle-copy edges" : ", with tet edges",
                 static_cast<double>(fs::file_size(out)) / 1e6, seconds_since(start));
      return 0;
    };
  });
}

void add_demo_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path directory = "out";
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "demo", "The default job, no input needed: the paper's Figure 4 (the 320-tet cube cut by 32 planes into 289 "
              "sticks) and Figure 2 (one tet cut by 50 random triangles), with summaries, meshes, surfaces and reports");
  command->add_option("-o,--output-dir", options->directory, "Directory for the outputs (created if missing)");
  command->callback([options, &action] {
    action = [options] {
      fs::create_directories(options->directory);
      const fs::path& dir = options->directory;
      CutOutputs figure4;
      figure4.mesh = dir / "figure4.vtu";
      figure4.surface = dir / "figure4_surface.obj";
      figure4.report = dir / "figure4_report.json";
      cut_and_report("figure 4: 4x4x4 grid of 5-tet cubes", figures::figure4_cube(),
                     {{"16 + 16 planes x, y = i/17", figures::figure4_planes()}}, figure4, 0);
      fmt::print("\n");
      CutOutputs figure2;
      figure2.mesh = dir / "figure2.vtu";
      figure2.surface = dir / "figure2_surface.obj";
      figure2.report = dir / "figure2_report.json";
      cut_and_report("figure 2: one tet", figures::figure2_tet(), {{"50 random triangles", figures::figure2_triangles()}},
                     figure2, 0);
      fmt::print("\nOpen the .vtu files in ParaView and colour by 'piece'; the .obj files are the material surfaces.\n");
      return 0;
    };
  });
}

}  // namespace tetcut::cli
