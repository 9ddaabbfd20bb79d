#pragma once
// Subcommands of the tetcut command-line tool, one file each (<name>_command.cpp). Each registers
// its options on the CLI11 app and runs when selected; errors propagate as tetcut::Error and become
// messages and exit codes in main. What several share is in common.hpp and cut_report.hpp.

#include <CLI/CLI.hpp>

#include <functional>

namespace tetcut::cli {

/// The action of the chosen subcommand; returns the exit code.
using Action = std::function<int()>;

void add_grid_command(CLI::App& app, Action& action);
void add_bcc_command(CLI::App& app, Action& action);
void add_info_command(CLI::App& app, Action& action);
void add_convert_command(CLI::App& app, Action& action);
void add_cut_command(CLI::App& app, Action& action);
void add_embed_command(CLI::App& app, Action& action);
void add_sim_command(CLI::App& app, Action& action);
void add_render_command(CLI::App& app, Action& action);
void add_view_command(CLI::App& app, Action& action);
void add_demo_command(CLI::App& app, Action& action);
void add_serve_command(CLI::App& app, Action& action);
void add_cut2d_command(CLI::App& app, Action& action);

}  // namespace tetcut::cli
