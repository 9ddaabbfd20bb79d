// Scene files: every error names the key, and a run writes the frames, the series and a summary
// that agree with the simulation (cuts applied in flight, pieces falling on the ground).

#include <gtest/gtest.h>

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>
#include <tetcut/scene.hpp>
#include <tetcut/session.hpp>

#include <algorithm>
#include <cstdlib>
#include <iterator>
#include <fstream>
#include <sstream>
#include <string>

#include "support/scene_files.hpp"
#include "support/temp_dir.hpp"

namespace tetcut {
namespace {

std::filesystem::path write_scene(const std::filesystem::path& dir, const std::string& text) {
  return testing::write_file(dir, "scene.json", text);
}

using testing::load_error;

constexpr const char* kCube = R"("mesh": {"grid": {"box": [0, 0, 0.05, 1, 1, 1.05], "cells": [2, 2, 2]}})";

// The benchmark scenes (bench/scenes), which no test runs (minutes each), still load as the
// scene format changes: the sliced hand and ball and the two larger stick piles of issue 16.
TEST(Scene, BenchScenesLoad) {
  const std::filesystem::path dir = TETCUT_BENCH_SCENES;
  for (const char* name : {"hand-sliced.json", "ball-sliced.json"}) {
    const Scene sliced = load_scene(dir / name);  // self_collision: the bench sets it
    EXPECT_EQ(sliced.cuts.size(), 1u) << name;
  }
  for (const auto& [name, planes] : {std::pair{"sticks-81.json", 16u}, std::pair{"sticks-144.json", 22u}}) {
    const Scene sticks = load_scene(dir / name);
    EXPECT_TRUE(sticks.self_collision) << name;
    EXPECT_EQ(sticks.cuts.size(), planes) << name;  // 8 or 11 planes each way: 81 or 144 sticks
  }
}

TEST(Scene, ErrorsNameTheKey) {
  const std::string time = R"("time": {"duration": 0.1})";
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "materal": {}})").find("unknown key 'materal'"), std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "}").find("missing key 'time'"), std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + R"(, "time": {"duration": -1}})").find("time.duration: must be positive"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "material": {"youngs_modulus": "soft"}})")
                .find("material.youngs_modulus: must be a number"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time +
                       R"(, "cuts": [{"time": 0, "plane": {"centre": [0,0,0], "normal": [0,0,1], "size": 2}, "helix": {}}]})")
                .find("cuts[0]: give exactly one of"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time +
                       R"(, "cuts": [{"time": 0, "cylinder": {"centre": [0,0,0], "axis": [0,0,0], "radius": 1, "length": 1}}]})")
                .find("cuts[0].cylinder.axis: must not be the zero vector"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "springs": [{"time": 0, "cuts": [0, 0]}]})")
                .find("springs[0].cuts: names a cut that does not exist"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "material": {"model": "jelly"}})")
                .find("'jelly' is not one of stable_neo_hookean, corotated"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "output": {"picture": {"fov": 2}}})")
                .find("output.picture: unknown key 'fov'"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "obstacles": [{"plane": {"point": [0,0,0], "normal": [0,0,1]}, "friction": -1}]})")
                .find("obstacles[0].friction: must not be negative"),
            std::string::npos);
  EXPECT_NE(load_error("{ \"mesh\": ").find("not valid JSON"), std::string::npos);
  EXPECT_NE(load_error(R"({"time": {"duration": 1}})").find("missing key 'mesh'"), std::string::npos);
}

TEST(Scene, ObstacleFrictionIsRead) {
  testing::TempDir dir;
  const Scene scene = load_scene(write_scene(dir.path(), std::string("{") + kCube + R"(, "time": {"duration": 0.1},
    "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}, "friction": 0.6}, {"sphere": {"centre": [0, 0, 0], "radius": 1}}]})"));
  ASSERT_EQ(scene.obstacles.size(), 2u);
  EXPECT_EQ(scene.obstacles[0].friction, 0.6);
  EXPECT_EQ(scene.obstacles[1].friction, 0.0);
}

