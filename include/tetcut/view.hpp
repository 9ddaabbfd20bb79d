#pragma once
// The web viewer: one self-contained HTML page (three.js bundled in, the data inlined) that
// shows a material surface, or the frames of a simulation, in any browser, offline. Orbit, colour
// by piece, toggle the embedding tets' edges, step or play the frames. Part of tetcut::render.
//
//   std::vector<tetcut::view::ViewFrame> frames = tetcut::view::load_frames("out/slinky");
//   tetcut::view::write_page("out/slinky/view.html", "slinky", frames);

#include <tetcut/surface.hpp>
#include <tetcut/types.hpp>

#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace tetcut::view {

struct ViewFrame {
  /// Simulated time, shown with the frame number; NaN for none.
  double time = std::numeric_limits<double>::quiet_NaN();
  TriangleSurface surface;
  /// The embedding mesh's edges (rows of `mesh_points`); none when empty.
  Points mesh_points;
  Edges mesh_edges;
  /// Whether those are a triangle mesh's (a cloth's triangle copies) rather than tets'.
  bool mesh_triangles = false;
};

/// The page's HTML. Frames whose triangles, pieces or edges equal the frame before them share
/// that frame's arrays, so a simulation without cuts stores its connectivity once. Positions are
/// quantised to 16 bits per coordinate within each frame's bounds (1/65535 of the box, below a
/// pixel): the page holds about 6 bytes per surface vertex (and per tet node, with edges) per
/// frame, plus the connectivity, base64-encoded. Throws Error(kUnsupported) when this build of tetcut
/// has no viewer script (built without Node.js), Error(kInvalidArgument) when there are no frames.
std::string page(const std::string& title, const std::vector<ViewFrame>& frames);
/// Writes page() to `path` atomically.
void write_page(const std::filesystem::path& path, const std::string& title, const std::vector<ViewFrame>& frames);

/// What `tetcut view` shows:
/// - a directory that `tetcut sim` wrote: its surface.pvd series, with the edges of the matching
///   mesh.pvd frames when that series exists (tets, or a cloth scene's triangle copies);
/// - a surface file: one frame;
/// - a tet mesh file: its boundary, with its edges.
/// `mesh` (optional) adds the edges of that mesh to every frame of a surface file: a tet mesh, or
/// a triangle surface (e.g. the triangle copies `tetcut cut2d --copies` writes).
/// Errors name the file: Error(kInvalidInput) for a directory without surface.pvd, or series of
/// different lengths.
std::vector<ViewFrame> load_frames(const std::filesystem::path& input, const std::filesystem::path& mesh = {});

/// Whether this build carries the viewer's script (it needs Node.js and npm at build time).
bool available();

}  // namespace tetcut::view
