// Cloth scenes: every error names its key, and runs cut the cloth as the scene says (in rest space,
// at once or progressively, and on the hanging cloth in world space) and write frames and series
// that agree with the summary.

#include <gtest/gtest.h>

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>
#include <tetcut/scene.hpp>
#include <tetcut/session.hpp>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "support/scene_files.hpp"
#include "support/temp_dir.hpp"

namespace tetcut {
namespace {

using testing::write_file;

using testing::load_error;

// A metre square of 4 x 4 cells hanging in the x-z plane from its top edge (z = 1).
constexpr const char* kHanging = R"("cloth": {"mesh": {"grid": {"cells": 4, "size": 1, "plane": "xz"}},
                                              "material": {"stretch_stiffness": 2000, "mass_damping": 1}},
                                    "pin": [{"box": [-1, -1, 0.99, 2, 1, 1.01]}])";

std::string scene(const std::string& rest) { return std::string("{") + kHanging + "," + rest + "}"; }

void expect_error(const std::string& text, const std::string& part) {
  const std::string error = load_error(text);
  EXPECT_NE(error.find(part), std::string::npos) << "expected '" << part << "' in: " << error;
}

TEST(ClothScene, ErrorsNameTheKey) {
  const std::string time = R"("time": {"duration": 0.1})";
  expect_error(scene(time + R"(, "obstacles": [])"), "obstacles: not in a cloth scene");
  expect_error(R"({"cloth": {"mesh": {"grid": {"cells": 2, "size": 1}}, "materal": {}}, "time": {"duration": 1}})",
               "cloth: unknown key 'materal'");
  expect_error(R"({"cloth": {"mesh": {"grid": {"cells": 2, "size": 1, "plane": "xw"}}}, "time": {"duration": 1}})",
               "cloth.mesh.grid.plane: 'xw' is not one of xy, xz, yz");
  expect_error(R"({"cloth": {"mesh": {}}, "time": {"duration": 1}})", "cloth.mesh: give exactly one of 'file' or 'grid'");
  expect_error(R"({"cloth": {"mesh": {"grid": {"cells": 2, "size": 1}}, "material": {"poisson_ratio": 0.7}}, "time": {"duration": 1}})",
               "cloth.material.poisson_ratio: must lie strictly between");
  expect_error(scene(R"("time": {"duration": 1}, "solver": {"linear": "cg"})"), "solver: unknown key 'linear'");
  expect_error(scene(time + R"(, "cuts": [{"time": 0, "polyline": [[0, 0, 0.5], [1, 0, 0.5]]}])"),
               "cuts[0]: a polyline placed in world space needs 'through'");
  expect_error(scene(time + R"(, "cuts": [{"time": 0, "space": "rest", "polyline": [[0, 0, 0.5]]}])"),
               "cuts[0].polyline: needs at least 2 points");
  expect_error(scene(time + R"(, "cuts": [{"time": 0, "until": 1, "blade": {"poses": [[0,0,0, 0,0,1], [1,0,0, 1,0,1]]}}])"),
               "cuts[0].until: a world-space cut is placed at one time");
  expect_error(scene(time + R"(, "cuts": [{"time": 0, "spiral": {"centre": [0.5, 0, 0.5], "outer_radius": 0.4, "spacing": 0.1}}])"),
               "cuts[0].spiral: a spiral is a path in the cloth's rest plane");
  expect_error(scene(time + R"(, "cuts": [{"time": 0, "space": "rest", "spiral": {"centre": [0.5, 0, 0.5], "outer_radius": 0.4, "spacing": 0.1, "pitch": 1}}])"),
               "cuts[0].spiral: unknown key 'pitch'");
  expect_error(scene(time + R"(, "cuts": [{"time": 0, "space": "rest", "blade": {"poses": []}}])"),
               "cuts[0]: a blade or triangles are placed in world space");
  expect_error(scene(time + R"(, "cuts": [{"time": 0.5, "until": 0.5, "space": "rest", "polyline": [[0, 0, 0.5], [1, 0, 0.5]]}])"),
               "cuts[0].until: must come after 'time'");
  expect_error(scene(time + R"(, "cuts": [{"time": 0, "closed": true, "polylines": "x.obj"}])"), "cuts[0].closed: goes with 'polyline'");

  // A mesh file that is not planar, or whose triangles turn both ways, is named with the key.
  testing::TempDir dir;
  write_file(dir.path(), "bent.obj", "v 0 0 0\nv 1 0 0\nv 0 1 1\nf 1 2 3\n");
  try {
    load_scene(write_file(dir.path(), "scene.json", R"({"cloth": {"mesh": {"file": "bent.obj"}}, "time": {"duration": 1}})"));
    FAIL() << "a bent cloth was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cloth.mesh.file:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("coordinate plane"), std::string::npos) << e.what();
  }
  // The live session takes tet meshes only.
  const Scene cloth = load_scene(write_file(dir.path(), "cloth.json", scene(time)));
  EXPECT_THROW(Session{cloth}, Error);
}