TEST(Scene, PictureCameraIsRead) {
  testing::TempDir dir;
  const Scene plain = load_scene(write_scene(dir.path(), std::string("{") + kCube + R"(, "time": {"duration": 0.1}})"));
  EXPECT_FALSE(plain.picture_box);
  EXPECT_EQ(plain.picture_azimuth, 35);
  const Scene scene = load_scene(write_scene(
      dir.path(), std::string("{") + kCube +
                      R"(, "time": {"duration": 0.1}, "output": {"picture": {"box": [-1, -2, -3, 1, 2, 3], "elevation": 5}}})"));
  ASSERT_TRUE(scene.picture_box);
  EXPECT_EQ(scene.picture_box->min, Vec3(-1, -2, -3));
  EXPECT_EQ(scene.picture_box->max, Vec3(1, 2, 3));
  EXPECT_EQ(scene.picture_elevation, 5);
  EXPECT_EQ(scene.picture_azimuth, 35);
  EXPECT_EQ(scene.picture_zoom, 1);
  EXPECT_EQ(scene.picture_width, 640);
  const Scene sized = load_scene(write_scene(
      dir.path(), std::string("{") + kCube + R"(, "time": {"duration": 0.1}, "output": {"picture": {"zoom": 1.5, "size": [300, 900]}}})"));
  EXPECT_EQ(sized.picture_zoom, 1.5);
  EXPECT_EQ(sized.picture_width, 300);
  EXPECT_EQ(sized.picture_height, 900);
  EXPECT_NE(load_error(std::string("{") + kCube + R"(, "time": {"duration": 0.1}, "output": {"picture": {"size": [300, 20000]}}})")
                .find("output.picture.size: must be at most 16384"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + R"(, "time": {"duration": 0.1}, "output": {"picture": {"size": [300]}}})")
                .find("output.picture.size: must be [width, height]"),
            std::string::npos);
}

TEST(Scene, CutInFlightThenBothPiecesLandOnTheGround) {
  testing::TempDir dir;
  const std::string text = std::string("{") + kCube + R"(,
    "material": {"youngs_modulus": 1e5, "density": 100, "mass_damping": 1},
    "time": {"dt": 0.01, "duration": 0.6, "output_every": 0.1},
    "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}],
    "cuts": [{"time": 0.05, "space": "world", "plane": {"centre": [0.52, 0.5, 0.5], "normal": [1, 0, 0], "size": 4}}]
  })";
  const Scene scene = load_scene(write_scene(dir.path(), text));
  ASSERT_EQ(scene.cuts.size(), 1u);
  const SceneSummary summary = run_scene(scene, dir.path() / "out");
  EXPECT_EQ(summary.steps, 60);
  EXPECT_EQ(summary.frames, 7);  // t = 0, 0.1, ..., 0.6
  EXPECT_EQ(summary.cuts_applied, 1);
  EXPECT_EQ(summary.pieces, 2);
  // The cube fell straight down before the cut: in the material the plane lies at x = 0.52 still.
  ASSERT_EQ(summary.piece_volumes.size(), 2u);
  EXPECT_NEAR(summary.piece_volumes[0], 0.52, 1e-9);
  EXPECT_NEAR(summary.piece_volumes[1], 0.48, 1e-9);
  EXPECT_EQ(summary.unconverged_steps, 0);
  // The series lists every frame, and the last frame's mesh lies on the ground (penetration at
  // most the penalty's compliance) with the cut's copies.
  std::ifstream pvd(dir.path() / "out" / "mesh.pvd");
  std::stringstream text_pvd;
  text_pvd << pvd.rdbuf();
  EXPECT_NE(text_pvd.str().find("mesh_0006.vtu"), std::string::npos);
  EXPECT_NE(text_pvd.str().find("timestep=\"0.59999999999999998\""), std::string::npos);
  const TetMesh last = read_tet_mesh(dir.path() / "out" / "mesh_0006.vtu");
  EXPECT_EQ(last.num_tets(), summary.tets);
  EXPECT_GT(last.num_tets(), 40);  // 40 tets, some duplicated by the cut
  const double lowest = last.rest().col(2).minCoeff();
  EXPECT_LT(lowest, 0.05);   // it fell
  EXPECT_GT(lowest, -0.02);  // and the ground held it
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "out" / "surface_0006.vtp"));
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "out" / "summary.json"));
}

