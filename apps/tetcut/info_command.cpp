// tetcut info: counts, bounding box, volume and element quality of a tet mesh or a surface, as
// text or as one JSON object.

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>
#include <tetcut/quality.hpp>

#include <fmt/core.h>

#include <memory>
#include <string>

#include "commands.hpp"
#include "common.hpp"

namespace tetcut::cli {

namespace {

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
      {"balanced", s.balanced},
      {"two_manifold", s.two_manifold},
      {"unbalanced_edges", s.num_unbalanced_edges},
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
  fmt::print("  balanced         {}", s.balanced ? "yes" : "no");
  if (!s.balanced) fmt::print(" ({} edges used more often in one direction than the other)", s.num_unbalanced_edges);
  fmt::print("\n");
  fmt::print("  two-manifold     {}", s.two_manifold ? "yes" : "no");
  if (!s.two_manifold) fmt::print(" ({} boundary edges, {} non-manifold edges)", s.num_boundary_edges, s.num_nonmanifold_edges);
  fmt::print("\n");
  if (s.balanced) fmt::print("  enclosed volume  {:.17g}\n", s.enclosed_volume);
  if (s.num_degenerate_triangles > 0) fmt::print("  degenerate       {} triangles\n", s.num_degenerate_triangles);
}

struct InfoOptions {
  fs::path input;
  bool json = false;
};

int run_info(const InfoOptions& options) {
  const fs::path& path = options.input;
  const FileKind kind = file_kind(path);
  if (kind == FileKind::kTetMesh) {
    const TetMesh mesh = read_tet_mesh(path);
    const MeshQuality q = measure_quality(mesh);
    if (options.json) {
      Json j = mesh_json(mesh, q);
      j["file"] = path.string();
      fmt::print("{}\n", j.dump(2));
    } else {
      print_mesh_summary(path.string(), mesh, q);
    }
  } else if (kind == FileKind::kSurface) {
    const TriangleSurface surface = read_surface(path);
    const SurfaceStats s = measure_surface(surface);
    if (options.json) {
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
}

}  // namespace

void add_info_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* command = app.add_subcommand("info", "Print counts, bounding box, volume and element quality of a file");
  command->add_option("FILE", options->input, "Tet mesh or surface file")->required();
  command->add_flag("--json", options->json, "Print one JSON object instead of text");
  command->callback([options, &action] { action = [options] { return run_info(*options); }; });
}

}  // namespace tetcut::cli