nlohmann::json summary_of(const std::filesystem::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in);
}

TEST(ClothScene, ABladeAtTheStartCutsWhereTheRestCutDoes) {
  // Before the first step the cloth is where its rest positions put it, so a horizontal blade
  // through z = 7/16 in world space cuts exactly what a rest-space polyline there cuts.
  testing::TempDir dir;
  const std::string time = R"("time": {"dt": 0.01, "duration": 0.02}, "output": {"mesh": false, "surface": false})";
  const SceneSummary world = run_scene(
      load_scene(write_file(dir.path(), "world.json",
                            scene(time + R"(, "cuts": [{"time": 0, "blade": {"poses": [[-1, -1, 0.4375, -1, 1, 0.4375], [2, -1, 0.4375, 2, 1, 0.4375]]}}])"))),
      dir.path() / "world");
  const SceneSummary rest = run_scene(
      load_scene(write_file(dir.path(), "rest.json",
                            scene(time + R"(, "cuts": [{"time": 0, "space": "rest", "polyline": [[-1, 0, 0.4375], [2, 0, 0.4375]]}])"))),
      dir.path() / "rest");
  ASSERT_TRUE(world.cloth);
  EXPECT_EQ(world.cuts_applied, 1);
  ASSERT_EQ(world.pieces, 2);
  EXPECT_NEAR(world.piece_areas[0], 0.5625, 1e-12);
  EXPECT_NEAR(world.piece_areas[1], 0.4375, 1e-12);
  EXPECT_EQ(world.triangle_copies, rest.triangle_copies);
  EXPECT_EQ(world.nodes, rest.nodes);
  EXPECT_EQ(world.triangles_in, 32);
  EXPECT_EQ(world.triangle_copies, 32 + 8);  // the row of eight triangles the blade crosses
}