TEST(Scene, EveryCutterMakesTriangles) {
  testing::TempDir dir;
  const std::string text = std::string("{") + kCube + R"(, "time": {"duration": 0.01}, "cuts": [
    {"time": 0, "plane": {"centre": [0.5, 0.5, 0.5], "normal": [0, 0, 1], "size": 2}},
    {"time": 0, "cylinder": {"centre": [0.5, 0.5, 0.5], "axis": [0, 0, 1], "radius": 0.3, "length": 2, "segments": 16}},
    {"time": 0, "helix": {"centre": [0.5, 0.5, 0], "axis": [0, 0, 1], "inner_radius": 0.1, "outer_radius": 0.4,
                          "pitch": 0.3, "turns": 2, "segments_per_turn": 12}},
    {"time": 0, "cookie_cutter": {"profile": [[0, 0], [0.2, 0], [0.1, 0.2]], "origin": [0.4, 0.4, 1.2],
                                  "u": [1, 0, 0], "v": [0, 1, 0], "depth": -0.5}},
    {"time": 0, "blade": {"poses": [[0, 0.5, 1.2, 0, 0.5, 0.6], [1, 0.5, 1.2, 1, 0.5, 0.6]]}}]})";
  const Scene scene = load_scene(write_scene(dir.path(), text));
  ASSERT_EQ(scene.cuts.size(), 5u);
  const std::vector<Index> expected = {2, 32, 48, 6, 2};
  for (std::size_t i = 0; i < scene.cuts.size(); ++i) EXPECT_EQ(scene.cuts[i].triangles.num_triangles(), expected[i]) << i;
}

TEST(Scene, IncisionPulledOpenThenClosedBySprings) {
  // The lip example, smaller: a slab cut from the top, its ends pulled apart and held, then
  // springs across the cut pull its sides back together.
  testing::TempDir dir;
  const std::string text = R"({
    "mesh": {"grid": {"box": [-1, -0.3, -0.3, 1, 0.3, 0.3], "cells": [10, 3, 3], "tets_per_cube": 5}},
    "material": {"youngs_modulus": 3e4, "poissons_ratio": 0.4, "density": 1000, "mass_damping": 4},
    "gravity": [0, 0, 0],
    "time": {"dt": 0.01, "duration": 1.2, "output_every": 0.1},
    "cuts": [{"time": 0.02, "plane": {"centre": [0.013, 0, 0.45], "normal": [1, 0, 0], "size": 0.7}}],
    "move": [{"box": [-1.1, -1, -1, -0.9, 1, 1], "velocity": [-0.3, 0, -0.3], "from": 0.05, "until": 0.45},
             {"box": [0.9, -1, -1, 1.1, 1, 1], "velocity": [0.3, 0, -0.3], "from": 0.05, "until": 0.45},
             {"box": [-1.1, -1, -1, -0.9, 1, 1], "velocity": [0, 0, 0], "from": 0.45},
             {"box": [0.9, -1, -1, 1.1, 1, 1], "velocity": [0, 0, 0], "from": 0.45}],
    "springs": [{"time": 0.6, "cuts": [0, 0]}]})";
  const SceneSummary s = run_scene(load_scene(write_scene(dir.path(), text)), dir.path() / "out");
  EXPECT_EQ(s.unconverged_steps, 0);
  EXPECT_GT(s.springs, 3);
  EXPECT_GT(s.spring_gap_when_attached, 0.03);
  EXPECT_LT(s.spring_gap_final, 0.05 * s.spring_gap_when_attached) << s.spring_gap_final << " of " << s.spring_gap_when_attached;
}

