#include "commands.hpp"

#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>
#include <tetcut/quality.hpp>

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace tetcut::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

Box box_from(const std::vector<double>& b) {
  Box box;
  box.min = Vec3(b[0], b[1], b[2]);
  box.max = Vec3(b[3], b[4], b[5]);
  return box;
}

// Rejects an output path that names an input: writing would replace the data being read.
void check_not_input(const fs::path& output, const fs::path& input) {
  std::error_code ec;
  if (fs::exists(output, ec) && fs::equivalent(output, input, ec)) {
    throw Error(ErrorKind::kInvalidArgument, "the output would overwrite the input file", output.string());
  }
}

void check_output_kind(const fs::path& path, FileKind wanted) {
  if (file_kind(path) != wanted) {
    throw Error(ErrorKind::kInvalidArgument,
                "output must be a tet mesh file (" + supported_tet_mesh_extensions() + ")", path.string());
  }
}

Json mesh_json(const TetMesh& mesh, const MeshQuality& q) {
  const TetAdjacency& adj = mesh.adjacency();
  return Json{
      {"kind", "tet_mesh"},
      {"nodes", mesh.num_nodes()},
      {"tets", mesh.num_tets()},
      {"faces", adj.num_faces()},
      {"boundary_faces", adj.num_boundary_faces()},
      {"edges", adj.num_edges()},
      {"unused_nodes", q.num_unused_nodes},
      {"bbox", {{"min", {q.bbox_min[0], q.bbox_min[1], q.bbox_min[2]}},
                {"max", {q.bbox_max[0], q.bbox_max[1], q.bbox_max[2]}}}},
      {"volume", q.volume},
      {"min_tet_volume", q.min_volume},
      {"min_dihedral_degrees", q.min_dihedral_degrees},
      {"max_dihedral_degrees", q.max_dihedral_degrees},
      {"min_altitude", q.min_altitude},
  };
}

Json surface_json(const TriangleSurface& surface, const SurfaceStats& s) {
  return Json{
      {"kind", "surface"},
      {"vertices", surface.num_vertices()},
      {"triangles", surface.num_triangles()},
      {"bbox", {{"min", {s.bbox_min[0], s.bbox_min[1], s.bbox_min[2]}},
                {"max", {s.bbox_max[0], s.bbox_max[1], s.bbox_max[2]}}}},
      {"area", s.area},
      {"closed", s.closed},
      {"boundary_edges", s.num_boundary_edges},
      {"nonmanifold_edges", s.num_nonmanifold_edges},
      {"degenerate_triangles", s.num_degenerate_triangles},
      {"enclosed_volume", s.enclosed_volume},
  };
}

void print_mesh_summary(const std::string& name, const TetMesh& mesh, const MeshQuality& q) {
  const TetAdjacency& adj = mesh.adjacency();
  fmt::print("{}\n", name);
  fmt::print("  nodes            {}\n", mesh.num_nodes());
  fmt::print("  tets             {}\n", mesh.num_tets());
  fmt::print("  faces            {} ({} on the boundary)\n", adj.num_faces(), adj.num_boundary_faces());
  fmt::print("  edges            {}\n", adj.num_edges());
  if (q.num_unused_nodes > 0) fmt::print("  unused nodes     {}\n", q.num_unused_nodes);
  fmt::print("  bounding box     ({:.6g}, {:.6g}, {:.6g}) - ({:.6g}, {:.6g}, {:.6g})\n", q.bbox_min[0], q.bbox_min[1],
             q.bbox_min[2], q.bbox_max[0], q.bbox_max[1], q.bbox_max[2]);
  fmt::print("  volume           {:.17g}\n", q.volume);
  fmt::print("  dihedral angles  {:.4f} to {:.4f} degrees\n", q.min_dihedral_degrees, q.max_dihedral_degrees);
  fmt::print("  min altitude     {:.6g}\n", q.min_altitude);
}

