// Counting where the material surface passes through itself (see collision.hpp): boxes of the
// triangles at their current positions in a hierarchy, each triangle's candidates found in
// parallel, and each candidate pair of different copies decided by the exact test.

#include <tetcut/collision.hpp>
#include <tetcut/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "collision/twins.hpp"
#include "geometry/predicates.hpp"
#include "spatial/box_tree.hpp"

namespace tetcut {
namespace {

}  // namespace

SurfaceIntersections count_surface_intersections(const MaterialSurface& surface, std::span<const std::array<Index, 4>> copy_nodes,
                                                 const Points& positions, double opened) {
  const TriangleSurface& s = surface.surface;
  if (positions.rows() != s.num_vertices()) {
    throw Error(ErrorKind::kInvalidArgument, "surface positions: " + std::to_string(positions.rows()) + " rows for " +
                                                 std::to_string(s.num_vertices()) + " surface vertices");
  }
  const Index F = s.num_triangles();
  for (const Index copy : surface.triangle_tet) {
    if (copy < 0 || static_cast<std::size_t>(copy) >= copy_nodes.size()) {
      throw Error(ErrorKind::kInvalidArgument, "the surface names tet copy " + std::to_string(copy) + " of " + std::to_string(copy_nodes.size()));
    }
  }
  const auto neighbours = [&](Index a, Index b) {
    const auto& p = copy_nodes[static_cast<std::size_t>(surface.triangle_tet[static_cast<std::size_t>(a)])];
    const auto& q = copy_nodes[static_cast<std::size_t>(surface.triangle_tet[static_cast<std::size_t>(b)])];
    for (const Index n : p) {
      if (std::find(q.begin(), q.end(), n) != q.end()) return true;
    }
    return false;
  };
  // Placing a vertex is 4 products and 3 sums of node coordinates: its rounding is a few ulps
  // of the largest coordinate; 64 of them is far below any motion that could open a cut.
  const double scale = positions.size() > 0 ? positions.cwiseAbs().maxCoeff() : 0.0;
  const double rest_scale = s.vertices.size() > 0 ? s.vertices.cwiseAbs().maxCoeff() : 0.0;
  const double rounding = 64 * std::numeric_limits<double>::epsilon();
  const std::vector<Index> weld =
      collision::twin_ids(s.vertices, positions, std::max(rounding * rest_scale, std::numeric_limits<double>::min()), std::max(opened, rounding * scale));
  // Per vertex: still one point with another (unopened).
  std::vector<std::uint8_t> unopened(weld.size(), 0);
  for (std::size_t v = 0; v < weld.size(); ++v) {
    if (weld[v] != static_cast<Index>(v)) unopened[v] = unopened[static_cast<std::size_t>(weld[v])] = 1;
  }
  // The two sides of one cut triangle where it has not opened: their triangulations of the same
  // polygon overlap, and need not share a corner.
  const auto closed_cut = [&](Index a, Index b) {
    const std::int64_t source = surface.triangle_source[static_cast<std::size_t>(a)];
    if (source < 0 || source != surface.triangle_source[static_cast<std::size_t>(b)]) return false;
    for (int k = 0; k < 3; ++k) {
      if (!unopened[static_cast<std::size_t>(s.triangles(a, k))] || !unopened[static_cast<std::size_t>(s.triangles(b, k))]) return false;
    }
    return true;
  };
  std::vector<spatial::Aabb> boxes(static_cast<std::size_t>(F));
  std::vector<std::uint8_t> degenerate(static_cast<std::size_t>(F), 0);
  const auto corners = [&](Index t) {
    return std::array<Vec3, 3>{positions.row(s.triangles(t, 0)).transpose(), positions.row(s.triangles(t, 1)).transpose(),
                               positions.row(s.triangles(t, 2)).transpose()};
  };
  tbb::parallel_for(tbb::blocked_range<Index>(0, F, 1024), [&](const auto& range) {
    for (Index t = range.begin(); t != range.end(); ++t) {
      const auto c = corners(t);
      for (const Vec3& p : c) boxes[static_cast<std::size_t>(t)].extend(p);
      degenerate[static_cast<std::size_t>(t)] = geometry::collinear(c[0], c[1], c[2]) ? 1 : 0;
    }
  });
  const spatial::BoxTree tree(boxes);

  struct Counts {
    Index intersecting = 0, candidates = 0;
    std::vector<std::array<Index, 2>> examples;
    std::vector<Index> found;
  };
  tbb::combinable<Counts> counts;
  tbb::parallel_for(tbb::blocked_range<Index>(0, F, 256), [&](const auto& range) {
    Counts& mine = counts.local();
    for (Index a = range.begin(); a != range.end(); ++a) {
      if (degenerate[static_cast<std::size_t>(a)]) continue;
      mine.found.clear();
      tree.query(boxes[static_cast<std::size_t>(a)], &mine.found);
      const auto ca = corners(a);
      for (const Index b : mine.found) {
        if (b <= a || degenerate[static_cast<std::size_t>(b)]) continue;
        if (surface.triangle_tet[static_cast<std::size_t>(a)] == surface.triangle_tet[static_cast<std::size_t>(b)]) continue;
        ++mine.candidates;
        bool shared = neighbours(a, b) || closed_cut(a, b);
        for (int i = 0; i < 3 && !shared; ++i) {
          for (int j = 0; j < 3 && !shared; ++j) shared = weld[static_cast<std::size_t>(s.triangles(a, i))] == weld[static_cast<std::size_t>(s.triangles(b, j))];
        }
        if (shared || !triangles_intersect(ca, corners(b))) continue;
        ++mine.intersecting;
        mine.examples.push_back({a, b});
      }
    }
  });
  SurfaceIntersections out;
  for (const std::uint8_t d : degenerate) out.degenerate_triangles += d;
  counts.combine_each([&](const Counts& c) {
    out.intersecting_pairs += c.intersecting;
    out.candidate_pairs += c.candidates;
    out.examples.insert(out.examples.end(), c.examples.begin(), c.examples.end());
  });
  std::sort(out.examples.begin(), out.examples.end());
  if (out.examples.size() > 16) out.examples.resize(16);
  return out;
}

}  // namespace tetcut