TEST(Scene, EmbedsASurfaceFromAnArchive) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "meshes");
  // A closed octahedron.
  dir.write("meshes/octa.off",
            "OFF\n6 8 0\n1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n"
            "3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n");
  const std::string pack = "cd '" + dir.path().string() + "' && tar czf shapes.tar.gz meshes/octa.off";
  ASSERT_EQ(std::system(pack.c_str()), 0);
  const std::string time = R"("time": {"duration": 0.1})";
  const Scene scene = load_scene(write_scene(
      dir.path(), R"({"embed": {"archive": "shapes.tar.gz", "surface": "meshes/octa.off", "cells": 4}, )" + time + "}"));
  ASSERT_TRUE(scene.embed_surface.has_value());
  EXPECT_EQ(scene.embed_surface->num_triangles(), 8);
  EXPECT_GT(scene.mesh.tets().size(), 0u);
  EXPECT_NE(load_error(R"({"embed": {"archive": "none.tar.gz", "surface": "a.off"}, )" + time + "}").find("cannot open the archive"),
            std::string::npos);
  // A recording names the archive by its absolute path (the member stays a path inside it), so
  // it replays from another directory.
  Session session(scene);
  session.advance();
  testing::TempDir elsewhere;
  write_recording(elsewhere / "take.json", scene, session);
  const Scene replay = load_scene(elsewhere / "take.json");
  ASSERT_TRUE(replay.embed_surface.has_value());
  EXPECT_EQ(replay.embed_surface->num_triangles(), 8);
  EXPECT_NE(recording_json(scene, session).find(std::filesystem::absolute(dir / "shapes.tar.gz").string()), std::string::npos);
  EXPECT_NE(recording_json(scene, session).find("\"surface\": \"meshes/octa.off\""), std::string::npos);
}

TEST(Scene, SolverModesAndScalpelsAreRead) {
  testing::TempDir dir;
  const std::string time = R"("time": {"dt": 0.01, "duration": 0.1})";
  const Scene converged = load_scene(write_scene(dir.path(), std::string("{") + kCube + "," + time + "}"));
  EXPECT_EQ(converged.step.max_cg_iterations, 0);
  const Scene real_time = load_scene(write_scene(dir.path(), std::string("{") + kCube + "," + time + R"(, "solver": {"mode": "real_time"}})"));
  EXPECT_EQ(real_time.step.max_newton_iterations, 1);
  EXPECT_EQ(real_time.step.max_cg_iterations, 30);
  const Scene budget = load_scene(
      write_scene(dir.path(), std::string("{") + kCube + "," + time + R"(, "solver": {"mode": "real_time", "max_cg_iterations": 5}})"));
  EXPECT_EQ(budget.step.max_cg_iterations, 5);
  EXPECT_EQ(budget.step.reuse_hessian, sim::StepOptions::real_time(0.01).reuse_hessian);
  const Scene fresh = load_scene(
      write_scene(dir.path(), std::string("{") + kCube + "," + time + R"(, "solver": {"mode": "real_time", "reuse_hessian": 1}})"));
  EXPECT_EQ(fresh.step.reuse_hessian, 1);
  // Where Newton starts: the prediction unless the scene says otherwise.
  EXPECT_EQ(converged.step.first_guess, sim::FirstGuess::kPrediction);
  EXPECT_EQ(real_time.step.first_guess, sim::FirstGuess::kPrediction);
  const Scene live = load_scene(
      write_scene(dir.path(), std::string("{") + kCube + "," + time + R"(, "solver": {"mode": "real_time", "first_guess": "start"}})"));
  EXPECT_EQ(live.step.first_guess, sim::FirstGuess::kStart);
  EXPECT_EQ(live.step.max_newton_iterations, 1);
  const Scene started = load_scene(write_scene(dir.path(), std::string("{") + kCube + "," + time + R"(, "solver": {"first_guess": "start"}})"));
  EXPECT_EQ(started.step.first_guess, sim::FirstGuess::kStart);
  EXPECT_EQ(started.step.max_newton_iterations, sim::StepOptions{}.max_newton_iterations);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "solver": {"first_guess": "guess"}})").find("solver.first_guess"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "solver": {"reuse_hessian": 0}})").find("solver.reuse_hessian"),
            std::string::npos);
  const Scene blade = load_scene(write_scene(dir.path(), std::string("{") + kCube + "," + time +
                                                           R"(, "scalpels": [{"from": 0, "until": 1, "poses": [[0,0,0, 0,0,1], [1,0,0, 1,0,1]]}]})"));
  ASSERT_EQ(blade.scalpels.size(), 1u);
  EXPECT_TRUE(blade.scalpels[0].world_space);
  const BladePose half = blade.scalpels[0].at(0.5);
  EXPECT_EQ(half.a, Vec3(0.5, 0, 0));
  EXPECT_EQ(half.b, Vec3(0.5, 0, 1));
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "scalpels": [{"from": 1, "until": 1, "poses": []}]})")
                .find("scalpels[0].until: must come after 'from'"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "scalpels": [{"from": 0, "until": 1, "poses": [[0,0,0,1,1,1]]}]})")
                .find("scalpels[0].poses: needs at least 2 poses"),
            std::string::npos);
  EXPECT_NE(load_error(std::string("{") + kCube + "," + time + R"(, "solver": {"mode": "fast"}})").find("'fast' is not one of converged, real_time"),
            std::string::npos);
}

