// tetcut embed: a surface carved out of a BCC lattice or a given tet mesh (see
// include/tetcut/embed.hpp), reported as tetcut cut reports, with the surface check and the time
// of each stage.

#include <tetcut/embed.hpp>
#include <tetcut/error.hpp>
#include <tetcut/io.hpp>

#include <fmt/core.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "cut_report.hpp"

namespace tetcut::cli {

namespace {

// The material an embedding keeps, from "--keep inside|largest|point X Y Z".
EmbedOptions keep_option(const std::vector<std::string>& words) {
  EmbedOptions options;
  const std::string& mode = words.empty() ? std::string("inside") : words.front();
  const auto bad = [](const std::string& why) {
    return Error(ErrorKind::kInvalidArgument, "--keep: " + why + " (use: inside, largest, or point X Y Z)");
  };
  const std::optional<KeepMaterial> keep = keep_material_from_name(mode);
  if (!keep) throw bad("unknown choice '" + mode + "'");
  options.keep = *keep;
  if (*keep != KeepMaterial::kPoint) {
    if (words.size() > 1) throw bad("'" + mode + "' takes no coordinates");
    return options;
  }
  if (words.size() != 4) throw bad("'point' needs three coordinates");
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

struct EmbedCommandOptions {
  fs::path surface;
  double spacing = std::nan("");  // NaN: not given
  Index cubes = 32;
  fs::path mesh;
  std::vector<std::string> keep;
  CutOutputs outputs;
  MeshOutputOptions out;
};

// embed(), with the surface's file named in its errors about the surface (the library's name none).
Cutter embed_naming_surface(TetMesh mesh, const TriangleSurface& surface, const EmbedOptions& embed_options,
                            const fs::path& surface_file, EmbedReport* report) {
  try {
    return embed(std::move(mesh), surface, embed_options, report);
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::kInvalidInput || !e.file().empty()) throw;
    throw Error(e.kind(), e.message(), surface_file.string());
  }
}

// What tetcut embed prints and adds to the cut report: the surface check and the embedding's counts.
RunSummary embed_summary(const EmbedCommandOptions& options, const EmbedOptions& embed_options, const EmbedReport& report,
                         double spacing) {
  const SurfaceCheck& check = report.check;
  RunSummary summary;
  const std::string into = options.mesh.empty() ? fmt::format("a BCC lattice of spacing {:.6g}", spacing) : options.mesh.string();
  summary.headline = fmt::format("embedded {} ({} triangles, {} component(s){}) in {}", options.surface.string(),
                                 check.triangles, check.components, check.balanced() ? ", balanced" : ", not balanced", into);
  summary.report = Json{{"surface_in", options.surface.string()},
                        {"mesh", options.mesh.empty() ? Json(nullptr) : Json(options.mesh.string())},
                        {"lattice_spacing", options.mesh.empty() ? Json(spacing) : Json(nullptr)}};
  summary.triangles = check.triangles;
  summary.skipped = check.degenerate_triangles;
  summary.extra = Json{{"embed",
                        {{"keep", keep_material_name(embed_options.keep)},
                         {"surface_vertices", check.vertices},
                         {"surface_components", check.components},
                         {"surface_balanced", check.balanced()},
                         {"unbalanced_edges", check.unbalanced_edges},
                         {"nonmanifold_edges", check.nonmanifold_edges},
                         {"tets_with_material", report.tets_with_material},
                         {"tets_duplicated", report.tets_duplicated},
                         {"overlap_polygons_joined", report.covered_facets_joined}}}};
  summary.peak_memory = true;
  return summary;
}

int run_embed(EmbedCommandOptions& options) {
  const EmbedOptions embed_options = keep_option(options.keep);
  std::vector<fs::path> inputs = {options.surface};
  if (!options.mesh.empty()) inputs.push_back(options.mesh);
  options.outputs.check(inputs);
  options.outputs.mesh_options = options.out.write_options();
  auto start = Clock::now();
  const TriangleSurface surface = read_surface(options.surface);
  if (surface.num_triangles() == 0) throw Error(ErrorKind::kInvalidInput, "the surface has no triangles", options.surface.string());
  const double read_seconds = seconds_since(start);

  start = Clock::now();
  double spacing = options.spacing;
  TetMesh mesh;
  if (!options.mesh.empty()) {
    mesh = read_tet_mesh(options.mesh);
  } else {
    if (std::isnan(spacing)) spacing = spacing_for_cubes(surface, options.cubes);
    mesh = embedding_lattice(surface, spacing);
  }
  const double mesh_seconds = seconds_since(start);

  EmbedReport report;
  Cutter cutter = embed_naming_surface(mesh, surface, embed_options, options.surface, &report);
  if (report.check.degenerate_triangles > 0) {
    fmt::print(stderr, "tetcut: warning: {}: skipped {} zero-area triangle(s)\n", options.surface.string(),
               report.check.degenerate_triangles);
  }
  start = Clock::now();
  const CutResult result = cutter.result();
  const double result_seconds = seconds_since(start) - result.seconds_surface;

  RunSummary summary = embed_summary(options, embed_options, report, spacing);
  summary.timings = Json{{"read", read_seconds},
                         {"lattice", mesh_seconds},
                         {"check", report.seconds_check},
                         {"insert", report.seconds_insert},
                         {"classify", report.seconds_classify},
                         {"copies", report.seconds_copies},
                         {"pieces", result_seconds}};
  write_and_report(mesh, result, options.outputs, summary);
  return 0;
}

}  // namespace

void add_embed_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<EmbedCommandOptions>();
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
  command->callback([options, &action] { action = [options] { return run_embed(*options); }; });
}

}  // namespace tetcut::cli
