// The renderer on a known scene: the size asked for, a picture that is not blank, the two pieces
// in their own colours, wireframe lines drawn, and PNG files that read back identically.

#include <gtest/gtest.h>

#include <tetcut/error.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/render.hpp>
#include <tetcut/view.hpp>

#include <nlohmann/json.hpp>

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

// The data inside a viewer page.
nlohmann::json page_data(const std::string& html) {
  const std::string open = "<script id=\"tetcut-data\" type=\"application/json\">";
  const std::size_t begin = html.find(open) + open.size();
  return nlohmann::json::parse(html.substr(begin, html.find("</script>", begin) - begin));
}

TEST(ViewPage, SharesUnchangedTopologyAndKeepsTheMarkupIntact) {
  ASSERT_TRUE(view::available());
  view::ViewFrame first;
  first.time = 0;
  first.surface = two_boxes();
  view::ViewFrame moved = first;
  moved.time = 0.5;
  moved.surface.vertices.col(2).array() += 1;
  view::ViewFrame cut = moved;  // a third box appears: new triangles, new pieces
  cut.surface = figures::concatenate(moved.surface, figures::box_surface(Box{Vec3(3, 0, 0), Vec3(4, 1, 1)}));
  // A title that would end the element it sits in, unless escaped.
  const std::string html = view::page("a </script> <b>title</b> & more", {first, moved, cut});
  EXPECT_NE(html.find("<title>a &lt;/script&gt; &lt;b&gt;title&lt;/b&gt; &amp; more - tetcut</title>"), std::string::npos);
  const nlohmann::json data = page_data(html);
  EXPECT_EQ(data["title"], "a </script> <b>title</b> & more");
  const nlohmann::json& frames = data["frames"];
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_TRUE(frames[0]["surface"]["triangles"].is_string());
  EXPECT_TRUE(frames[1]["surface"]["triangles"].is_null());
  EXPECT_TRUE(frames[1]["surface"]["colours"].is_null());
  EXPECT_TRUE(frames[2]["surface"]["triangles"].is_string());
  EXPECT_EQ(frames[0]["surface"]["pieces"], 2);
  EXPECT_EQ(frames[2]["surface"]["pieces"], 3);
  EXPECT_EQ(frames[1]["time"], 0.5);
  EXPECT_TRUE(frames[0]["mesh"].is_null());
  // Positions are 16-bit steps in the frame's box: 16 vertices, 6 bytes each, base64 (4 characters
  // per 3 bytes). The box of the moved boxes: [0, 2.5] x [0, 1] x [1, 2].
  const nlohmann::json& positions = frames[1]["surface"]["positions"];
  EXPECT_EQ(positions["q"].get<std::string>().size(), 16u * 6 / 3 * 4);
  EXPECT_EQ(positions["min"], nlohmann::json({0.0, 0.0, 1.0}));
  EXPECT_DOUBLE_EQ(positions["step"][0].get<double>(), 2.5 / 65535);
  // The script is inline, and the page has exactly its own closing script tags.
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  std::size_t closes = 0;
  for (std::size_t at = html.find("</script>"); at != std::string::npos; at = html.find("</script>", at + 1)) ++closes;
  EXPECT_EQ(closes, 2u);
  EXPECT_THROW(view::page("empty", {}), Error);
}

TEST(ViewPage, MeshFramesCarryTheirEdges) {
  const TetMesh mesh = make_grid(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}, {1, 1, 1}, 6);
  view::ViewFrame frame;
  frame.surface = boundary_surface(mesh);
  frame.mesh_points = mesh.rest();
  frame.mesh_edges = mesh_edges(mesh);
  const nlohmann::json data = page_data(view::page("cube", {frame, frame}));
  // One cube of 6 tets: 12 sides, 6 face diagonals and 1 body diagonal; 2 uint32 each, base64.
  EXPECT_EQ(frame.mesh_edges.rows(), 19);
  EXPECT_EQ(data["frames"][0]["mesh"]["edges"].get<std::string>().size(), (19u * 2 * 4 + 2) / 3 * 4);
  EXPECT_EQ(data["frames"][0]["mesh"]["positions"]["q"].get<std::string>().size(), 8u * 6 / 3 * 4);
  EXPECT_TRUE(data["frames"][1]["mesh"]["edges"].is_null());
}

}  // namespace
}  // namespace tetcut::render