// A block hanging from its top, cut by a scalpel that crosses its front face at mid-height while
// it swings: `depth` of its thickness, in world or rest space.
std::string scalpel_scene(double depth, const char* space) {
  return std::string(R"({
    "mesh": {"grid": {"box": [0, 0, 0, 1, 1, 1], "cells": [4, 4, 4], "tets_per_cube": 5}},
    "material": {"youngs_modulus": 1e5, "density": 100},
    "time": {"dt": 0.01, "duration": 0.2, "output_every": 0.1},
    "pin": [{"box": [-1, -1, 0.999, 2, 2, 2]}],
    "scalpels": [{"from": 0.02, "until": 0.1, "space": ")") + space + R"(",
                  "poses": [[-0.1, -0.1, 0.53, -0.1, )" + std::to_string(depth) + R"(, 0.53], [1.1, -0.1, 0.53, 1.1, )" +
         std::to_string(depth) + R"(, 0.53]]}]})";
}

TEST(Scene, ScalpelCutsAnIncisionFollowingTheMaterial) {
  testing::TempDir dir;
  // Part way in: one piece, an incision on the surface; a step's strip per step while it moves.
  const SceneSummary partial = run_scene(load_scene(write_scene(dir.path(), scalpel_scene(0.4, "world"))), dir.path() / "partial");
  EXPECT_EQ(partial.cuts_applied, 8);  // steps 2 .. 9 of the blade's 0.08 s
  EXPECT_EQ(partial.pieces, 1);
  EXPECT_EQ(partial.unconverged_steps, 0);
  EXPECT_GT(partial.tets, 320);  // tets the incision crossed got copies
  const TriangleSurface before = read_surface(dir.path() / "partial" / "surface_0000.vtp");
  const TriangleSurface after = read_surface(dir.path() / "partial" / "surface_0002.vtp");
  EXPECT_GT(after.num_triangles(), before.num_triangles() + 100);  // both sides of the incision
  // Right through: the lower half comes off and falls.
  const SceneSummary through = run_scene(load_scene(write_scene(dir.path(), scalpel_scene(1.1, "world"))), dir.path() / "through");
  EXPECT_EQ(through.pieces, 2);
  EXPECT_LT(through.final_box.min[2], -0.05);  // the lower piece fell
  // In rest space the blade ignores the swing: the same pieces.
  const SceneSummary rest = run_scene(load_scene(write_scene(dir.path(), scalpel_scene(1.1, "rest"))), dir.path() / "rest");
  EXPECT_EQ(rest.pieces, 2);
  // The stages were timed: steps, and cuts while the blade moved.
  EXPECT_GT(through.stage_seconds.step, 0);
  EXPECT_GT(through.stage_seconds.cut, 0);
  EXPECT_GT(through.step_ms_max, 0);
  EXPECT_GE(through.step_ms_max, through.step_ms_median);
}

TEST(Scene, FramesLimitStopsEarly) {
  testing::TempDir dir;
  const std::string text = std::string("{") + kCube + R"(, "time": {"dt": 0.01, "duration": 1, "output_every": 0.05}})";
  SceneRunOptions options;
  options.max_frames = 2;
  int calls = 0;
  options.progress = [&](int, int expected) {
    ++calls;
    EXPECT_EQ(expected, 20);
  };
  const SceneSummary summary = run_scene(load_scene(write_scene(dir.path(), text)), dir.path() / "out", options);
  EXPECT_EQ(summary.frames, 3);
  EXPECT_EQ(summary.steps, 10);
  EXPECT_EQ(calls, 3);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "out" / "mesh_0003.vtu"));
}

}  // namespace
}  // namespace tetcut

