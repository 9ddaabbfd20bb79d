// tetcut grid: a box of cubes, each split into 5 or 6 tets (see include/tetcut/generators.hpp).

#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>

#include <fmt/core.h>

#include <memory>
#include <vector>

#include "commands.hpp"
#include "common.hpp"

namespace tetcut::cli {

namespace {

struct GridOptions {
  std::vector<Index> cells;
  std::vector<double> box{0, 0, 0, 1, 1, 1};
  int tets_per_cube = 5;
  fs::path output;
  MeshOutputOptions out;
};

int run_grid(const GridOptions& options) {
  check_tet_mesh_output(options.output);
  const TetMesh mesh = make_grid(box_from(options.box), {options.cells[0], options.cells[1], options.cells[2]},
                                 options.tets_per_cube);
  write_tet_mesh(options.output, mesh, options.out.write_options());
  fmt::print("wrote {}: {} nodes, {} tets\n", options.output.string(), mesh.num_nodes(), mesh.num_tets());
  return 0;
}

}  // namespace

void add_grid_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<GridOptions>();
  CLI::App* command = app.add_subcommand("grid", "Generate a box of cubes, each split into 5 or 6 tets");
  command->add_option("--cells", options->cells, "Cubes along x, y and z")->expected(3)->required()
      ->check(CLI::Range(1, 10000));
  command->add_option("--box", options->box, "Box corners: x0 y0 z0 x1 y1 z1 (default: the unit cube)")->expected(6);
  command->add_option("--tets-per-cube", options->tets_per_cube, "5 or 6")->check(CLI::IsMember({5, 6}));
  command->add_option("-o,--output", options->output, "Output tet mesh (" + supported_tet_mesh_extensions() + ")")
      ->required();
  options->out.add(command);
  command->callback([options, &action] { action = [options] { return run_grid(*options); }; });
}

}  // namespace tetcut::cli
