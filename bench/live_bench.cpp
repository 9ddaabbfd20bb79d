// The live session's loop, measured without a browser: what `tetcut serve` does each tick on its
// default scene (examples/live-femur.json: the CT femur from libcgal-demo in an 11k-tet lattice,
// held at its base, a floor below), driven by a scripted hand.
//
// Phases, one blade pose or hook target per step as the page sends them at 30 frames a second:
//   idle      30 steps untouched
//   scalpel   a horizontal blade (its edge along y, 1.2 long) swept along x through the shaft
//             at two thirds of its height in 45 poses: the strip between poses is cut each step
//   falling   60 steps: the freed top falls onto the floor
//   hook      a hook on the stump's surface pulled sideways for 30 steps, held 15, let go, 30 more
// Per step: the work of one tick (events, cut, the new surface and topology message after a
// cut, the step, the frame message), its median and 99th percentile, the steps a second that
// leaves room for, and for the cutting steps, how long from a blade pose arriving to its
// topology message being ready (the server sends it before stepping; a pose also waits up to
// one tick, 33 ms, for the tick to begin).
//
// Usage: tetcut_bench_live [SCENE] [per-tick]   (default: examples/live-femur.json); with per-tick,
// also a line for each tick: its wall time, Newton and rescue iterations, the residual, and, where
// the scene has self_collision, the moves CCD shortened, contact's seconds in the step, its pairs,
// candidates and guards after it, and the list's rebuilds and contact's parts within the tick
// (where a tick with contact goes: a side pressed onto its cut and dragged costs a rebuild of the
// list per leg of each Newton move; docs/contact.md).

#include <tetcut/render.hpp>
#include <tetcut/scene.hpp>
#include <tetcut/session.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "server/live_protocol.hpp"
#include "step_times.hpp"

namespace {

using tetcut::Index;
using tetcut::Vec3;
using tetcut::bench::Clock;
using tetcut::bench::ms_since;
using tetcut::bench::percentile;

struct Phase {
  explicit Phase(std::string n) : name(std::move(n)) {}
  std::string name;
  std::vector<double> tick_ms, step_ms, surface_ms, topology_ms, latency_ms, change_bytes;
  double max_residual = 0;
  int rescues = 0;
};

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : TETCUT_EXAMPLES "/live-femur.json";
  const std::string detail = argc > 2 ? argv[2] : "";
  if (!detail.empty() && detail != "per-tick") {
    std::fprintf(stderr, "tetcut_bench_live: the second argument is per-tick, not '%s'\n", detail.c_str());
    return 2;
  }
  const bool per_tick = !detail.empty();
  const auto setup = Clock::now();
  const tetcut::Scene scene = tetcut::load_scene(path);
  tetcut::Session session(scene);
  std::printf("tetcut_bench_live: %s\n  %lld tets, %lld nodes, %lld surface triangles; set up in %.0f ms; dt %.4f s\n", path.c_str(),
              static_cast<long long>(session.simulator().num_tets()), static_cast<long long>(session.simulator().num_nodes()),
              static_cast<long long>(session.surface().surface.num_triangles()), ms_since(setup), scene.step.dt);

  std::uint32_t version = 0;
  tetcut::live::NodePieces pieces;
  // The server's work after a cut: the surface, the pieces, the topology message.
  tetcut::live::TopologyEncoder encoder;
  const auto topology = [&] { return encoder.encode(++version, session, &pieces); };
  std::size_t topology_bytes = topology().full.size();

  // The femur's box, for the scripted hand.
  const tetcut::Points rest = session.surface_positions();
  const Vec3 low = rest.colwise().minCoeff().transpose(), high = rest.colwise().maxCoeff().transpose();
  const Vec3 centre = (low + high) / 2;
  const double height = high.z() - low.z();

  std::vector<Phase> phases;
  std::size_t frame_bytes = 0;
  using ContactState = tetcut::sim::Simulator::SurfaceContactState;
  ContactState contact_before = session.simulator().surface_contact();
  if (per_tick) {
    std::printf("  %-8s %4s %7s %6s %6s %9s %7s %10s %6s %10s %6s %8s %8s %7s %7s %7s %7s\n", "phase", "tick", "ms", "newton", "rescue",
                "residual", "limited", "contact ms", "pairs", "candidates", "guards", "rebuilds", "rebuild", "ccd", "active", "guards", "joins");
  }
  // One tick: `events` (before the step), then the server's messages and the step.
  const auto tick = [&](Phase& phase, const auto& events) {
    const auto start = Clock::now();
    const int changes = session.topology_changes();
    events();
    if (session.topology_changes() != changes) {
      const auto t0 = Clock::now();
      session.surface();  // rebuilt after the cut
      phase.surface_ms.push_back(ms_since(t0));
      const auto t1 = Clock::now();
      const tetcut::live::TopologyEncoder::Messages messages = topology();
      phase.topology_ms.push_back(ms_since(t1));
      topology_bytes = messages.full.size();
      phase.change_bytes.push_back(static_cast<double>(messages.change.size()));
      phase.latency_ms.push_back(ms_since(start));
    }
    const auto s0 = Clock::now();
    const tetcut::SessionStep step = session.advance();
    phase.step_ms.push_back(ms_since(s0));
    if (step.topology_changed && session.topology_changes() == changes) topology_bytes = topology().full.size();
    frame_bytes = tetcut::live::encode_frame(version, static_cast<std::uint32_t>(session.steps()), session.time(),
                                             session.simulator().positions(), pieces)
                      .size();
    phase.tick_ms.push_back(ms_since(start));
    if (per_tick) {
      const ContactState c = session.simulator().surface_contact();
      const auto ms = [](double after, double before) { return 1e3 * (after - before); };
      std::printf("  %-8s %4zu %7.1f %6d %6d %9.3g %7d %10.1f %6lld %10lld %6lld %8lld %8.1f %7.1f %7.1f %7.1f %7.1f\n", phase.name.c_str(),
                  phase.tick_ms.size(), phase.tick_ms.back(), step.report.newton_iterations, step.report.rescue_iterations,
                  step.report.residual, step.report.contact_limited_steps, 1e3 * step.report.contact_seconds,
                  static_cast<long long>(step.report.contact_pairs), static_cast<long long>(c.candidates), static_cast<long long>(c.guards),
                  static_cast<long long>(c.rebuilds - contact_before.rebuilds), ms(c.rebuild_seconds, contact_before.rebuild_seconds),
                  ms(c.ccd_seconds, contact_before.ccd_seconds), ms(c.active_seconds, contact_before.active_seconds),
                  ms(c.guard_seconds, contact_before.guard_seconds), ms(c.join_seconds, contact_before.join_seconds));
      contact_before = c;
    }
    phase.max_residual = std::max(phase.max_residual, step.report.residual);
    phase.rescues += step.report.rescue_iterations;
  };
  const auto nothing = [] {};

