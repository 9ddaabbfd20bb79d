// Simulation at interactive rates, measured: a block 1 x 1 x 2 hanging from its top (BCC lattices
// of 11,520 and 114,444 tets; E = 1e5, nu = 0.3, density 1000, dt = 0.01, lumped mass), as the
// simulation issue and Vega FEM's comparison use it.
//
// 1. Steps: 30 consecutive steps from rest, per model and mode (converged to the default
//    tolerance; one Newton iteration; the real-time budget of one Newton iteration with 30 CG
//    iterations, Newton started at the prediction and at the step's start), the median and 90th
//    percentile of the wall time per step, the stages, and the tip's sag after the 30 steps
//    against the converged run's (what the budget costs). Then the first block turning freely:
//    the kinetic energy each mode leaves after 2 s.
// 2. A scalpel cutting the hanging block live: each frame the blade advances 5 steps (10 triangles),
//    its world-space poses are followed in the material (set_current, to_rest), the strip is cut,
//    the surface updated, the simulator remeshed from the cutter, and one step taken. Median and
//    99th percentile over 60 frames, and each stage's median and 99th percentile. The blade is
//    scaled to the lattice spacing as in tetcut_bench_progressive (1.5 spacings long, 0.3 per
//    step, rows 2.1 apart), so that every batch crosses fresh tets, a similar number at both sizes.
//
// Usage: tetcut_bench_sim [--small | --large] [--steps | --scalpel]
//   --small / --large: the 11.5k or the 114k mesh only; --steps / --scalpel: that part only.

#include <tetcut/blade.hpp>
#include <tetcut/cutter.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/sim.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "step_times.hpp"