void print_surface_summary(const std::string& name, const TriangleSurface& surface, const SurfaceStats& s) {
  fmt::print("{}\n", name);
  fmt::print("  vertices         {}\n", surface.num_vertices());
  fmt::print("  triangles        {}\n", surface.num_triangles());
  fmt::print("  bounding box     ({:.6g}, {:.6g}, {:.6g}) - ({:.6g}, {:.6g}, {:.6g})\n", s.bbox_min[0], s.bbox_min[1],
             s.bbox_min[2], s.bbox_max[0], s.bbox_max[1], s.bbox_max[2]);
  fmt::print("  area             {:.17g}\n", s.area);
  fmt::print("  closed           {}", s.closed ? "yes" : "no");
  if (!s.closed) fmt::print(" ({} boundary edges, {} non-manifold edges)", s.num_boundary_edges, s.num_nonmanifold_edges);
  fmt::print("\n");
  if (s.closed) fmt::print("  enclosed volume  {:.17g}\n", s.enclosed_volume);
  if (s.num_degenerate_triangles > 0) fmt::print("  degenerate       {} triangles\n", s.num_degenerate_triangles);
}

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

}  // namespace

void add_grid_command(CLI::App& app, Action& action) {
  struct Options {
    std::vector<Index> cells;
    std::vector<double> box{0, 0, 0, 1, 1, 1};
    int tets_per_cube = 5;
    fs::path output;
    MeshOutputOptions out;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand("grid", "Generate a box of cubes, each split into 5 or 6 tets");
  command->add_option("--cells", options->cells, "Cubes along x, y and z")->expected(3)->required()
      ->check(CLI::Range(1, 10000));
  command->add_option("--box", options->box, "Box corners: x0 y0 z0 x1 y1 z1 (default: the unit cube)")->expected(6);
  command->add_option("--tets-per-cube", options->tets_per_cube, "5 or 6")->check(CLI::IsMember({5, 6}));
  command->add_option("-o,--output", options->output, "Output tet mesh (" + supported_tet_mesh_extensions() + ")")
      ->required();
  options->out.add(command);
  command->callback([options, &action] {
    action = [options] {
      check_output_kind(options->output, FileKind::kTetMesh);
      const TetMesh mesh = make_grid(box_from(options->box), {options->cells[0], options->cells[1], options->cells[2]},
                                     options->tets_per_cube);
      write_tet_mesh(options->output, mesh, options->out.write_options());
      fmt::print("wrote {}: {} nodes, {} tets\n", options->output.string(), mesh.num_nodes(), mesh.num_tets());
      return 0;
    };
  });
}

void add_bcc_command(CLI::App& app, Action& action) {
  struct Options {
    std::vector<double> box;
    double spacing = 0;
    fs::path output;
    MeshOutputOptions out;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand("bcc", "Generate a body-centred cubic lattice of tets covering a box");
  command->add_option("--box", options->box, "Box corners: x0 y0 z0 x1 y1 z1")->expected(6)->required();
  command->add_option("--spacing", options->spacing, "Cube size of the lattice")->required()
      ->check(CLI::PositiveNumber);
  command->add_option("-o,--output", options->output, "Output tet mesh (" + supported_tet_mesh_extensions() + ")")
      ->required();
  options->out.add(command);
  command->callback([options, &action] {
    action = [options] {
      check_output_kind(options->output, FileKind::kTetMesh);
      const TetMesh mesh = make_bcc(box_from(options->box), options->spacing);
      write_tet_mesh(options->output, mesh, options->out.write_options());
      fmt::print("wrote {}: {} nodes, {} tets\n", options->output.string(), mesh.num_nodes(), mesh.num_tets());
      return 0;
    };
  });
}

void add_info_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path input;
    bool json = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand("info", "Print counts, bounding box, volume and element quality of a file");
  command->add_option("FILE", options->input, "Tet mesh or surface file")->required();
  command->add_flag("--json", options->json, "Print one JSON object instead of text");
  command->callback([options, &action] {
    action = [options] {
      const fs::path& path = options->input;
      const FileKind kind = file_kind(path);
      if (kind == FileKind::kTetMesh) {
        const TetMesh mesh = read_tet_mesh(path);
        const MeshQuality q = measure_quality(mesh);
        if (options->json) {
          Json j = mesh_json(mesh, q);
          j["file"] = path.string();
          fmt::print("{}\n", j.dump(2));
        } else {
          print_mesh_summary(path.string(), mesh, q);
        }
      } else if (kind == FileKind::kSurface) {
        const TriangleSurface surface = read_surface(path);
        const SurfaceStats s = measure_surface(surface);
        if (options->json) {
          Json j = surface_json(surface, s);
          j["file"] = path.string();
          fmt::print("{}\n", j.dump(2));
        } else {
          print_surface_summary(path.string(), surface, s);
        }
      } else {
        throw Error(ErrorKind::kInvalidArgument,
                    "unknown file type; tet meshes: " + supported_tet_mesh_extensions() +
                        "; surfaces: " + supported_surface_extensions(),
                    path.string());
      }
      return 0;
    };
  });
}

void add_convert_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path input;
    fs::path output;
    bool binary = false;
    MeshOutputOptions out;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "convert", "Convert between formats; a tet mesh written to a surface format gives its boundary surface");
  command->add_option("IN", options->input, "Input tet mesh or surface")->required();
  command->add_option("OUT", options->output, "Output file; the format follows the extension")->required();
  command->add_flag("--binary", options->binary, "Binary PLY or STL output");
  options->out.add(command);
  command->callback([options, &action] {
    action = [options] {
      check_not_input(options->output, options->input);
      const FileKind in_kind = file_kind(options->input);
      const FileKind out_kind = file_kind(options->output);
      if (out_kind == FileKind::kUnknown) {
        throw Error(ErrorKind::kInvalidArgument,
                    "unknown output format; tet meshes: " + supported_tet_mesh_extensions() +
                        "; surfaces: " + supported_surface_extensions(),
                    options->output.string());
      }
      if (in_kind == FileKind::kTetMesh) {
        const TetMesh mesh = read_tet_mesh(options->input);
        if (out_kind == FileKind::kTetMesh) {
          write_tet_mesh(options->output, mesh, options->out.write_options());
          fmt::print("wrote {}: {} nodes, {} tets\n", options->output.string(), mesh.num_nodes(), mesh.num_tets());
        } else {
          const TriangleSurface surface = boundary_surface(mesh);
          write_surface(options->output, surface, SurfaceWriteOptions{options->binary});
          fmt::print("wrote {}: boundary surface, {} vertices, {} triangles\n", options->output.string(),
                     surface.num_vertices(), surface.num_triangles());
        }
      } else if (in_kind == FileKind::kSurface) {
        if (out_kind != FileKind::kSurface) {
          throw Error(ErrorKind::kInvalidArgument, "a surface cannot be written as a tet mesh (use 'tetcut embed' when it exists)",
                      options->output.string());
        }
        const TriangleSurface surface = read_surface(options->input);
        write_surface(options->output, surface, SurfaceWriteOptions{options->binary});
        fmt::print("wrote {}: {} vertices, {} triangles\n", options->output.string(), surface.num_vertices(),
                   surface.num_triangles());
      } else {
        throw Error(ErrorKind::kInvalidArgument, "unknown input format", options->input.string());
      }
      return 0;
    };
  });
}

