// Generation and I/O throughput on a ~100k-tet BCC mesh.

#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>

#include <benchmark/benchmark.h>

#include <filesystem>

namespace {

const tetcut::TetMesh& bcc_mesh() {
  // Spacing 1/19 gives 19^3 cubes, 12 tets per cube: about 82k tets plus boundary pyramids.
  static const tetcut::TetMesh mesh = tetcut::make_bcc(tetcut::Box{}, 1.0 / 19);
  return mesh;
}

void BM_MakeBcc(benchmark::State& state) {
  for (auto _ : state) {
    const tetcut::TetMesh mesh = tetcut::make_bcc(tetcut::Box{}, 1.0 / 19);
    benchmark::DoNotOptimize(mesh.num_tets());
  }
  state.counters["tets"] = static_cast<double>(bcc_mesh().num_tets());
}
BENCHMARK(BM_MakeBcc)->Unit(benchmark::kMillisecond);

void BM_WriteRead(benchmark::State& state, const char* extension) {
  const auto path = std::filesystem::temp_directory_path() / (std::string("tetcut_bench") + extension);
  for (auto _ : state) {
    tetcut::write_tet_mesh(path, bcc_mesh());
    const tetcut::TetMesh back = tetcut::read_tet_mesh(path);
    benchmark::DoNotOptimize(back.num_tets());
  }
  state.counters["tets"] = static_cast<double>(bcc_mesh().num_tets());
  std::filesystem::remove(path);
}
BENCHMARK_CAPTURE(BM_WriteRead, vtu, ".vtu")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WriteRead, medit, ".mesh")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WriteRead, gmsh41, ".msh")->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
