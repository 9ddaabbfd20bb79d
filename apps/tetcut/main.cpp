// tetcut: cut tetrahedral meshes by triangle soups. Exit codes: 0 success, 2 bad input or usage,
// 1 an unexpected internal failure.

#include <tetcut/error.hpp>

#include <fmt/core.h>

#include <cstdio>
#include <exception>

#include "commands.hpp"

namespace {

constexpr int kExitBadInput = 2;
constexpr int kExitInternal = 1;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tetcut: exact cutting of tetrahedral meshes by triangle soups"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "tetcut 0.1.0");
  tetcut::cli::Action action;
  tetcut::cli::add_grid_command(app, action);
  tetcut::cli::add_bcc_command(app, action);
  tetcut::cli::add_info_command(app, action);
  tetcut::cli::add_convert_command(app, action);
  tetcut::cli::add_cut_command(app, action);
  tetcut::cli::add_cut2d_command(app, action);
  tetcut::cli::add_embed_command(app, action);
  tetcut::cli::add_sim_command(app, action);
  tetcut::cli::add_render_command(app, action);
  tetcut::cli::add_view_command(app, action);
  tetcut::cli::add_demo_command(app, action);
  tetcut::cli::add_serve_command(app, action);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    fmt::print(stderr, "tetcut: error: {}\nRun 'tetcut --help' (or 'tetcut COMMAND --help') for usage.\n", e.what());
    return kExitBadInput;
  }
  try {
    return action();
  } catch (const tetcut::Error& e) {
    if (e.kind() == tetcut::ErrorKind::kInternal) {
      fmt::print(stderr, "tetcut: internal error: {}\n", e.what());
      return kExitInternal;
    }
    fmt::print(stderr, "tetcut: error: {}\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    fmt::print(stderr, "tetcut: internal error: {}\n", e.what());
    return kExitInternal;
  }
}
