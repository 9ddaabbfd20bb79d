#pragma once
// What the subcommands share: checks of output paths, the options every tet mesh writer takes,
// the JSON type of reports, and the library's clock (util/stopwatch.hpp) for their timings.

#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

#include "util/stopwatch.hpp"

namespace tetcut::cli {

namespace fs = std::filesystem;

/// Reports keep their keys in the order written.
using Json = nlohmann::ordered_json;

/// Rejects an output path that names an input: writing would replace the data being read.
void check_not_input(const fs::path& output, const fs::path& input);

/// Rejects an output path whose extension is not a tet mesh format.
void check_tet_mesh_output(const fs::path& path);

/// Rejects an output path whose extension is not a surface format.
void check_surface_output(const fs::path& path);

/// The box of "--box x0 y0 z0 x1 y1 z1" (six values, as CLI11 checked).
Box box_from(const std::vector<double>& corners);

/// --msh-version, for the commands that write tet meshes.
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

}  // namespace tetcut::cli
