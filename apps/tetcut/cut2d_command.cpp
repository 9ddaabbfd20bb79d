// tetcut cut2d: a planar triangle mesh (cloth) cut by polylines (see include/tetcut/planar_cutter.hpp).

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>
#include <tetcut/planar_cutter.hpp>
#include <tetcut/surface.hpp>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"

namespace tetcut::cli {

namespace {
// Errors from the library name no file; this one is where the data came from.
template <typename F>
auto naming(const std::filesystem::path& file, F&& f) {
  try {
    return f();
  } catch (const Error& e) {
    if (!e.file().empty()) throw;
    throw Error(e.kind(), e.message(), file.string());
  }
}
}  // namespace

void add_cut2d_command(CLI::App& app, Action& action) {
  struct Options {
    std::filesystem::path mesh;
    std::vector<std::filesystem::path> cuts;
    std::filesystem::path material, copies, boundary;
    bool json = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "cut2d", "Cut a planar triangle mesh (cloth) by polylines: each material component of a triangle gets its own copy "
               "of it; each polyline file is one batch, cut in order");
  command->add_option("MESH", options->mesh, "Triangle mesh in a coordinate plane (" + supported_surface_extensions() + ")")
      ->required();
  command->add_option("CUTS", options->cuts, "Polyline files (" + supported_polyline_extensions() + ")")->required();
  command->add_option("-o,--output", options->material, "Write the material (its cells as triangles) as a surface");
  command->add_option("--copies", options->copies, "Write the cut mesh (the triangle copies over their nodes) as a surface");
  command->add_option("--boundary", options->boundary, "Write the material's boundary as polylines (.obj or .vtk)");
  command->add_flag("--json", options->json, "Print the result as JSON instead of text");
  command->callback([options, &action] {
    action = [options] {
      std::vector<std::filesystem::path> inputs = options->cuts;
      inputs.push_back(options->mesh);
      for (const auto* output : {&options->material, &options->copies, &options->boundary}) {
        for (const auto& input : inputs) {
          if (!output->empty()) check_not_input(*output, input);
        }
      }
      RestPlane plane;
      const TriangleSurface surface = read_surface(options->mesh);
      PlanarCutter cutter = naming(options->mesh, [&] { return PlanarCutter(planar_mesh(surface, &plane)); });
      // Read every batch before cutting any: a bad file changes nothing and writes nothing.
      std::vector<std::vector<Polyline>> batches;
      for (const auto& file : options->cuts) {
        std::vector<Polyline>& batch = batches.emplace_back();
        for (const Points& line : read_polylines(file)) batch.push_back(Polyline{to_plane(line, plane), false});
      }
      nlohmann::ordered_json report = nlohmann::ordered_json::array();
      Index segments = 0, skipped = 0;
      for (std::size_t b = 0; b < batches.size(); ++b) {
        const PlanarCutReport r = naming(options->cuts[b], [&] { return cutter.cut(batches[b]); });
        segments += r.segments;
        skipped += static_cast<Index>(r.degenerate.size());
        if (!r.degenerate.empty()) {
          fmt::print(stderr, "tetcut: warning: {}: skipped {} zero-length segment(s)\n", options->cuts[b].string(), r.degenerate.size());
        }
        report.push_back({{"file", options->cuts[b].string()},
                          {"segments", r.segments},
                          {"zero_length_segments", r.degenerate.size()},
                          {"triangles_touched", r.touched.size()},
                          {"new_copies", r.new_triangle_source.size()},
                          {"new_nodes", r.new_node_source.size()}});
      }
      const PlanarCutResult result = cutter.result();
      double area = 0;
      for (const double a : result.mesh.piece_areas) area += a;
      if (!options->material.empty()) {
        write_surface(options->material, TriangleSurface{to_space(result.material.rest, plane), result.material.triangles});
      }
      if (!options->copies.empty()) {
        write_surface(options->copies, TriangleSurface{to_space(result.mesh.mesh.rest, plane), result.mesh.mesh.triangles});
      }
      if (!options->boundary.empty()) write_polylines(options->boundary, to_space(result.material.rest, plane), result.material.segments);
      if (options->json) {
        nlohmann::ordered_json out = {{"mesh", options->mesh.string()},
                                      {"triangles_in", surface.num_triangles()},
                                      {"segments", segments},
                                      {"zero_length_segments", skipped},
                                      {"pieces", result.mesh.num_pieces()},
                                      {"piece_areas", result.mesh.piece_areas},
                                      {"area", area},
                                      {"triangle_copies", result.mesh.mesh.num_triangles()},
                                      {"nodes", result.mesh.mesh.num_nodes()},
                                      {"boundary_segments", result.material.num_segments()},
                                      {"batches", report}};
        fmt::print("{}\n", out.dump(2));
      } else {
        fmt::print("cut {} ({} triangles) by {} segments in {} batch(es): {} piece(s), {} triangle copies, {} nodes\n",
                   options->mesh.string(), surface.num_triangles(), segments, batches.size(), result.mesh.num_pieces(),
                   result.mesh.mesh.num_triangles(), result.mesh.mesh.num_nodes());
        for (Index p = 0; p < result.mesh.num_pieces(); ++p) fmt::print("  piece {}: area {:.12g}\n", p, result.mesh.piece_areas[p]);
      }
      return 0;
    };
  });
}

}  // namespace tetcut::cli
