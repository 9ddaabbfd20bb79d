// The live session: a blade's strokes cut where it goes in the material, a hook pulls the surface
// and lets go, pins hold; bad events change nothing; and a recording replays to the same pieces
// and the same positions, bit for bit, through a session and through tetcut sim's runner.

#include <gtest/gtest.h>

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>
#include <tetcut/session.hpp>

#include <cmath>
#include <fstream>

#include "support/temp_dir.hpp"

namespace tetcut {
namespace {

// A block 1 x 1 x 1 hanging from its top, 4 x 4 x 4 cubes of 5 tets.
Scene hanging_block(const std::filesystem::path& dir) {
  const std::filesystem::path path = dir / "block.json";
  std::ofstream(path) << R"({
    "mesh": {"grid": {"box": [0, 0, 0, 1, 1, 1], "cells": [4, 4, 4], "tets_per_cube": 5}},
    "material": {"youngs_modulus": 1e5, "density": 100},
    "time": {"dt": 0.01, "duration": 1},
    "pin": [{"box": [-1, -1, 0.999, 2, 2, 2]}]
  })";
  return load_scene(path);
}

// A blade across the block at height z, along y from -0.1 to `depth`, at x.
BladePose blade_at(double x, double depth, double z = 0.53) { return {Vec3(x, -0.1, z), Vec3(x, depth, z)}; }

TEST(Session, AStrokeBesideTheObjectChangesNothing) {
  testing::TempDir dir;
  const Scene scene = hanging_block(dir.path());  // outlives the session, which reads it
  Session session(scene);
  session.advance();
  const Index tets = session.simulator().num_tets();
  session.blade(blade_at(-0.6, 1.1));
  session.blade(blade_at(-0.3, 1.1));  // a strip cut, wholly outside the block
  EXPECT_EQ(session.cuts_applied(), 1);
  EXPECT_EQ(session.topology_changes(), 0);
  EXPECT_FALSE(session.advance().topology_changed);
  EXPECT_EQ(session.simulator().num_tets(), tets);
  // Into the block: the mesh changes.
  session.blade(blade_at(0.3, 1.1));
  EXPECT_EQ(session.cuts_applied(), 2);
  EXPECT_EQ(session.topology_changes(), 1);
  EXPECT_TRUE(session.advance().topology_changed);
}

TEST(Session, StrokesCutWhereTheBladeGoesInTheMaterial) {
  testing::TempDir dir;
  const Scene scene = hanging_block(dir.path());
  Session session(scene);
  for (int s = 0; s < 5; ++s) session.advance();
  // The first pose of a stroke cuts nothing; then each pose cuts the strip since the last.
  session.blade(blade_at(-0.2, 1.1));
  EXPECT_EQ(session.cuts_applied(), 0);
  for (int k = 1; k <= 7; ++k) {
    session.blade(blade_at(-0.2 + 0.2 * k, 1.1));
    session.advance();
  }
  EXPECT_EQ(session.cuts_applied(), 7);
  // Right through at mid-height: the lower half comes off.
  EXPECT_EQ(session.result().mesh.num_pieces(), 2);
  // A new stroke starts where the blade comes back; lifting it in between cuts nothing.
  session.lift_blade();
  session.blade(blade_at(0.5, 0.3, 0.8));
  EXPECT_EQ(session.cuts_applied(), 7);
  const auto pieces_before = session.result().mesh.num_pieces();
  for (int s = 0; s < 20; ++s) session.advance();
  EXPECT_EQ(session.result().mesh.num_pieces(), pieces_before);
  // The lower piece fell.
  EXPECT_LT(session.simulator().positions().col(2).minCoeff(), -0.05);
  EXPECT_EQ(session.recording().size(), 10u);  // 8 poses, a lift, a pose
}

TEST(Session, AHookPullsTheSurfaceAndLetsGo) {
  testing::TempDir dir;
  const Scene scene = hanging_block(dir.path());
  Session session(scene);
  // Hook the middle of the front face and pull it out of the block.
  const int hook = session.grab(Vec3(0.5, -0.05, 0.5));
  EXPECT_EQ(hook, 0);
  EXPECT_EQ(session.num_hooks(), 1);
  const auto front = [&] { return session.surface_positions().col(1).minCoeff(); };
  const double before = front();
  session.move_hook(hook, Vec3(0.5, -0.4, 0.5));
  for (int s = 0; s < 30; ++s) session.advance();
  const double pulled = front();
  EXPECT_LT(pulled, before - 0.05);  // the surface came forward
  session.release(hook);
  EXPECT_EQ(session.num_hooks(), 0);
  EXPECT_TRUE(session.simulator().anchors().empty());
  // A second hook gets the next number.
  EXPECT_EQ(session.grab(Vec3(0.5, 1.05, 0.5), 1e4), 1);
}

