// The renderer on a known scene: the size asked for, a picture that is not blank, the two pieces
// in their own colours, wireframe lines drawn, and PNG files that read back identically.

#include <gtest/gtest.h>

#include <tetcut/error.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/render.hpp>

#include "support/temp_dir.hpp"

namespace tetcut::render {
namespace {

TriangleSurface two_boxes() {
  return figures::concatenate(figures::box_surface(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}),
                              figures::box_surface(Box{Vec3(1.5, 0, 0), Vec3(2.5, 1, 1)}));
}

bool background(const Image& image, std::size_t pixel) {
  for (int k = 0; k < 3; ++k) {
    if (image.rgb[3 * pixel + k] != kBackground[k]) return false;
  }
  return true;
}

// The colour's direction (r, g, b) / |(r, g, b)|: lighting scales it, so it names the base colour.
Eigen::Vector3d chroma(const std::uint8_t* rgb) {
  const Eigen::Vector3d c(rgb[0], rgb[1], rgb[2]);
  return c / std::max(c.norm(), 1.0);
}

TEST(Render, KnownSceneHasItsSizeAndBothPiecesInTheirColours) {
  RenderOptions options;
  options.width = 240;
  options.height = 160;
  options.colour_pieces = true;
  const Image image = render(two_boxes(), options);
  ASSERT_EQ(image.width, 240);
  ASSERT_EQ(image.height, 160);
  ASSERT_EQ(image.rgb.size(), 3u * 240 * 160);
  const std::vector<Index> pieces = surface_pieces(two_boxes());
  EXPECT_EQ(pieces.front(), 0);
  EXPECT_EQ(pieces.back(), 1);
  const Eigen::Vector3d first = chroma(piece_colour(0).data()), second = chroma(piece_colour(1).data());
  ASSERT_GT((first - second).norm(), 0.1) << "the palette's first two colours are too close to tell apart";
  std::size_t covered = 0, near_first = 0, near_second = 0;
  for (std::size_t p = 0; p < image.rgb.size() / 3; ++p) {
    if (background(image, p)) continue;
    ++covered;
    const Eigen::Vector3d c = chroma(&image.rgb[3 * p]);
    ((c - first).norm() < (c - second).norm() ? near_first : near_second) += 1;
  }
  EXPECT_GT(covered, image.rgb.size() / 3 / 10) << "the picture is nearly blank";
  EXPECT_GT(near_first, covered / 5);
  EXPECT_GT(near_second, covered / 5);
}

TEST(Render, OneColourWithoutPiecesAndLinesOnTop) {
  RenderOptions options;
  options.width = 200;
  options.height = 200;
  options.colour_pieces = false;
  const Image plain = render(two_boxes(), options);
  // Grey: every covered pixel's channels nearly equal.
  for (std::size_t p = 0; p < plain.rgb.size() / 3; ++p) {
    if (background(plain, p)) continue;
    const auto* c = &plain.rgb[3 * p];
    EXPECT_LE(std::max({c[0], c[1], c[2]}) - std::min({c[0], c[1], c[2]}), 12) << "pixel " << p;
  }
  // Lines of a tet mesh over the same view darken some pixels.
  const TetMesh grid = make_grid(Box{Vec3(0, 0, 0), Vec3(2.5, 1, 1)}, {5, 2, 2}, 5);
  options.line_points = grid.rest();
  options.lines = mesh_edges(grid);
  EXPECT_EQ(options.lines.rows(), grid.adjacency().num_edges());
  const Image with_lines = render(two_boxes(), options);
  std::size_t dark_before = 0, dark_after = 0;
  for (std::size_t p = 0; p < plain.rgb.size() / 3; ++p) {
    dark_before += plain.rgb[3 * p] < 90;
    dark_after += with_lines.rgb[3 * p] < 90;
  }
  EXPECT_GT(dark_after, dark_before + 500);
}

TEST(Render, PngRoundTripAndBadSizes) {
  testing::TempDir dir;
  RenderOptions options;
  options.width = 64;
  options.height = 48;
  const Image image = render(two_boxes(), options);
  write_png(dir.path() / "a.png", image);
  const Image back = read_png(dir.path() / "a.png");
  EXPECT_EQ(back.width, 64);
  EXPECT_EQ(back.height, 48);
  EXPECT_EQ(back.rgb, image.rgb);
  options.width = 0;
  EXPECT_THROW(render(two_boxes(), options), Error);
  EXPECT_THROW(read_png(dir.path() / "missing.png"), Error);
}

}  // namespace
}  // namespace tetcut::render
