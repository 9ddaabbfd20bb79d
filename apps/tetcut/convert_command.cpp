// tetcut convert: between file formats; a tet mesh written to a surface format gives its boundary.

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>

#include <fmt/core.h>

#include <memory>

#include "commands.hpp"
#include "common.hpp"

namespace tetcut::cli {

namespace {

struct ConvertOptions {
  fs::path input;
  fs::path output;
  bool binary = false;
  MeshOutputOptions out;
};

int run_convert(const ConvertOptions& options) {
  check_not_input(options.output, options.input);
  const FileKind in_kind = file_kind(options.input);
  const FileKind out_kind = file_kind(options.output);
  if (out_kind == FileKind::kUnknown) {
    throw Error(ErrorKind::kInvalidArgument,
                "unknown output format; tet meshes: " + supported_tet_mesh_extensions() +
                    "; surfaces: " + supported_surface_extensions(),
                options.output.string());
  }
  if (in_kind == FileKind::kTetMesh) {
    const TetMesh mesh = read_tet_mesh(options.input);
    if (out_kind == FileKind::kTetMesh) {
      write_tet_mesh(options.output, mesh, options.out.write_options());
      fmt::print("wrote {}: {} nodes, {} tets\n", options.output.string(), mesh.num_nodes(), mesh.num_tets());
    } else {
      const TriangleSurface surface = boundary_surface(mesh);
      write_surface(options.output, surface, SurfaceWriteOptions{options.binary});
      fmt::print("wrote {}: boundary surface, {} vertices, {} triangles\n", options.output.string(),
                 surface.num_vertices(), surface.num_triangles());
    }
  } else if (in_kind == FileKind::kSurface) {
    if (out_kind != FileKind::kSurface) {
      throw Error(ErrorKind::kInvalidArgument, "a surface cannot be written as a tet mesh (use 'tetcut embed' when it exists)",
                  options.output.string());
    }
    const TriangleSurface surface = read_surface(options.input);
    write_surface(options.output, surface, SurfaceWriteOptions{options.binary});
    fmt::print("wrote {}: {} vertices, {} triangles\n", options.output.string(), surface.num_vertices(),
               surface.num_triangles());
  } else {
    throw Error(ErrorKind::kInvalidArgument, "unknown input format", options.input.string());
  }
  return 0;
}

}  // namespace

void add_convert_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* command = app.add_subcommand(
      "convert", "Convert between formats; a tet mesh written to a surface format gives its boundary surface");
  command->add_option("IN", options->input, "Input tet mesh or surface")->required();
  command->add_option("OUT", options->output, "Output file; the format follows the extension")->required();
  command->add_flag("--binary", options->binary, "Binary PLY or STL output");
  options->out.add(command);
  command->callback([options, &action] { action = [options] { return run_convert(*options); }; });
}

}  // namespace tetcut::cli