TEST(Session, PinsHoldNodesWhereTheyAre) {
  testing::TempDir dir;
  Scene scene = hanging_block(dir.path());
  scene.pins.clear();  // nothing holds it: it falls
  Session session(scene);
  session.pin(Vec3(0, 0, 1), 0.3);  // a corner's nodes
  for (int s = 0; s < 20; ++s) session.advance();
  const Points held = session.simulator().positions();
  bool some_held = false;
  for (Index n = 0; n < held.rows(); ++n) {
    if ((scene.mesh.rest().row(n) - Vec3(0, 0, 1).transpose()).norm() <= 0.3) {
      EXPECT_EQ(held.row(n), scene.mesh.rest().row(n)) << "node " << n;
      some_held = true;
    }
  }
  EXPECT_TRUE(some_held);
  session.unpin(Vec3(0, 0, 1), 0.3);
  for (int s = 0; s < 20; ++s) session.advance();
  EXPECT_LT(session.simulator().positions().col(2).maxCoeff(), 1.0);  // all of it falls now
}

TEST(Session, BadEventsAreRefusedAndChangeNothing) {
  testing::TempDir dir;
  const Scene scene = hanging_block(dir.path());
  Session session(scene);
  session.advance();
  const Points x = session.simulator().positions();
  const std::size_t recorded = session.recording().size();
  const double nan = std::nan("");
  EXPECT_THROW(session.blade({Vec3(nan, 0, 0), Vec3(0, 0, 1)}), Error);
  EXPECT_THROW(session.blade({Vec3(0, 0, 0), Vec3(0, 0, 0)}), Error);
  EXPECT_THROW(session.grab(Vec3(0, nan, 0)), Error);
  EXPECT_THROW(session.grab(Vec3(0.5, 0.5, 0.5), -1), Error);
  EXPECT_THROW(session.move_hook(0, Vec3(0, 0, 0)), Error);  // no hook yet
  EXPECT_THROW(session.release(3), Error);
  EXPECT_THROW(session.pin(Vec3(0, 0, 0), 0), Error);
  EXPECT_THROW(session.unpin(Vec3(0, 0, nan), 1), Error);
  const int hook = session.grab(Vec3(0.5, -0.1, 0.5));
  session.release(hook);
  EXPECT_THROW(session.release(hook), Error);  // released already
  EXPECT_THROW(session.move_hook(hook, Vec3(0, 0, 0)), Error);
  EXPECT_EQ(session.recording().size(), recorded + 2);  // the grab and the release only
  EXPECT_EQ(session.simulator().positions(), x);
  EXPECT_EQ(session.cuts_applied(), 0);
}

TEST(Session, ARecordingReplaysBitForBit) {
  testing::TempDir dir;
  const Scene scene = hanging_block(dir.path());
  Session live(scene);
  // A user's minute: swing, a stroke half through, a hook pulling a flap, a pin, another stroke.
  for (int s = 0; s < 5; ++s) live.advance();
  for (int k = 0; k <= 6; ++k) {
    live.blade(blade_at(-0.2 + 0.25 * k, 0.6));
    live.advance();
  }
  live.lift_blade();
  const int hook = live.grab(Vec3(0.5, -0.05, 0.45));
  for (int s = 0; s < 10; ++s) {
    live.move_hook(hook, Vec3(0.5, -0.05 - 0.03 * s, 0.45));
    live.advance();
  }
  live.pin(Vec3(1, 1, 0), 0.2);
  live.release(hook);
  // Right through below the flap, the blade reaching past the pulled-out front.
  for (int k = 0; k <= 6; ++k) {
    const double x = -0.2 + 0.25 * k;
    live.blade({Vec3(x, -0.8, 0.3), Vec3(x, 1.3, 0.3)});
    live.advance();
  }
  for (int s = 0; s < 5; ++s) live.advance();
  const std::filesystem::path take = dir.path() / "take.json";
  write_recording(take, scene, live);

  // Through a session: the same events at the same steps.
  const Scene recorded = load_scene(take);
  EXPECT_EQ(recorded.events.size(), live.recording().size());
  Session replay(recorded);
  while (replay.steps() < live.steps()) replay.advance();
  EXPECT_EQ(replay.result().mesh.num_pieces(), live.result().mesh.num_pieces());
  EXPECT_TRUE(replay.simulator().positions() == live.simulator().positions())
      << "largest difference " << (replay.simulator().positions() - live.simulator().positions()).cwiseAbs().maxCoeff();
  // Through tetcut sim's runner: the same pieces and the same final box.
  const SceneSummary summary = run_scene(recorded, dir.path() / "replay");
  EXPECT_EQ(summary.steps, live.steps());
  EXPECT_EQ(summary.pieces, live.result().mesh.num_pieces());
  EXPECT_EQ(summary.final_box.min, Vec3(live.simulator().positions().colwise().minCoeff().transpose()));
  EXPECT_EQ(summary.final_box.max, Vec3(live.simulator().positions().colwise().maxCoeff().transpose()));
  EXPECT_GE(live.result().mesh.num_pieces(), 2);
}

}  // namespace
}  // namespace tetcut