namespace {

using tetcut::Index;
using tetcut::Vec3;
using tetcut::bench::Clock;
using tetcut::bench::median;
using tetcut::bench::ms_since;
using tetcut::bench::percentile;

struct Block {
  double spacing;
  tetcut::TetMesh mesh;
};

tetcut::sim::Material material(tetcut::sim::Model model) {
  tetcut::sim::Material m;
  m.model = model;
  m.youngs_modulus = 1e5;
  m.poissons_ratio = 0.3;
  m.density = 1000;
  return m;
}

void pin_top(const tetcut::TetMesh& mesh, tetcut::sim::Simulator* sim) {
  for (Index n = 0; n < mesh.num_nodes(); ++n) {
    if (mesh.rest()(n, 2) >= 2 - 1e-12) sim->pin(n);
  }
}

// Mean vertical displacement of the bottom face's nodes.
double tip_sag(const tetcut::TetMesh& mesh, const tetcut::sim::Simulator& sim) {
  double sum = 0;
  int count = 0;
  for (Index n = 0; n < mesh.num_nodes(); ++n) {
    if (mesh.rest()(n, 2) > 1e-12) continue;
    sum += mesh.rest()(n, 2) - sim.positions()(n, 2);
    ++count;
  }
  return sum / count;
}

struct Mode {
  const char* name;
  tetcut::sim::StepOptions options;
};

void steps(const Block& block, tetcut::sim::Model model, const char* model_name) {
  const int count = 30;
  std::vector<Mode> modes;
  tetcut::sim::StepOptions converged;
  converged.dt = 0.01;
  modes.push_back({"converged", converged});
  tetcut::sim::StepOptions one = converged;
  one.max_newton_iterations = 1;
  modes.push_back({"1 Newton iteration", one});
  modes.push_back({"real time (1 x 30 CG)", tetcut::sim::StepOptions::real_time(0.01)});
  tetcut::sim::StepOptions from_start = tetcut::sim::StepOptions::real_time(0.01);
  from_start.first_guess = tetcut::sim::FirstGuess::kStart;
  modes.push_back({"real time, from the start", from_start});
  double converged_sag = 0;
  for (const Mode& mode : modes) {
    tetcut::sim::Simulator sim(block.mesh, material(model));
    pin_top(block.mesh, &sim);
    std::vector<double> total, assemble, solve, search;
    double newton = 0, cg = 0, residual = 0;
    for (int s = 0; s < count; ++s) {
      const auto start = Clock::now();
      const tetcut::sim::StepReport r = sim.step(mode.options);
      total.push_back(ms_since(start));
      assemble.push_back(1e3 * r.assemble_seconds);
      solve.push_back(1e3 * r.solve_seconds);
      search.push_back(1e3 * r.line_search_seconds);
      newton += r.newton_iterations;
      cg += r.cg_iterations;
      residual = std::max(residual, r.residual);
    }
    const double sag = tip_sag(block.mesh, sim);
    if (&mode == &modes.front()) converged_sag = sag;
    std::printf("| %s | %s | %s | %.2f | %.2f | %.2f / %.2f / %.2f | %.2f | %.1f | %.1e | %.6f (%+.2e) |\n",
                (std::to_string(block.mesh.num_tets()) + " tets").c_str(), model_name, mode.name, median(total), percentile(total, 0.9),
                median(assemble), median(solve), median(search), newton / count, cg / count, residual, sag,
                (sag - converged_sag) / converged_sag);
  }
}

// The block turning freely about its long axis at 1 rad/s (no gravity, dt = 1/30 as in the live
// session, 60 steps): the share of its kinetic energy left after 2 s, per mode. Backward Euler
// damps a turn; a budget of one iteration a step damps it more, and more again from the start
// (StepOptions::first_guess), whose linearisation does not see the turn's curve.
void turning(const Block& block, double youngs_modulus) {
  tetcut::sim::StepOptions converged;
  converged.dt = 1.0 / 30;
  converged.gravity = Vec3::Zero();
  tetcut::sim::StepOptions predicted = tetcut::sim::StepOptions::real_time(1.0 / 30);
  predicted.gravity = Vec3::Zero();
  tetcut::sim::StepOptions started = predicted;
  started.first_guess = tetcut::sim::FirstGuess::kStart;
  std::printf("| %s | %.0e |", (std::to_string(block.mesh.num_tets()) + " tets").c_str(), youngs_modulus);
  for (const tetcut::sim::StepOptions& options : {converged, predicted, started}) {
    tetcut::sim::Material m = material(tetcut::sim::Model::kStableNeoHookean);
    m.youngs_modulus = youngs_modulus;
    tetcut::sim::Simulator sim(block.mesh, m);
    tetcut::Points v = tetcut::Points::Zero(sim.num_nodes(), 3);
    for (Index n = 0; n < sim.num_nodes(); ++n) v.row(n) = Vec3(0, 0, 1).cross(sim.positions().row(n).transpose() - Vec3(0.5, 0.5, 1)).transpose();
    sim.set_velocities(v);
    const double before = sim.kinetic_energy();
    for (int s = 0; s < 60; ++s) sim.step(options);
    std::printf(" %.3f |", sim.kinetic_energy() / before);
  }
  std::printf("\n");
}

// A blade along y, entering the front face (y = 0) 1.5 lattice spacings deep at height z, advancing
// along x 0.3 spacings per step; rows descend 2.1 spacings at a time (fresh tets), off the
// lattice's planes.
class Scalpel {
 public:
  explicit Scalpel(double h) : h_(h), z_(1.8 + 0.293 * h) {}
  tetcut::BladePose pose() const { return {Vec3(x_, -0.1 * h_, z_), Vec3(x_, 1.4 * h_, z_)}; }
  void advance() {
    x_ += 0.3 * h_;
    if (x_ > 1.1) {
      x_ = -0.1 + 0.137 * h_;
      z_ -= 2.1 * h_;
    }
  }

