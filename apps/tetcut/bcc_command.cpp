// tetcut bcc: a body-centred cubic lattice of tets covering a box (see include/tetcut/generators.hpp).

#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>

#include <fmt/core.h>

#include <memory>
#include <vector>

#include "commands.hpp"
#include "common.hpp"

namespace tetcut::cli {

namespace {

struct BccOptions {
  std::vector<double> box;
  double spacing = 0;
  fs::path output;
  MeshOutputOptions out;
};

int run_bcc(const BccOptions& options) {
  check_tet_mesh_output(options.output);
  const TetMesh mesh = make_bcc(box_from(options.box), options.spacing);
  write_tet_mesh(options.output, mesh, options.out.write_options());
  fmt::print("wrote {}: {} nodes, {} tets\n", options.output.string(), mesh.num_nodes(), mesh.num_tets());
  return 0;
}

}  // namespace

void add_bcc_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<BccOptions>();
  CLI::App* command = app.add_subcommand("bcc", "Generate a body-centred cubic lattice of tets covering a box");
  command->add_option("--box", options->box, "Box corners: x0 y0 z0 x1 y1 z1")->expected(6)->required();
  command->add_option("--spacing", options->spacing, "Cube size of the lattice")->required()
      ->check(CLI::PositiveNumber);
  command->add_option("-o,--output", options->output, "Output tet mesh (" + supported_tet_mesh_extensions() + ")")
      ->required();
  options->out.add(command);
  command->callback([options, &action] { action = [options] { return run_bcc(*options); }; });
}

}  // namespace tetcut::cli
