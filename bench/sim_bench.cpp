// One implicit (backward Euler) step of a hanging block under gravity, on BCC lattices of about 10k
// and 100k tets: assembly, projected Newton, the linear solves, line search. The first steps from
// rest are timed (the block is deforming, so Newton takes its usual few iterations).

#include <benchmark/benchmark.h>

#include <tetcut/generators.hpp>
#include <tetcut/sim.hpp>

namespace {

void step(benchmark::State& state, double spacing, tetcut::sim::Model model, tetcut::sim::LinearSolver solver) {
  const tetcut::TetMesh mesh = tetcut::make_bcc(tetcut::Box{tetcut::Vec3(0, 0, 0), tetcut::Vec3(1, 1, 2)}, spacing);
  tetcut::sim::Material material;
  material.model = model;
  material.youngs_modulus = 1e5;
  tetcut::sim::StepOptions options;
  options.dt = 0.01;
  options.solver = solver;
  int iterations = 0, steps = 0;
  for (auto _ : state) {
    state.PauseTiming();
    tetcut::sim::Simulator sim(mesh, material);
    for (tetcut::Index n = 0; n < mesh.num_nodes(); ++n) {
      if (mesh.rest()(n, 2) >= 2 - 1e-12) sim.pin(n);
    }
    state.ResumeTiming();
    const tetcut::sim::StepReport report = sim.step(options);
    iterations += report.newton_iterations;
    ++steps;
  }
  state.counters["tets"] = mesh.num_tets();
  state.counters["newton_per_step"] = static_cast<double>(iterations) / steps;
}

void BM_Step10k_Cholesky(benchmark::State& s) { step(s, 0.136, tetcut::sim::Model::kStableNeoHookean, tetcut::sim::LinearSolver::kCholesky); }
void BM_Step100k_ConjugateGradient(benchmark::State& s) {
  step(s, 0.0624, tetcut::sim::Model::kStableNeoHookean, tetcut::sim::LinearSolver::kConjugateGradient);
}
void BM_Step10k_ConjugateGradient(benchmark::State& s) {
  step(s, 0.136, tetcut::sim::Model::kStableNeoHookean, tetcut::sim::LinearSolver::kConjugateGradient);
}
void BM_Step10k_Corotated(benchmark::State& s) {
  step(s, 0.136, tetcut::sim::Model::kCorotated, tetcut::sim::LinearSolver::kConjugateGradient);
}

BENCHMARK(BM_Step10k_Cholesky)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Step10k_ConjugateGradient)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Step10k_Corotated)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Step100k_ConjugateGradient)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
