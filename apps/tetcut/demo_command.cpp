// tetcut demo: the paper's Figures 4 and 2, cut with no input needed.

#include <tetcut/figures.hpp>

#include <fmt/core.h>

#include <memory>

#include "commands.hpp"
#include "common.hpp"
#include "cut_report.hpp"

namespace tetcut::cli {

namespace {

struct DemoOptions {
  fs::path directory = "out";
};

int run_demo(const DemoOptions& options) {
  fs::create_directories(options.directory);
  const fs::path& dir = options.directory;
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
}

}  // namespace

void add_demo_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* command = app.add_subcommand(
      "demo", "The default job, no input needed: the paper's Figure 4 (the 320-tet cube cut by 32 planes into 289 "
              "sticks) and Figure 2 (one tet cut by 50 random triangles), with summaries, meshes, surfaces and reports");
  command->add_option("-o,--output-dir", options->directory, "Directory for the outputs (created if missing)");
  command->callback([options, &action] { action = [options] { return run_demo(*options); }; });
}

}  // namespace tetcut::cli
