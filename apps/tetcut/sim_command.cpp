// tetcut sim: a scene simulated and written frame by frame (see include/tetcut/scene.hpp), with
// pictures and an animation on request.

#include <tetcut/error.hpp>
#include <tetcut/render.hpp>
#include <tetcut/scene.hpp>

#include <fmt/core.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "common.hpp"

namespace tetcut::cli {

namespace {

// Without a camera box in the scene, pictures frame the first frame's surface grown by a quarter
// of its size on every side (by half in all): room for the pieces to move without the camera
// moving with them.
constexpr double kFrameMargin = 0.25;
// An animation's default rate is real time (1 / output_every), within what players show smoothly
// and files stay small at.
constexpr double kMinFps = 1, kMaxFps = 60;

struct SimOptions {
  fs::path scene;
  fs::path out;
  int frames = -1;
  bool png = false;
  fs::path animation;
  double fps = 0;
  bool check_intersections = false;
};

// A progress bar on a terminal: frames done, time so far and time left at the pace so far.
void print_progress(int frame, int total, Clock::time_point start) {
  const int width = 30, filled = total > 0 ? std::min(width, width * frame / total) : width;
  const double elapsed = seconds_since(start);
  // Time left at the pace so far (frames take about equally long).
  const std::string left = frame > 0 && frame < total ? fmt::format(", about {:.0f} s left", elapsed * (total - frame) / frame) : "";
  fmt::print(stderr, "\r[{}{}] frame {}/{}  {:.1f} s{}    ", std::string(static_cast<std::size_t>(filled), '#'),
             std::string(static_cast<std::size_t>(width - filled), ' '), frame, total, elapsed, left);
}

void print_summary(const SimOptions& options, const SceneSummary& summary) {
  fmt::print("simulated {} ({} s in {} steps)\n", options.scene.string(), summary.simulated_seconds, summary.steps);
  fmt::print("  frames           {} in {}\n", summary.frames, options.out.string());
  fmt::print("  cuts             {}\n", summary.cuts_applied);
  if (summary.cloth) {
    fmt::print("  cloth            {} triangle copies of {} triangles, {} nodes, {} pieces\n", summary.triangle_copies,
               summary.triangles_in, summary.nodes, summary.pieces);
  } else {
    fmt::print("  mesh             {} tets, {} nodes, {} pieces\n", summary.tets, summary.nodes, summary.pieces);
  }
  fmt::print("  time             {:.2f} s, {:.3f} s per frame, {:.2f} Newton iterations per step\n", summary.wall_seconds,
             summary.seconds_per_frame, summary.mean_newton_iterations);
  const SceneStageSeconds& t = summary.stage_seconds;
  const double per_step = summary.steps > 0 ? 1e3 / summary.steps : 0;
  fmt::print("  ms per step      {:.2f} (cut {:.2f}, surface {:.2f}, remesh {:.2f}, step {:.2f}); median {:.2f}, max {:.2f}\n",
             (t.cut + t.surface + t.remesh + t.step) * per_step, t.cut * per_step, t.surface * per_step, t.remesh * per_step,
             t.step * per_step, summary.step_ms_median, summary.step_ms_max);
  if (options.check_intersections) {
    fmt::print("  intersections    at most {} pair(s) of surface triangles of different copies, over {} frames\n",
               summary.max_intersecting_pairs, summary.intersecting_pairs.size());
  }
  if (summary.unconverged_steps > 0) {
    fmt::print(stderr, "tetcut: warning: {} step(s) stopped before Newton converged\n", summary.unconverged_steps);
  }
}

int run_sim(SimOptions& options) {
  if (!options.animation.empty()) {
    const std::string ext = options.animation.extension().string();
    if (ext != ".mp4" && ext != ".gif") {
      throw Error(ErrorKind::kInvalidArgument, "an animation must be .mp4 or .gif", options.animation.string());
    }
    options.png = true;
  }
  const Scene scene = load_scene(options.scene);
  SceneRunOptions run;
  run.max_frames = options.frames;
  run.check_intersections = options.check_intersections;
  const bool terminal = isatty(fileno(stderr)) != 0;
  const auto start = Clock::now();
  run.progress = [&](int frame, int expected) {
    if (terminal) print_progress(frame, options.frames >= 0 ? std::min(expected, options.frames) : expected, start);
  };
  Eigen::AlignedBox3d frame_box;
  if (scene.picture_box) frame_box = Eigen::AlignedBox3d(scene.picture_box->min, scene.picture_box->max);
  if (options.png) {
    run.frame_surface = [&](int frame, const SceneFrame& shown) {
      const TriangleSurface& surface = shown.surface;
      if (frame_box.isEmpty()) {
        for (Index v = 0; v < surface.num_vertices(); ++v) frame_box.extend(surface.vertices.row(v).transpose());
        const Vec3 grow = kFrameMargin * frame_box.sizes();
        frame_box = Eigen::AlignedBox3d(frame_box.min() - grow, frame_box.max() + grow);
      }
      render::RenderOptions render_options;
      render_options.width = scene.picture_width;
      render_options.height = scene.picture_height;
      render_options.frame = frame_box;
      render_options.camera.azimuth_degrees = scene.picture_azimuth;
      render_options.camera.elevation_degrees = scene.picture_elevation;
      render_options.camera.zoom = scene.picture_zoom;
      render_options.line_points = shown.line_points;  // a cloth's triangle copies
      render_options.lines = shown.lines;
      render::write_png(options.out / frame_file_name("frame", frame, ".png"), render::render(surface, render_options));
    };
  }
  const SceneSummary summary = run_scene(scene, options.out, run);
  if (terminal) fmt::print(stderr, "\n");
  if (!options.animation.empty()) {
    const double every = scene.output_every > 0 ? scene.output_every : scene.step.dt;
    const double fps = options.fps > 0 ? options.fps : std::clamp(1 / every, kMinFps, kMaxFps);
    render::write_animation(options.out / frame_file_pattern("frame", ".png"), fps, options.animation);
    fmt::print("  animation        {} ({} frames at {:g} per second)\n", options.animation.string(), summary.frames, fps);
  }
  print_summary(options, summary);
  return 0;
}

}  // namespace

void add_sim_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<SimOptions>();
  CLI::App* command = app.add_subcommand(
      "sim", "Simulate a scene (JSON): FEM on the mesh, timed cuts, obstacles, springs, or a cloth cut by polylines; "
             "writes one mesh (.vtu; a cloth's triangle copies as .vtp) and one .vtp surface per output frame, ParaView "
             ".pvd series and summary.json");
  command->add_option("SCENE", options->scene, "Scene file (.json); see include/tetcut/scene.hpp for the format")->required();
  command->add_option("-o,--out", options->out, "Output directory (created)")->required();
  command->add_option("--frames", options->frames, "Stop after this many output frames (a quick look)")
      ->check(CLI::NonNegativeNumber);
  command->add_flag("--png", options->png,
                    "Also render each frame's surface to frame_NNNN.png (pieces coloured; the camera is the scene's "
                    "output.picture, by default framing the first frame grown by half)");
  command->add_option("--animation", options->animation,
                      "Also assemble the frames into an animation with ffmpeg: .mp4 or .gif (implies --png)");
  command->add_option("--fps", options->fps, "Frames per second of the animation (default: real time, 1 / output_every, "
                                             "within 1 to 60)")
      ->check(CLI::Range(0.1, 240.0));
  command->add_flag("--check-intersections", options->check_intersections,
                    "Count, at each output frame, the pairs of material-surface triangles of different tet copies that "
                    "intersect (exact tests; pairs sharing a vertex, or a point of a cut not yet opened, excluded); "
                    "summary.json gives them per frame and their maximum");
  command->callback([options, &action] { action = [options] { return run_sim(*options); }; });
}

}  // namespace tetcut::cli