namespace tetcut {
namespace {

// Two halves of a cut block, the right one driven left through the left one or away from it
// (nothing keeps pieces apart yet): the check sees the crossing, and nothing when they part.
std::string halves_driven(double velocity) {
  return R"({"mesh": {"grid": {"box": [0, 0, 0, 1, 1, 1], "cells": [3, 3, 3]}},
    "material": {"youngs_modulus": 1e5, "density": 100}, "gravity": [0, 0, 0],
    "time": {"dt": 0.02, "duration": 0.3, "output_every": 0.1},
    "cuts": [{"time": 0, "plane": {"centre": [0.5, 0.5, 0.5], "normal": [1, 0, 0], "size": 3}}],
    "move": [{"box": [0.8, -1, -1, 2, 2, 2], "velocity": [)" + std::to_string(velocity) + R"(, 0, 0]}],
    "output": {"mesh": false, "surface": false}})";
}

TEST(Scene, CheckIntersectionsCountsPiecesPassingThroughEachOther) {
  testing::TempDir dir;
  SceneRunOptions check;
  check.check_intersections = true;
  const SceneSummary through = run_scene(load_scene(write_scene(dir.path(), halves_driven(-1))), dir.path() / "through", check);
  EXPECT_EQ(through.pieces, 2);
  ASSERT_EQ(through.intersecting_pairs.size(), 4u);  // frames at 0, 0.1, 0.2, 0.3 s
  EXPECT_EQ(through.intersecting_pairs[0], 0);      // fresh cut: its sides coincide
  EXPECT_GT(through.max_intersecting_pairs, 10);
  EXPECT_EQ(through.max_intersecting_pairs, *std::max_element(through.intersecting_pairs.begin(), through.intersecting_pairs.end()));
  std::ifstream summary(dir.path() / "through" / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"max_intersecting_pairs\": " + std::to_string(through.max_intersecting_pairs)), std::string::npos);

  const SceneSummary apart = run_scene(load_scene(write_scene(dir.path(), halves_driven(1))), dir.path() / "apart", check);
  EXPECT_EQ(apart.max_intersecting_pairs, 0);
  // Not asked: nothing counted, no key.
  const SceneSummary unchecked = run_scene(load_scene(write_scene(dir.path(), halves_driven(-1))), dir.path() / "plain");
  EXPECT_TRUE(unchecked.intersecting_pairs.empty());
  std::ifstream plain(dir.path() / "plain" / "summary.json");
  const std::string plain_text((std::istreambuf_iterator<char>(plain)), std::istreambuf_iterator<char>());
  EXPECT_EQ(plain_text.find("intersecting"), std::string::npos);
}

