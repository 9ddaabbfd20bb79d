// The paper's Figure 10 size: a surface of at least 250k triangles embedded in a BCC lattice of
// about 850k tets. The surface is a real scan (bunny00, 75k triangles, from Debian's
// libcgal-demo) refined once by Loop subdivision (301k triangles: smooth, so no two sub-triangles
// are coplanar, as in a finer scan). Prints the time of each stage and the peak memory.
//
//   tetcut_bench_embed_scale [SURFACE.off] [TARGET_TETS]   (defaults: bunny00, 850000)

#include <tetcut/embed.hpp>
#include <tetcut/io.hpp>

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>
#include <vector>

namespace {

using tetcut::Index;
using tetcut::TriangleSurface;
using tetcut::Vec3;

// One step of Loop subdivision of a closed surface (boundary edges use their midpoints).
TriangleSurface loop_subdivide(const TriangleSurface& in) {
  const Index nv = in.num_vertices();
  std::vector<std::vector<Index>> neighbours(static_cast<std::size_t>(nv));
  std::map<std::pair<Index, Index>, std::vector<Index>> opposite;  // edge -> opposite corners
  for (Index t = 0; t < in.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Index a = in.triangles(t, k), b = in.triangles(t, (k + 1) % 3), c = in.triangles(t, (k + 2) % 3);
      opposite[std::minmax(a, b)].push_back(c);
      neighbours[a].push_back(b);
    }
  }
  std::vector<Vec3> out;
  for (Index v = 0; v < nv; ++v) {
    const double n = static_cast<double>(neighbours[v].size());
    const double beta = (5.0 / 8 - std::pow(3.0 / 8 + std::cos(2 * std::numbers::pi / n) / 4, 2)) / n;
    Vec3 sum = Vec3::Zero();
    for (const Index u : neighbours[v]) sum += in.vertices.row(u).transpose();
    out.push_back((1 - n * beta) * in.vertices.row(v).transpose() + beta * sum);
  }
  std::map<std::pair<Index, Index>, Index> middle;
  for (const auto& [edge, corners] : opposite) {
    const Vec3 a = in.vertices.row(edge.first).transpose(), b = in.vertices.row(edge.second).transpose();
    middle[edge] = static_cast<Index>(out.size());
    if (corners.size() == 2) {
      out.push_back(3.0 / 8 * (a + b) + 1.0 / 8 * (in.vertices.row(corners[0]).transpose() + in.vertices.row(corners[1]).transpose()));
    } else {
      out.push_back((a + b) / 2);
    }
  }
  TriangleSurface s;
  s.vertices.resize(static_cast<Index>(out.size()), 3);
  for (std::size_t i = 0; i < out.size(); ++i) s.vertices.row(static_cast<Index>(i)) = out[i].transpose();
  s.triangles.resize(4 * in.num_triangles(), 3);
  for (Index t = 0; t < in.num_triangles(); ++t) {
    const Index a = in.triangles(t, 0), b = in.triangles(t, 1), c = in.triangles(t, 2);
    const Index ab = middle[std::minmax(a, b)], bc = middle[std::minmax(b, c)], ca = middle[std::minmax(c, a)];
    s.triangles.row(4 * t) << a, ab, ca;
    s.triangles.row(4 * t + 1) << ab, b, bc;
    s.triangles.row(4 * t + 2) << ca, bc, c;
    s.triangles.row(4 * t + 3) << ab, bc, ca;
  }
  return s;
}

double peak_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024;
}

}  // namespace

int main(int argc, char** argv) {
  using Clock = std::chrono::steady_clock;
  const auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  const std::string path = argc > 1 ? argv[1] : std::string(TETCUT_REAL_DATA) + "/bunny00.off";
  const double target = argc > 2 ? std::stod(argv[2]) : 850000;
  TriangleSurface surface = tetcut::read_surface(path);
  while (surface.num_triangles() < 250000) surface = loop_subdivide(surface);
  // Tets grow as spacing^-3 (plus the margin): two corrections from a coarse lattice land close.
  double spacing = tetcut::spacing_for_cubes(surface, 16);
  for (int step = 0; step < 3; ++step) {
    spacing *= std::cbrt(tetcut::embedding_lattice(surface, spacing).num_tets() / target);
  }

  auto start = Clock::now();
  tetcut::TetMesh lattice = tetcut::embedding_lattice(surface, spacing);
  const double lattice_seconds = since(start);
  const Index lattice_tets = lattice.num_tets();
  tetcut::EmbedReport report;
  start = Clock::now();
  tetcut::Cutter cutter = tetcut::embed(std::move(lattice), surface, {}, &report);
  const double embed_seconds = since(start);
  start = Clock::now();
  const tetcut::CutResult result = cutter.result();
  const double result_seconds = since(start);

  std::printf("surface     %s, Loop-subdivided to %d triangles\n", path.c_str(), static_cast<int>(surface.num_triangles()));
  std::printf("lattice     spacing %.5g, %d tets (%.3f s)\n", spacing, static_cast<int>(lattice_tets), lattice_seconds);
  std::printf("embed       check %.3f s, insert %.3f s, classify %.3f s, copies %.3f s (total %.3f s)\n",
              report.seconds_check, report.seconds_insert, report.seconds_classify, report.seconds_copies, embed_seconds);
  std::printf("result      pieces %.3f s, surface %.3f s\n", result.seconds_mesh, result.seconds_surface);
  std::printf("output      %d tets with material (%d duplicated), %d copies, %d nodes, %d surface triangles\n",
              static_cast<int>(report.tets_with_material), static_cast<int>(report.tets_duplicated),
              static_cast<int>(result.mesh.mesh.num_tets()), static_cast<int>(result.mesh.mesh.num_nodes()),
              static_cast<int>(result.surface.surface.num_triangles()));
  std::printf("total       %.3f s (lattice + embed + result), peak memory %.0f MiB\n",
              lattice_seconds + embed_seconds + result_seconds, peak_mib());
  return 0;
}
