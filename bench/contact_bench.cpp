// What surface contact (self_collision) adds to a step: the same scene run twice through the
// live session, without and with contact of the material surface, printing the median and 99th
// percentile of consecutive steps' wall times, the surface's size, the contact pairs and the
// time in continuous collision detection. Default: examples/live-femur.json (the CT femur from
// libcgal-demo embedded in an 11k-tet lattice, hanging under gravity, the real-time solver).
//
// Usage: tetcut_bench_contact [SCENE] [STEPS]

#include <tetcut/scene.hpp>
#include <tetcut/session.hpp>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "step_times.hpp"

int main(int argc, char** argv) {
  using namespace tetcut;
  const std::string path = argc > 1 ? argv[1] : TETCUT_EXAMPLES "/live-femur.json";
  const int steps = argc > 2 ? std::atoi(argv[2]) : 60;
  Scene scene = load_scene(path);
  std::printf("scene %s, %d steps from rest\n", path.c_str(), steps);
  std::printf("%-16s %8s %8s %10s %10s %12s %10s %10s %12s %10s\n", "self_collision", "tets", "surface", "median ms", "p99 ms",
              "contact pairs", "ccd ms", "rebuilds", "copy pairs", "candidates");
  for (const bool on : {false, true}) {
    scene.self_collision = on;
    Session session(scene);
    std::vector<double> ms;
    Index pairs = 0;
    double ccd = 0;
    for (int s = 0; s < steps; ++s) {
      const bench::Clock::time_point start = bench::Clock::now();
      const SessionStep step = session.advance();
      ms.push_back(bench::ms_since(start));
      pairs = std::max(pairs, step.report.contact_pairs);
      ccd += 1e3 * step.report.contact_seconds;
    }
    const sim::Simulator::SurfaceContactState contact = session.simulator().surface_contact();
    std::printf("%-16s %8d %8d %10.2f %10.2f %12d %10.2f %10d %12d %10d\n", on ? "on" : "off", session.simulator().num_tets(),
                session.surface().surface.num_triangles(), bench::median(ms), bench::percentile(ms, 0.99), pairs, ccd / steps,
                contact.rebuilds, contact.copy_pair_rebuilds, contact.candidates);
  }
}