TEST(ClothScene, AProgressiveCutSeparatesOnlyWhenItHasGoneAcross) {
  // The same cut drawn from left to right over 0.2 s: halfway it has separated nothing; at the end
  // the bottom falls away, and the frames, the series and the summary agree.
  testing::TempDir dir;
  const std::string cut = R"("cuts": [{"time": 0, "until": 0.2, "space": "rest", "polyline": [[-0.5, 0, 0.4375], [1.5, 0, 0.4375]]}])";
  const SceneSummary half = run_scene(
      load_scene(write_file(dir.path(), "half.json", scene(R"("time": {"dt": 0.01, "duration": 0.1}, "output": {"mesh": false, "surface": false},)" + cut))),
      dir.path() / "half");
  EXPECT_EQ(half.pieces, 1);
  EXPECT_GT(half.triangle_copies, 32);
  const SceneSummary whole = run_scene(
      load_scene(write_file(dir.path(), "whole.json", scene(R"("time": {"dt": 0.01, "duration": 0.4, "output_every": 0.1},)" + cut))),
      dir.path() / "whole");
  EXPECT_EQ(whole.pieces, 2);
  EXPECT_EQ(whole.triangle_copies, 40);
  EXPECT_EQ(whole.frames, 5);
  EXPECT_EQ(whole.steps, 40);
  EXPECT_EQ(whole.unconverged_steps, 0);
  // The lower piece falls: cut free at 0.2 s, its bottom edge (z = 0) is some 0.2 m lower 0.2 s later.
  EXPECT_LT(whole.final_box.min[2], -0.1);
  const nlohmann::json s = summary_of(dir.path() / "whole");
  EXPECT_EQ(s["cloth"], true);
  EXPECT_EQ(s["triangle_copies"], 40);
  EXPECT_EQ(s["pieces"], 2);
  EXPECT_GT(s["ms_per_step"]["step"].get<double>(), 0);
  const std::vector<SeriesEntry> surfaces = read_series(dir.path() / "whole" / "surface.pvd");
  const std::vector<SeriesEntry> meshes = read_series(dir.path() / "whole" / "mesh.pvd");
  ASSERT_EQ(surfaces.size(), 5u);
  ASSERT_EQ(meshes.size(), 5u);
  EXPECT_DOUBLE_EQ(surfaces.back().time, 0.4);
  const TriangleSurface copies = read_surface(meshes.back().file);
  EXPECT_EQ(copies.num_triangles(), 40);
  // The material is the cut cloth: its area is the square's, wherever the frame has moved it to.
  const TriangleSurface first = read_surface(surfaces.front().file);
  double area = 0;
  for (Index t = 0; t < first.num_triangles(); ++t) {
    const Vec3 a = first.vertices.row(first.triangles(t, 0)), b = first.vertices.row(first.triangles(t, 1)),
               c = first.vertices.row(first.triangles(t, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  EXPECT_NEAR(area, 1.0, 1e-12);
}

TEST(ClothScene, FilesSpiralsAndPolylinesPushedThroughTheHangingCloth) {
  // A cloth read from a file (in the y-z plane), a rest-space spiral led in from outside and a
  // polyline file, then a world-space polyline pushed through the cloth as it hangs.
  testing::TempDir dir;
  write_file(dir.path(), "square.obj", "v 0 0 0\nv 0 1 0\nv 0 1 1\nv 0 0 1\nf 1 2 3\nf 1 3 4\n");
  write_file(dir.path(), "slit.xyz", "0 0.2 0.9\n0 0.4 0.9\n");
  const std::string text = R"({"cloth": {"mesh": {"file": "square.obj"}},
      "pin": [{"box": [-1, -1, 0.99, 1, 2, 1.01]}],
      "time": {"dt": 0.01, "duration": 0.1},
      "cuts": [{"time": 0, "space": "rest", "spiral": {"centre": [0, 0.5, 0.5], "outer_radius": 0.3, "spacing": 0.1, "from": [0, 0.5, -0.1]}},
               {"time": 0, "space": "rest", "polylines": "slit.xyz"},
               {"time": 0.05, "polyline": [[0, 0.6, -1], [0, 0.6, 2]], "through": [0.5, 0, 0]}]})";
  const Scene loaded = load_scene(write_file(dir.path(), "scene.json", text));
  ASSERT_TRUE(loaded.cloth);
  EXPECT_EQ(loaded.cloth->plane.normal, 0);
  ASSERT_EQ(loaded.cloth->cuts.size(), 3u);
  EXPECT_GT(loaded.cloth->cuts[0].polylines[0].points.rows(), 20);
  EXPECT_EQ(loaded.cloth->cuts[2].triangles.num_triangles(), 2);
  const SceneSummary s = run_scene(loaded, dir.path() / "out");
  EXPECT_EQ(s.cuts_applied, 3);
  EXPECT_GE(s.pieces, 2);  // the world-space cut, along the whole height, takes a strip off
  double area = 0;
  for (const double a : s.piece_areas) area += a;
  EXPECT_NEAR(area, 1.0, 1e-12);
  EXPECT_EQ(s.skipped_coplanar, 0);
  // --check-intersections is for tet scenes.
  SceneRunOptions check;
  check.check_intersections = true;
  EXPECT_THROW(run_scene(loaded, dir.path() / "checked", check), Error);
}

}  // namespace
}  // namespace tetcut