void add_demo_command(CLI::App& app, Action& action) {
  struct Options {
    fs::path directory = "out";
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand("demo", "The default job: build the paper's 320-tet cube and a BCC lattice, "
                                                 "report them and write them out");
  command->add_option("-o,--output-dir", options->directory, "Directory for the outputs (created if missing)");
  command->callback([options, &action] {
    action = [options] {
      fs::create_directories(options->directory);
      using Clock = std::chrono::steady_clock;
      const auto start = Clock::now();
      // The paper's Figure 4 mesh: a 4x4x4 grid of 5-tet cubes, 320 tets.
      const TetMesh cube = make_grid(Box{}, {4, 4, 4}, 5);
      const TetMesh bcc = make_bcc(Box{}, 0.125);
      const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
      print_mesh_summary("cube: 4x4x4 grid of 5-tet cubes (the paper's Figure 4 mesh)", cube, measure_quality(cube));
      print_mesh_summary("bcc: BCC lattice of the unit cube, spacing 1/8", bcc, measure_quality(bcc));
      const fs::path cube_path = options->directory / "cube.vtu";
      const fs::path bcc_path = options->directory / "bcc.vtu";
      const fs::path surface_path = options->directory / "cube_boundary.obj";
      write_tet_mesh(cube_path, cube);
      write_tet_mesh(bcc_path, bcc);
      write_surface(surface_path, boundary_surface(cube));
      fmt::print("generated in {:.3f} s; wrote {}, {}, {}\n", seconds, cube_path.string(), bcc_path.string(),
                 surface_path.string());
      fmt::print("cutting ('tetcut cut') is not implemented yet: see README.md, status\n");
      return 0;
    };
  });
}

}  // namespace tetcut::cli