  phases.emplace_back("idle");
  for (int i = 0; i < 30; ++i) tick(phases.back(), nothing);

  phases.emplace_back("scalpel");
  const double z = low.z() + 2.0 / 3.0 * height;
  for (int i = 0; i <= 45; ++i) {
    const double x = low.x() - 0.1 + (high.x() - low.x() + 0.2) * i / 45.0;
    tick(phases.back(), [&] { session.blade({Vec3(x, centre.y() - 0.6, z), Vec3(x, centre.y() + 0.6, z)}); });
  }
  session.lift_blade();
  const Index pieces_after_cut = pieces.count;

  phases.emplace_back("falling");
  for (int i = 0; i < 60; ++i) tick(phases.back(), nothing);

  phases.emplace_back("hook");
  // On the surface, as the page grabs (where the pointer's ray meets it): the surface vertex
  // nearest a point beside the stump. The hook's target starts there and moves from there (a
  // target set at the point beside it, 7.75 cm off the surface, yanked the stump that far in one
  // step).
  const Vec3 beside(centre.x(), high.y(), low.z() + 0.45 * height);
  Vec3 grab_at = beside;
  {
    const tetcut::Points on_surface = session.surface_positions();
    tetcut::Index nearest = 0;
    (on_surface.rowwise() - beside.transpose()).rowwise().squaredNorm().minCoeff(&nearest);
    grab_at = on_surface.row(nearest).transpose();
  }
  int hook = -1;
  tick(phases.back(), [&] { hook = session.grab(grab_at); });
  for (int i = 1; i <= 30; ++i) tick(phases.back(), [&] { session.move_hook(hook, grab_at + Vec3(0.005 * i, 0.002 * i, 0)); });
  for (int i = 0; i < 15; ++i) tick(phases.back(), nothing);
  tick(phases.back(), [&] { session.release(hook); });
  for (int i = 0; i < 30; ++i) tick(phases.back(), nothing);

  std::printf("  after the scalpel: %lld pieces, %lld tets; the whole topology %.2f MB, a cut's change %.1f KB median (max %.1f KB), "
              "frame %.1f KB\n\n",
              static_cast<long long>(pieces_after_cut), static_cast<long long>(session.simulator().num_tets()),
              static_cast<double>(topology_bytes) / 1e6, percentile(phases[1].change_bytes, 0.5) / 1e3,
              percentile(phases[1].change_bytes, 1.0) / 1e3, static_cast<double>(frame_bytes) / 1e3);
  std::printf("  %-8s %5s %22s %8s %22s %24s %9s %7s\n", "phase", "ticks", "tick ms median / p99", "ticks/s", "step ms median / p99",
              "pose to topology ms med/p99", "residual", "rescue");
  std::vector<double> all;
  for (const Phase& p : phases) {
    all.insert(all.end(), p.tick_ms.begin(), p.tick_ms.end());
    double mean = 0;
    for (const double t : p.tick_ms) mean += t;
    mean /= static_cast<double>(p.tick_ms.size());
    char latency[64] = "-";
    if (!p.latency_ms.empty()) std::snprintf(latency, sizeof latency, "%.1f / %.1f", percentile(p.latency_ms, 0.5), percentile(p.latency_ms, 0.99));
    std::printf("  %-8s %5zu %12.1f / %6.1f %8.0f %12.1f / %6.1f %24s %9.3g %7d\n", p.name.c_str(), p.tick_ms.size(), percentile(p.tick_ms, 0.5),
                percentile(p.tick_ms, 0.99), 1000 / mean, percentile(p.step_ms, 0.5), percentile(p.step_ms, 0.99), latency, p.max_residual,
                p.rescues);
  }
  double mean = 0;
  for (const double t : all) mean += t;
  mean /= static_cast<double>(all.size());
  std::printf("  %-8s %5zu %12.1f / %6.1f %8.0f\n", "all", all.size(), percentile(all, 0.5), percentile(all, 0.99), 1000 / mean);
  const Phase& cut = phases[1];
  std::printf("\n  after each cut: the material surface rebuilt in %.1f ms (median; p99 %.1f), the topology messages (whole and change) encoded in %.1f ms\n",
              percentile(cut.surface_ms, 0.5), percentile(cut.surface_ms, 0.99), percentile(cut.topology_ms, 0.5));
  std::printf("  (ticks/s: 1000 over the mean tick, the rate the server could hold; it paces itself to 1/dt)\n");
  return 0;
}
