// Progressive cutting: a scalpel sweeping through BCC lattices of the unit cube of about 10k, 100k
// and 1M tets, 10 triangles (5 blade steps) per batch. The blade is scaled to the lattice spacing,
// so every batch crosses a similar number of tets (reported as tets_per_batch); the claim to check
// is that the time per batch does not grow with the mesh. World-space batches run on a deformed
// mesh whose positions were set once; setting positions (a refit over all copies) is timed apart.

#include <benchmark/benchmark.h>

#include <tetcut/blade.hpp>
#include <tetcut/cutter.hpp>
#include <tetcut/generators.hpp>

#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <vector>

namespace {

using tetcut::BladePose;
using tetcut::Cutter;
using tetcut::Vec3;

// Lattice spacings giving about 10k, 100k and 1M tets (12 per cube plus the boundary).
double spacing(int tets_thousands) { return tets_thousands <= 10 ? 1.0 / 9 : tets_thousands <= 100 ? 1.0 / 20 : 1.0 / 44; }

const tetcut::TetMesh& lattice(int tets_thousands) {
  static std::map<int, std::unique_ptr<tetcut::TetMesh>> meshes;
  auto& mesh = meshes[tets_thousands];
  if (!mesh) mesh = std::make_unique<tetcut::TetMesh>(tetcut::make_bcc(tetcut::Box{}, spacing(tets_thousands)));
  return *mesh;
}

// A vertical blade 1.5 lattice cells long, advancing 0.3 cells per step along rows across the
// cube: row after row, at rising depth, so that every batch cuts fresh material (the smallest
// lattice has room for the 20 batches timed). In general position the rows are offset from the
// lattice's planes; `aligned` starts them on lattice planes, so the strip runs along tet faces
// and through nodes: the degenerate case, where exact arithmetic has most to do.
class Scalpel {
 public:
  Scalpel(double h, bool aligned) : h_(h) {
    if (!aligned) {
      x_ += 0.137 * h;
      y_ += 0.371 * h;
      z_ += 0.293 * h;
    }
  }
  std::vector<BladePose> next_batch() {
    std::vector<BladePose> poses;
    for (int i = 0; i <= 5; ++i) {
      if (i > 0) advance();
      poses.push_back({Vec3(x_, y_, z_), Vec3(x_, y_, z_ + 1.5 * h_)});
    }
    return poses;
  }

 private:
  void advance() {
    x_ += 0.3 * h_;
    if (x_ > 0.9) {
      x_ = 0.1;
      y_ += 1.1 * h_;
      if (y_ > 0.9) {
        y_ = 0.1;
        z_ += 2.1 * h_;
      }
    }
  }
  double h_, x_ = 0.1, y_ = 0.1, z_ = 0.05;
};

void BM_ScalpelStep(benchmark::State& state, bool world, bool aligned) {
  const int size = static_cast<int>(state.range(0));
  const tetcut::TetMesh& mesh = lattice(size);
  Cutter cutter(mesh);
  if (world) {
    // A gentle twist about the vertical axis, set once.
    tetcut::Points twisted = mesh.rest();
    for (tetcut::Index n = 0; n < twisted.rows(); ++n) {
      const double angle = 0.2 * mesh.rest()(n, 2);
      const double x = mesh.rest()(n, 0) - 0.5, y = mesh.rest()(n, 1) - 0.5;
      twisted(n, 0) = 0.5 + std::cos(angle) * x - std::sin(angle) * y;
      twisted(n, 1) = 0.5 + std::sin(angle) * x + std::cos(angle) * y;
    }
    cutter.set_current(twisted);
  }
  Scalpel scalpel(spacing(size), aligned);
  double touched = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const std::vector<BladePose> poses = scalpel.next_batch();
    const tetcut::TriangleSurface batch = tetcut::swept_blade(poses);
    state.ResumeTiming();
    const tetcut::CutBatchReport report = world ? cutter.cut_deformed(batch) : cutter.cut(batch);
    touched += report.tets_touched;
  }
  state.counters["tets"] = mesh.num_tets();
  state.counters["tets_per_batch"] = touched / static_cast<double>(state.iterations());
}

// A scalpel step followed by the updated material surface, as a simulator that draws every frame
// needs it: the surface was built once before timing, so each step rebuilds only the patches the
// batch changed and numbers the whole surface (O(surface)), which is timed apart as well.
void BM_ScalpelStepWithSurface(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  const tetcut::TetMesh& mesh = lattice(size);
  Cutter cutter(mesh);
  (void)cutter.surface();
  Scalpel scalpel(spacing(size), false);
  double triangles = 0, surface_seconds = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const tetcut::TriangleSurface batch = tetcut::swept_blade(scalpel.next_batch());
    state.ResumeTiming();
    cutter.cut(batch);
    const auto start = std::chrono::steady_clock::now();
    const tetcut::MaterialSurface surface = cutter.surface();
    surface_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    triangles += static_cast<double>(surface.surface.num_triangles());
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["tets"] = mesh.num_tets();
  state.counters["surface_triangles"] = triangles / n;
  state.counters["surface_ms"] = 1e3 * surface_seconds / n;
}

void BM_ScalpelStepRest(benchmark::State& state) { BM_ScalpelStep(state, false, false); }
void BM_ScalpelStepWorld(benchmark::State& state) { BM_ScalpelStep(state, true, false); }
void BM_ScalpelStepRestAlongLatticePlanes(benchmark::State& state) { BM_ScalpelStep(state, false, true); }
void BM_ScalpelStepWorldAlongLatticePlanes(benchmark::State& state) { BM_ScalpelStep(state, true, true); }

void BM_SetCurrent(benchmark::State& state) {
  const tetcut::TetMesh& mesh = lattice(static_cast<int>(state.range(0)));
  Cutter cutter(mesh);
  tetcut::Points moved = mesh.rest();
  for (auto _ : state) {
    moved.col(2).array() += 1e-3;
    cutter.set_current(moved);
  }
  state.counters["tets"] = mesh.num_tets();
}

// Sizes in thousands of tets.
BENCHMARK(BM_ScalpelStepRest)->Arg(10)->Arg(100)->Arg(1000)->Iterations(20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScalpelStepWorld)->Arg(10)->Arg(100)->Arg(1000)->Iterations(20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScalpelStepRestAlongLatticePlanes)->Arg(100)->Iterations(20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScalpelStepWorldAlongLatticePlanes)->Arg(100)->Iterations(20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScalpelStepWithSurface)->Arg(10)->Arg(100)->Arg(1000)->Iterations(20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SetCurrent)->Arg(10)->Arg(100)->Arg(1000)->Iterations(5)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
