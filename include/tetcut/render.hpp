#pragma once
// Pictures of surfaces and meshes, rendered offscreen with OpenGL ES 3 through EGL (Mesa's
// software rasteriser where there is no GPU), written as PNG. A separate library,
// tetcut::render, so that the cutting library itself needs no graphics stack.
//
//   tetcut::render::RenderOptions options;        // 800 x 600, pieces coloured
//   tetcut::render::Image image = tetcut::render::render(surface, options);
//   tetcut::render::write_png("cut.png", image);

#include <tetcut/surface.hpp>
#include <tetcut/tet_mesh.hpp>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace tetcut::render {

struct Camera {
  double azimuth_degrees = 35;    ///< around the vertical (z) axis, from +x towards +y
  double elevation_degrees = 25;  ///< above the horizontal plane
  double zoom = 1;                ///< 1: the whole scene fills the view; 2: twice as close
};

struct RenderOptions {
  int width = 800, height = 600;
  Camera camera;
  /// Colour each piece (connected component of the surface, through shared vertices) in its own
  /// colour; otherwise one colour.
  bool colour_pieces = true;
  /// Line segments drawn over the surface (e.g. the edges of the embedding tets), |E| x 2 rows
  /// of `line_points`.
  Points line_points;
  Edges lines;
  /// The region to frame; empty: the scene's own bounds. Frames of an animation share one so the
  /// camera holds still.
  Eigen::AlignedBox3d frame;
  /// Smoothing of edges by multisampling (samples per pixel; 1 for none).
  int samples = 4;
};

/// RGB, 8 bits per channel, rows from the top.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};

/// The background colour of every render (a light grey).
inline constexpr std::uint8_t kBackground[3] = {242, 242, 242};

/// Renders the surface (lit, both sides) and the lines. Throws Error(kUnsupported) when no
/// OpenGL ES 3 context can be made (no EGL or Mesa), Error(kInvalidArgument) on a bad size.
Image render(const TriangleSurface& surface, const RenderOptions& options = {});

/// Per triangle, its piece: the connected component through shared vertices, numbered by first
/// triangle.
std::vector<Index> surface_pieces(const TriangleSurface& surface);
/// The colour of piece i: well separated hues, the same for a given i in every picture.
std::array<std::uint8_t, 3> piece_colour(Index piece);

/// The edges of a tet mesh, for RenderOptions::lines.
Edges mesh_edges(const TetMesh& mesh);

void write_png(const std::filesystem::path& path, const Image& image);
Image read_png(const std::filesystem::path& path);

/// Assembles numbered PNG frames into an animation with ffmpeg (run as a separate program):
/// `frames` is a printf pattern such as "out/frame_%04d.png", numbered from 0. The output's
/// extension picks the format: .mp4 (H.264, yuv420p, playable in browsers) or .gif (with a
/// palette made from the frames). The file appears only when ffmpeg succeeded. Throws
/// Error(kUnsupported) when ffmpeg is not installed, Error(kInvalidArgument) for another
/// extension or a frame rate outside (0, 240], Error(kIo) with ffmpeg's message when it fails.
void write_animation(const std::filesystem::path& frames, double frames_per_second, const std::filesystem::path& output);

}  // namespace tetcut::render
