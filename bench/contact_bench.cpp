// What surface contact (self_collision) adds to a step: the same scene run twice through the
// live session, without and with contact of the material surface, printing the median, mean and
// 99th percentile of consecutive steps' wall times (the mean holds what is done every few steps,
// a rebuild of the candidates, which the median may not), the surface's size, the contact pairs
// and the time in continuous collision detection, and where a step's time goes, contact's own
// parts too. Default: examples/live-femur.json (the CT femur from libcgal-demo embedded in an
// 11k-tet lattice, hanging under gravity, the real-time solver: nothing comes near). With
// contact at work: bench/scenes/hand-sliced.json (libcgal-demo's hand in an 11k-tet lattice, 43k
// surface triangles, cut by a slanted plane; the upper part slides down the cut, thousands of
// pairs within the thickness). Cut while it runs: bench/scenes/femur-incision.json (the femur
// incised halfway through by a scalpel over 0.8 s, the surface set again after every cut).
//
// Usage: tetcut_bench_contact [SCENE] [STEPS] [off|on] [per-step]: both runs unless one is named
// (one alone, for a profiler); with per-step, also a line for each step of each run: its wall
// time and stages (a cut's steps carry the cut, the new surface and the simulator's remesh, the
// contact surface set again in it), Newton and rescue iterations, and contact's parts in it (the
// list's rebuilds, their ms, CCD, active terms, guards, joins), the candidates and pairs after it
// (the first step's stages hold the session's set-up). The mean of a scene cut while it runs mixes
// its cut steps' cost with its other steps', which this tells apart.

#include <tetcut/scene.hpp>
#include <tetcut/session.hpp>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "step_times.hpp"

int main(int argc, char** argv) {
  using namespace tetcut;
  const std::string path = argc > 1 ? argv[1] : TETCUT_EXAMPLES "/live-femur.json";
  const int steps = argc > 2 ? std::atoi(argv[2]) : 60;
  const std::string only = argc > 3 ? argv[3] : "";
  if (!only.empty() && only != "on" && only != "off") {
    std::fprintf(stderr, "tetcut_bench_contact: the third argument is on or off, not '%s'\n", only.c_str());
    return 2;
  }
  const std::string detail = argc > 4 ? argv[4] : "";
  if (!detail.empty() && detail != "per-step") {
    std::fprintf(stderr, "tetcut_bench_contact: the fourth argument is per-step, not '%s'\n", detail.c_str());
    return 2;
  }
  const bool per_step = !detail.empty();
  Scene scene = load_scene(path);
  std::printf("scene %s, %d steps from rest\n", path.c_str(), steps);
  std::printf("%-16s %8s %8s %10s %10s %10s %12s %10s %10s %12s %10s %8s %8s %11s %9s %10s\n", "self_collision", "tets", "surface",
              "median ms", "mean ms", "p99 ms", "contact pairs", "ccd ms", "rebuilds", "copy pairs", "candidates", "newton", "cg",
              "assemble ms", "solve ms", "search ms");
  std::vector<sim::Simulator::SurfaceContactState> parts;
  std::vector<double> matrix_ms;  // per run, the constraint terms' matrix ms a step
  for (const bool on : {false, true}) {
    if (!only.empty() && (only == "on") != on) continue;
    scene.self_collision = on;
    Session session(scene);
    std::vector<double> ms;
    Index pairs = 0;
    double ccd = 0;
    // Per step, over the steps: where a step's time goes (contact's energies and matrices are
    // in assemble and search, its CCD in ccd).
    double newton = 0, cg = 0, assemble = 0, solve = 0, search = 0, matrix = 0;
    if (per_step) {
      std::printf("%-4s %5s %4s %8s %7s %7s %7s %7s %6s %6s %5s %8s %8s %7s %7s %7s %7s %10s %8s\n", on ? "on" : "off", "step", "cut",
                  "ms", "cut", "surface", "remesh", "step", "newton", "rescue", "cg", "rebuilds", "rebuild", "ccd", "active", "guards",
                  "joins", "candidates", "pairs");
    }
    for (int s = 0; s < steps; ++s) {
      using ContactState = sim::Simulator::SurfaceContactState;
      const ContactState before = per_step ? session.simulator().surface_contact() : ContactState{};
      const bench::Clock::time_point start = bench::Clock::now();
      const SessionStep step = session.advance();
      ms.push_back(bench::ms_since(start));
      if (per_step) {
        const ContactState after = session.simulator().surface_contact();
        const SceneStageSeconds& stage = step.seconds;
        std::printf("%-4s %5d %4d %8.2f %7.2f %7.2f %7.2f %7.2f %6d %6d %5d %8d %8.2f %7.2f %7.2f %7.2f %7.2f %10d %8d\n",
                    on ? "on" : "off", s, step.topology_changed ? 1 : 0, ms.back(), 1e3 * stage.cut, 1e3 * stage.surface,
                    1e3 * stage.remesh, 1e3 * stage.step,
                    step.report.newton_iterations, step.report.rescue_iterations, step.report.cg_iterations,
                    static_cast<int>(after.rebuilds - before.rebuilds), 1e3 * (after.rebuild_seconds - before.rebuild_seconds),
                    1e3 * (after.ccd_seconds - before.ccd_seconds), 1e3 * (after.active_seconds - before.active_seconds),
                    1e3 * (after.guard_seconds - before.guard_seconds), 1e3 * (after.join_seconds - before.join_seconds),
                    static_cast<int>(after.candidates), static_cast<int>(step.report.contact_pairs));
      }
      pairs = std::max(pairs, step.report.contact_pairs);
      ccd += 1e3 * step.report.contact_seconds;
      newton += step.report.newton_iterations;
      cg += step.report.cg_iterations;
      assemble += 1e3 * step.report.assemble_seconds;
      solve += 1e3 * step.report.solve_seconds;
      search += 1e3 * step.report.line_search_seconds;
      matrix += 1e3 * step.report.constraint_matrix_seconds;
    }
    const sim::Simulator::SurfaceContactState contact = session.simulator().surface_contact();
    std::printf("%-16s %8d %8d %10.2f %10.2f %10.2f %12d %10.2f %10d %12d %10d %8.2f %8.1f %11.2f %9.2f %10.2f\n", on ? "on" : "off",
                session.simulator().num_tets(), session.surface().surface.num_triangles(), bench::median(ms), bench::mean(ms),
                bench::percentile(ms, 0.99), pairs, ccd / steps, contact.rebuilds, contact.copy_pair_rebuilds, contact.candidates,
                newton / steps, cg / steps, assemble / steps, solve / steps, search / steps);
    parts.push_back(contact);
    matrix_ms.push_back(matrix / steps);
  }
  // Contact's own parts, ms a step over the run (each apart from the rebuilds it set off), and
  // the constraint terms' blocks added into the Newton matrix (in assemble above; without
  // contact, the obstacles' and springs' terms). The solve with contact's blocks is in solve.
  std::printf("%-16s %10s %10s %10s %10s %10s %10s\n", "contact parts", "rebuild", "ccd", "active", "guards", "joins", "matrix");
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const sim::Simulator::SurfaceContactState& c = parts[i];
    std::printf("%-16s %10.2f %10.2f %10.2f %10.2f %10.2f %10.2f\n", parts.size() == 1 ? only.c_str() : i == 0 ? "off" : "on",
                1e3 * c.rebuild_seconds / steps, 1e3 * c.ccd_seconds / steps, 1e3 * c.active_seconds / steps, 1e3 * c.guard_seconds / steps,
                1e3 * c.join_seconds / steps, matrix_ms[i]);
  }
}