TEST(Scene, SelfCollisionIsReadAndReported) {
  const std::string base = std::string("{") + kCube + R"(, "time": {"duration": 0.1}, )";
  EXPECT_NE(load_error(base + R"("self_collision": 3})").find("self_collision: must be true or false"), std::string::npos);
  EXPECT_NE(load_error(base + R"("self_collision": {"thickness": -1}})").find("self_collision.thickness: must be positive"), std::string::npos);
  EXPECT_NE(load_error(base + R"("self_collision": {"restitution": 1}})").find("self_collision: unknown key 'restitution'"), std::string::npos);
  EXPECT_NE(load_error(base + R"("self_collision": {"friction": -0.5}})").find("self_collision.friction: must not be negative"), std::string::npos);
  EXPECT_NE(load_error(base + R"("self_collision": {"cushion": -1}})").find("self_collision.cushion: must not be negative"), std::string::npos);
  testing::TempDir dir;
  const Scene plain = load_scene(write_scene(dir.path(), base + R"("self_collision": true})"));
  EXPECT_TRUE(plain.self_collision);
  EXPECT_EQ(plain.self_contact.thickness, 0);  // the simulator's default
  EXPECT_EQ(plain.self_contact.cushion, 0);
  const Scene tuned =
      load_scene(write_scene(dir.path(), base + R"("self_collision": {"thickness": 0.01, "stiffness": 5e3, "friction": 0.4, "cushion": 0.5}})"));
  EXPECT_TRUE(tuned.self_collision);
  EXPECT_EQ(tuned.self_contact.thickness, 0.01);
  EXPECT_EQ(tuned.self_contact.stiffness, 5e3);
  EXPECT_EQ(tuned.self_contact.friction, 0.4);
  EXPECT_EQ(tuned.self_contact.cushion, 0.5);
  EXPECT_FALSE(load_scene(write_scene(dir.path(), base + R"("self_collision": false})")).self_collision);

  // The halves of a fresh cut pulled apart: contact on, nothing crosses, the summary says what
  // contact did.
  std::string apart = halves_driven(1);
  apart.insert(apart.find("\"time\""), R"("self_collision": true, )");
  SceneRunOptions check;
  check.check_intersections = true;
  const SceneSummary summary = run_scene(load_scene(write_scene(dir.path(), apart)), dir.path() / "apart", check);
  EXPECT_EQ(summary.pieces, 2);
  EXPECT_EQ(summary.max_intersecting_pairs, 0);
  EXPECT_EQ(summary.unconverged_steps, 0);
  std::ifstream file(dir.path() / "apart" / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"self_collision\""), std::string::npos);
  EXPECT_NE(text.find("\"max_contact_pairs\""), std::string::npos);

  // Driven straight through the other half the moment it was cut: the fresh cut's guards stop
  // it (without contact: CheckIntersectionsCountsPiecesPassingThroughEachOther).
  std::string through = halves_driven(-1);
  through.insert(through.find("\"time\""), R"("self_collision": true, )");
  const SceneSummary held = run_scene(load_scene(write_scene(dir.path(), through)), dir.path() / "through", check);
  EXPECT_EQ(held.pieces, 2);
  EXPECT_EQ(held.max_intersecting_pairs, 0);
}

// Frame files are named in one place: four digits, and the same as a printf pattern for ffmpeg.
TEST(Scene, FrameFileNames) {
  EXPECT_EQ(frame_file_name("mesh", 7, ".vtu"), "mesh_0007.vtu");
  EXPECT_EQ(frame_file_name("surface", 12345, ".vtp"), "surface_12345.vtp");
  EXPECT_EQ(frame_file_pattern("frame", ".png"), "frame_%04d.png");
}

}  // namespace
}  // namespace tetcut
