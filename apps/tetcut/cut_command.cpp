// tetcut cut: a tet mesh cut by triangle soups, batch by batch, in rest space or placed on a
// deformed configuration (see include/tetcut/cutter.hpp).

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>

#include <memory>
#include <optional>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "cut_report.hpp"

namespace tetcut::cli {

namespace {

struct CutOptions {
  fs::path mesh;
  std::vector<fs::path> cuts;
  fs::path deform;
  CutOutputs outputs;
  MeshOutputOptions out;
};

int run_cut(CutOptions& options) {
  std::vector<fs::path> inputs = options.cuts;
  inputs.push_back(options.mesh);
  if (!options.deform.empty()) inputs.push_back(options.deform);
  options.outputs.check(inputs);
  const auto start = Clock::now();
  const TetMesh mesh = read_tet_mesh(options.mesh);
  std::vector<NamedBatch> batches;
  for (const fs::path& path : options.cuts) {
    batches.push_back({path.string(), read_surface(path)});
    if (batches.back().triangles.num_triangles() == 0) {
      throw Error(ErrorKind::kInvalidInput, "the cut has no triangles", path.string());
    }
  }
  std::optional<Points> deformed;
  if (!options.deform.empty()) deformed = read_deformed_positions(options.deform, mesh);
  options.outputs.mesh_options = options.out.write_options();
  cut_and_report(options.mesh.string(), mesh, batches, options.outputs, seconds_since(start),
                 deformed ? &*deformed : nullptr);
  return 0;
}

}  // namespace

void add_cut_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<CutOptions>();
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
  command->callback([options, &action] { action = [options] { return run_cut(*options); }; });
}

}  // namespace tetcut::cli
