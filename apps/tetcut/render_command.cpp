// tetcut render: a surface, a tet mesh's boundary or a frame of a tetcut sim directory drawn to a
// PNG offscreen (see include/tetcut/render.hpp).

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>
#include <tetcut/render.hpp>

#include <fmt/core.h>

#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"

namespace tetcut::cli {

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

// The picture's size unless --size says: SVGA, a still worth a closer look than a frame of
// tetcut sim (640 x 480), and quick for Mesa's software renderer.
constexpr int kDefaultWidth = 800, kDefaultHeight = 600;

struct RenderCommandOptions {
  fs::path input;
  fs::path out;
  std::vector<int> size{kDefaultWidth, kDefaultHeight};
  render::Camera camera;
  bool pieces = false;
  std::vector<std::string> wireframe;
  bool wireframe_given = false;
  int frame = -1;
};

int run_render(const RenderCommandOptions& options) {
  if (options.out.extension() != ".png") throw Error(ErrorKind::kInvalidArgument, "the output must be a .png file", options.out.string());
  check_not_input(options.out, options.input);
  if (options.frame >= 0 && !fs::is_directory(options.input)) {
    throw Error(ErrorKind::kInvalidArgument, "--frame goes with a directory 'tetcut sim' wrote", options.input.string());
  }
  render::RenderOptions render_options;
  render_options.width = options.size[0];
  render_options.height = options.size[1];
  render_options.camera = options.camera;
  render_options.colour_pieces = options.pieces;
  RenderInput in = render_input(options.input, options.frame);
  if (options.wireframe_given) {
    if (!options.wireframe.empty() && !options.wireframe.front().empty()) {
      read_edges(options.wireframe.front(), &render_options.line_points, &render_options.lines);
    } else if (in.edges.rows() > 0) {
      render_options.line_points = std::move(in.edge_points);
      render_options.lines = std::move(in.edges);
    } else {
      throw Error(ErrorKind::kInvalidArgument,
                  "--wireframe without a file needs IN to be a tet mesh or a 'tetcut sim' directory with meshes",
                  options.input.string());
    }
  }
  const auto start = Clock::now();
  const render::Image image = render::render(in.surface, render_options);
  render::write_png(options.out, image);
  fmt::print("rendered {} ({} triangles{}) to {} ({} x {}) in {:.2f} s\n", in.name, in.surface.num_triangles(),
             options.wireframe_given ? fmt::format(", {} edges", render_options.lines.rows()) : std::string(),
             options.out.string(), image.width, image.height, seconds_since(start));
  return 0;
}

}  // namespace

void add_render_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<RenderCommandOptions>();
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
    action = [options] { return run_render(*options); };
  });
}

}  // namespace tetcut::cli