 private:
  double h_, x_ = -0.1, z_;
};

void scalpel(const Block& block, const tetcut::sim::StepOptions& options, const char* mode) {
  tetcut::Cutter cutter(block.mesh);
  tetcut::sim::Simulator sim(block.mesh, material(tetcut::sim::Model::kStableNeoHookean));
  pin_top(block.mesh, &sim);
  // Let the block hang and swing a little first, so that the blade cuts a deformed, moving body.
  for (int s = 0; s < 10; ++s) sim.step(options);
  Scalpel blade(block.spacing);
  std::vector<double> total, cut, surface, remesh, step, touched;
  std::vector<tetcut::BladePose> poses;
  for (int frame = 0; frame < 60; ++frame) {
    const auto start = Clock::now();
    // Follow the blade in the material: its world-space poses mapped through the current motion.
    cutter.set_current(sim.positions());
    tetcut::Points world(12, 3);
    for (int i = 0; i < 6; ++i) {
      if (i > 0) blade.advance();
      const tetcut::BladePose p = blade.pose();
      world.row(2 * i) = p.a.transpose();
      world.row(2 * i + 1) = p.b.transpose();
    }
    const tetcut::Points rest = cutter.to_rest(world);
    poses.clear();
    for (int i = 0; i < 6; ++i) poses.push_back({rest.row(2 * i).transpose(), rest.row(2 * i + 1).transpose()});
    const tetcut::CutBatchReport batch = cutter.cut(tetcut::swept_blade(poses));
    const double cut_ms = ms_since(start);
    auto t = Clock::now();
    const tetcut::MaterialSurface material_surface = cutter.surface();
    const double surface_ms = ms_since(t);
    t = Clock::now();
    sim.remesh(cutter, batch);
    const double remesh_ms = ms_since(t);
    t = Clock::now();
    sim.step(options);
    const double step_ms = ms_since(t);
    total.push_back(ms_since(start));
    cut.push_back(cut_ms);
    surface.push_back(surface_ms);
    remesh.push_back(remesh_ms);
    step.push_back(step_ms);
    touched.push_back(batch.tets_touched);
    if (material_surface.surface.num_triangles() == 0) std::printf("no surface?\n");
  }
  const auto stage = [](const std::vector<double>& v) {
    char text[64];
    std::snprintf(text, sizeof text, "%.2f / %.2f", median(v), percentile(v, 0.99));
    return std::string(text);
  };
  std::printf("| %d -> %d tets | %s | %.2f | %.2f | %s | %s | %s | %s | %.0f |\n", block.mesh.num_tets(), sim.num_tets(), mode,
              median(total), percentile(total, 0.99), stage(cut).c_str(), stage(surface).c_str(), stage(remesh).c_str(),
              stage(step).c_str(), median(touched));
}

}  // namespace

int main(int argc, char** argv) {
  bool small = true, large = true, run_steps = true, run_scalpel = true;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--small") == 0) large = false;
    else if (std::strcmp(argv[i], "--large") == 0) small = false;
    else if (std::strcmp(argv[i], "--steps") == 0) run_scalpel = false;
    else if (std::strcmp(argv[i], "--scalpel") == 0) run_steps = false;
    else {
      std::fprintf(stderr, "usage: %s [--small | --large] [--steps | --scalpel]\n", argv[0]);
      return 2;
    }
  }
  std::vector<Block> blocks;
  for (const double h : {0.136, 0.0624}) {
    if ((h > 0.1 && !small) || (h < 0.1 && !large)) continue;
    blocks.push_back({h, tetcut::make_bcc(tetcut::Box{Vec3(0, 0, 0), Vec3(1, 1, 2)}, h)});
  }
  if (run_steps) {
  std::printf("Steps from rest (30 in a row): median and 90th percentile ms per step; stage medians (assemble / solve / line "
              "search) ms; Newton and CG iterations per step; the largest residual left; tip sag after 30 steps (relative to "
              "the converged run's)\n\n");
  std::printf("| Mesh | Model | Mode | Median | p90 | Stages | Newton | CG | Residual | Tip sag |\n|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Block& b : blocks) {
    steps(b, tetcut::sim::Model::kStableNeoHookean, "stable Neo-Hookean");
    steps(b, tetcut::sim::Model::kCorotated, "corotated");
  }
  std::printf("\nTurning freely at 1 rad/s about the long axis (no gravity, dt = 1/30, 60 steps): kinetic energy left after 2 s\n\n");
  std::printf("| Mesh | E | converged | real time | real time, from the start |\n|---|---|---|---|---|\n");
  for (const double e : {1e5, 1e6}) turning(blocks.front(), e);
  }
  if (!run_scalpel) return 0;
  std::printf("\nScalpel loop (60 frames, each: follow the blade, cut 10 triangles, surface, remesh, one step): ms per frame, "
              "median and 99th percentile, and per stage (median / p99)\n\n");
  std::printf("| Mesh | Step mode | Median | p99 | Cut | Surface | Remesh | Step | Tets touched |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const Block& b : blocks) {
    tetcut::sim::StepOptions converged;
    converged.dt = 0.01;
    scalpel(b, tetcut::sim::StepOptions::real_time(0.01), "real time");
    scalpel(b, tetcut::sim::StepOptions::real_time(0.01, 1, 10), "real time, 10 CG");
    scalpel(b, converged, "converged");
  }
  return 0;
}
