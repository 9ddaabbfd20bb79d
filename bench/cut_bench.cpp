// Cutting benchmarks: the paper's Figures 2 and 4, and a 111k-tet BCC lattice of the unit cube cut
// by a 20,480-triangle sphere (a closed surface crossing about 7,600 tets). Each reports the time
// to insert the triangles (Cutter::cut) and, separately, to build the result (components, copies,
// joins, material surface), with the sizes of what was built as counters.

#include <benchmark/benchmark.h>

#include <tetcut/cutter.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>

#include <optional>

namespace {

using tetcut::CutResult;
using tetcut::Cutter;
using tetcut::TetMesh;
using tetcut::TriangleSurface;

void report(benchmark::State& state, const CutResult& r) {
  state.counters["tets_out"] = r.mesh.mesh.num_tets();
  state.counters["pieces"] = r.mesh.num_pieces();
  state.counters["surface_triangles"] = r.surface.surface.num_triangles();
}

// Insertion alone: a fresh Cutter per iteration (construction excluded from the time).
void insert(benchmark::State& state, const TetMesh& mesh, const TriangleSurface& cut) {
  for (auto _ : state) {
    state.PauseTiming();
    std::optional<Cutter> cutter(std::in_place, mesh);
    state.ResumeTiming();
    cutter->cut(cut);
    benchmark::ClobberMemory();
    state.PauseTiming();
    cutter.reset();
    state.ResumeTiming();
  }
  state.counters["tets_in"] = mesh.num_tets();
  state.counters["triangles"] = cut.num_triangles();
}

// Building the result from a fresh cut state (cutting excluded from the time): the first
// result() builds every surface patch; later ones would rebuild only what later batches changed.
void result(benchmark::State& state, const TetMesh& mesh, const TriangleSurface& cut) {
  std::optional<CutResult> r;
  for (auto _ : state) {
    state.PauseTiming();
    std::optional<Cutter> cutter(std::in_place, mesh);
    cutter->cut(cut);
    state.ResumeTiming();
    r = cutter->result();
    benchmark::DoNotOptimize(r);
    state.PauseTiming();
    cutter.reset();
    state.ResumeTiming();
  }
  report(state, *r);
}

const TetMesh& sphere_mesh() {
  static const TetMesh mesh = tetcut::make_bcc(tetcut::Box{}, 1.0 / 21);
  return mesh;
}
const TriangleSurface& sphere() {
  static const TriangleSurface s = tetcut::figures::icosphere(tetcut::Vec3(0.5, 0.5, 0.5), 0.37, 5);
  return s;
}

void BM_Figure2_Insert(benchmark::State& s) { insert(s, tetcut::figures::figure2_tet(), tetcut::figures::figure2_triangles()); }
void BM_Figure2_Result(benchmark::State& s) { result(s, tetcut::figures::figure2_tet(), tetcut::figures::figure2_triangles()); }
void BM_Figure4_Insert(benchmark::State& s) { insert(s, tetcut::figures::figure4_cube(), tetcut::figures::figure4_planes()); }
void BM_Figure4_Result(benchmark::State& s) { result(s, tetcut::figures::figure4_cube(), tetcut::figures::figure4_planes()); }
void BM_SphereInBcc111k_Insert(benchmark::State& s) { insert(s, sphere_mesh(), sphere()); }
void BM_SphereInBcc111k_Result(benchmark::State& s) { result(s, sphere_mesh(), sphere()); }

BENCHMARK(BM_Figure2_Insert)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Figure2_Result)->Unit(benchmark::kMillisecond)->Iterations(10);
BENCHMARK(BM_Figure4_Insert)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Figure4_Result)->Unit(benchmark::kMillisecond)->Iterations(10);
BENCHMARK(BM_SphereInBcc111k_Insert)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_SphereInBcc111k_Result)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
