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

#include "collision/proximity.hpp"
#include "collision/twins.hpp"
#include "geometry/predicates.hpp"
#include "spatial/box_tree.hpp"

namespace tetcut {
namespace {

// How far triangle `a` reaches behind triangle `b`, both oriented outward (the material is behind
// each): the largest distance behind b's plane of the part of `a` that lies over b (a clipped to
// the prism over b). 0 where b is flat or no part of `a` lies over it. Floating point: a depth.
double reach_behind(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
  const Vec3 n = (b[1] - b[0]).cross(b[2] - b[0]);
  const double length = n.norm();
  if (!(length > 0)) return 0;
  const Vec3 unit = n / length;
  // Clip by the prism's three sides (each through an edge of b, along its normal, facing in).
  std::vector<Vec3> polygon(a.begin(), a.end()), clipped;
  for (int e = 0; e < 3 && !polygon.empty(); ++e) {
    const Vec3 p = b[e], inward = unit.cross(b[(e + 1) % 3] - p);
    clipped.clear();
    for (std::size_t i = 0; i < polygon.size(); ++i) {
      const Vec3& u = polygon[i];
      const Vec3& w = polygon[(i + 1) % polygon.size()];
      const double su = inward.dot(u - p), sw = inward.dot(w - p);
      if (su >= 0) clipped.push_back(u);
      if ((su < 0) != (sw < 0)) clipped.push_back(u + (w - u) * (su / (su - sw)));
    }
    polygon.swap(clipped);
  }
  double deepest = 0;
  for (const Vec3& p : polygon) deepest = std::max(deepest, -unit.dot(p - b[0]));
  return deepest;
}

// How far from their rims two triangles cross: the largest distance from either triangle's rim of
// a point of the segment where they cross. Two sides of a cut pressed together by d where a third
// face meets them (a stick's top face and its neighbour's side, which touch along a rim in the
// material) cross in a strip about d wide along both rims, while either reaches a whole triangle
// behind the other (reach_behind measures the part over the other, not the overlap): this is
// about d there; one passing through the other, or a rim pushed over a face well inside it, is
// the size of the overlap. Inside a convex polygon the distance to its rim is the least distance
// to its sides' lines: along the segment, per triangle, the least of three affine functions,
// concave, so its largest value is at an end or where two of them meet. Infinity where the
// triangles are too near coplanar for a segment (an angle below 1e-3: reach_behind decides those),
// 0 where they do not cross. Floating point: a depth.
double crossing_depth(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
  const Vec3 na = (a[1] - a[0]).cross(a[2] - a[0]), nb = (b[1] - b[0]).cross(b[2] - b[0]);
  constexpr double kCoplanar = 1e-3;
  if (!(na.cross(nb).norm() > kCoplanar * na.norm() * nb.norm())) return std::numeric_limits<double>::infinity();
  const Vec3 ub = nb.normalized();
  // Where a meets b's plane: the ends of the segment, from a's edges whose ends lie on either side.
  std::array<double, 3> side{};
  for (int k = 0; k < 3; ++k) side[k] = ub.dot(a[k] - b[0]);
  std::array<Vec3, 3> ends;
  int count = 0;
  for (int k = 0; k < 3; ++k) {
    const double s0 = side[k], s1 = side[(k + 1) % 3];
    if (s0 == 0) ends[count++] = a[k];
    if ((s0 < 0 && s1 > 0) || (s0 > 0 && s1 < 0)) ends[count++] = a[k] + (a[(k + 1) % 3] - a[k]) * (s0 / (s0 - s1));
  }
  if (count < 2) return 0;  // at most a corner on b's plane
  const Vec3 p = ends[0], q = ends[1];
  // The rims' lines as inward unit normals in each triangle's plane: distance = m . (x - corner).
  std::array<Vec3, 6> inward;
  std::array<Vec3, 6> on;
  const Vec3 ua = na.normalized();
  for (int e = 0; e < 3; ++e) {
    inward[e] = ua.cross(a[(e + 1) % 3] - a[e]).normalized();
    on[e] = a[e];
    inward[3 + e] = ub.cross(b[(e + 1) % 3] - b[e]).normalized();
    on[3 + e] = b[e];
  }
  // f_i(s) = c_i + s g_i along x(s) = p + s (q - p) (a's sides, then b's); the part of [0, 1]
  // inside b (f_3..5 >= 0; the segment is a's already).
  std::array<double, 6> c{}, g{};
  double lo = 0, hi = 1;
  for (int i = 0; i < 6; ++i) {
    c[i] = inward[i].dot(p - on[i]);
    g[i] = inward[i].dot(q - p);
    if (i < 3) continue;
    if (g[i] == 0) {
      if (c[i] < 0) return 0;
    } else if (g[i] > 0) {
      lo = std::max(lo, -c[i] / g[i]);
    } else {
      hi = std::min(hi, -c[i] / g[i]);
    }
  }
  if (!(lo <= hi)) return 0;
  double deepest = 0;
  for (const int first : {0, 3}) {
    const auto inside_by = [&](double s) {
      double d = std::numeric_limits<double>::infinity();
      for (int i = first; i < first + 3; ++i) d = std::min(d, c[i] + s * g[i]);
      return d;
    };
    deepest = std::max({deepest, inside_by(lo), inside_by(hi)});
    for (int i = first; i < first + 3; ++i) {
      for (int j = i + 1; j < first + 3; ++j) {
        if (g[i] == g[j]) continue;
        const double s = (c[j] - c[i]) / (g[i] - g[j]);
        if (s > lo && s < hi) deepest = std::max(deepest, inside_by(s));
      }
    }
  }
  return deepest;
}

// The distance between two triangles where they do not intersect: the least of each corner's
// distance to the other triangle and each pair of edges' distance. Floating point.
double triangle_distance(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
  double d = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    d = std::min(d, collision::point_triangle(a[k], b[0], b[1], b[2]).distance);
    d = std::min(d, collision::point_triangle(b[k], a[0], a[1], a[2]).distance);
    for (int l = 0; l < 3; ++l) d = std::min(d, collision::segment_segment(a[k], a[(k + 1) % 3], b[l], b[(l + 1) % 3]).distance);
  }
  return d;
}

// Whether triangles a and b lie in one plane, every corner of each within `tolerance` of the
// other's plane, with opposite orientations (the two sides of a cut). Floating point.
bool facing_in_one_plane(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b, double tolerance) {
  const Vec3 na = (a[1] - a[0]).cross(a[2] - a[0]), nb = (b[1] - b[0]).cross(b[2] - b[0]);
  if (!(na.norm() > 0 && nb.norm() > 0) || !(na.dot(nb) < 0)) return false;
  const Vec3 ua = na.normalized(), ub = nb.normalized();
  for (int k = 0; k < 3; ++k) {
    if (!(std::abs(ua.dot(b[k] - a[0])) <= tolerance) || !(std::abs(ub.dot(a[k] - b[0])) <= tolerance)) return false;
  }
  return true;
}

}  // namespace

SurfaceIntersections count_surface_intersections(const MaterialSurface& surface, std::span<const std::array<Index, 4>> copy_nodes,
                                                 const Points& positions, double opened, double slid) {
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
  // Placing a vertex is 4 products and 3 sums of node coordinates: its rounding is a few ulps
  // of the largest coordinate; 64 of them is far below any motion that could open a cut.
  const double scale = positions.size() > 0 ? positions.cwiseAbs().maxCoeff() : 0.0;
  const double rest_scale = s.vertices.size() > 0 ? s.vertices.cwiseAbs().maxCoeff() : 0.0;
  const double rounding = 64 * std::numeric_limits<double>::epsilon();
  // Two rest points closer than this are one material point, rounded differently by two copies.
  const double rest_twin = std::max(rounding * rest_scale, std::numeric_limits<double>::min());
  const std::vector<Index> weld = collision::twin_ids(s.vertices, positions, rest_twin, std::max(opened, rounding * scale));
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
  // Two sides of a cut pressed into each other, less than `opened` deep: triangles that touch in
  // the material (decided exactly, or apart by no more than the rounding of rest points) and now
  // cross no deeper than that (either reaches at most `opened` behind the other, or, where they
  // are not coplanar, they cross within `opened` of both rims: crossing_depth). Pressed
  // together, the sides of a cut slide along each other (each bulges as it is squeezed), so
  // their twin points part while the cut stays closed.
  const auto pressed_cut = [&](Index a, Index b, const std::array<Vec3, 3>& ca, const std::array<Vec3, 3>& cb) {
    const auto rest = [&](Index t) {
      return std::array<Vec3, 3>{s.vertices.row(s.triangles(t, 0)).transpose(), s.vertices.row(s.triangles(t, 1)).transpose(),
                                 s.vertices.row(s.triangles(t, 2)).transpose()};
    };
    if (!(std::min(reach_behind(ca, cb), reach_behind(cb, ca)) <= opened) && !(crossing_depth(ca, cb) <= opened)) return false;
    const auto ra = rest(a), rb = rest(b);
    if (!geometry::collinear(ra[0], ra[1], ra[2]) && !geometry::collinear(rb[0], rb[1], rb[2]) && triangles_intersect(ra, rb)) return true;
    // Copies may round one exact point differently (a junction of two cuts is placed from each
    // side's planes): triangles meeting there can miss each other by an ulp. And triangles
    // apart by no more than `opened` there touch as far as surface contact can tell: it leaves
    // such pairs of joined copies out of its barrier, as touching in the material (within its
    // guards' allowance), so they may come that close to crossing. Where a cut's rim meets the
    // outer surface, the two sides' fans over their polygons put corners a little apart on the
    // rim (a wall's triangle and the neighbouring top face's 2e-4 apart in the folded flap).
    const double touching = std::max(rounding * rest_scale, opened);
    // Farther apart there, within `slid`: the sides of a cut pressed together that have slid along
    // each other, which contact's guards hold to the allowance as they hold touching ones (the
    // slinky's upper lip of a slit pressed 3e-5 into the lower lip's rim, 0.0017 along the cut from
    // it in the material).
    if (triangle_distance(ra, rb) <= std::max(touching, slid)) return true;
    // Or they lay in one plane there, facing each other: the two sides of one flat part of a cut,
    // apart along it. Pressed together, the sides slide along each other, and where one side's fan
    // puts a corner a little beside the other side's triangle they graze as sides that touched do
    // (the folded flap's floor: triangles 0.0016 apart along the cut crossing by 1.2e-6, when
    // contact, which leaves such pairs out as lying across one cut, allows a fifth of its thickness).
    return facing_in_one_plane(ra, rb, touching);
  };
  std::vector<spatial::Aabb> boxes(static_cast<std::size_t>(F));
  std::vector<std::uint8_t> degenerate(static_cast<std::size_t>(F), 0);
  const auto corners = [&](Index t) {
    return std::array<Vec3, 3>{positions.row(s.triangles(t, 0)).transpose(), positions.row(s.triangles(t, 1)).transpose(),
                               positions.row(s.triangles(t, 2)).transpose()};
  };
  // Not tested: triangles flat where they are now, and those flat in the material, which bound no
  // material. Among these, two corners at one material point embedded twice, in copies that share
  // the nodes it hangs on, with weights an ulp apart (barycentric coordinates from each copy's
  // tet): placed by those weights, the sliver opens into a needle an ulp wide, which crossed the
  // neighbour sharing that corner (Figure 4's one crossing pair over its first 0.35 s). The two
  // embeddings of that point may differ by the rounding of rest points too (each copy places it):
  // a needle in the material as well, whose plane, and so its crossing's depth, is rounding; its
  // long sides are its neighbours', which are tested (Figure 4's one crossing pair at 0.9 and
  // 1.3 s: a needle measured 1.1e-3 from the rims, its side crossing 2.6e-4 from them).
  const auto twins = [&](const Vec3& p, const Vec3& q) { return (p - q).cwiseAbs().maxCoeff() <= rest_twin; };
  tbb::parallel_for(tbb::blocked_range<Index>(0, F, 1024), [&](const auto& range) {
    for (Index t = range.begin(); t != range.end(); ++t) {
      const auto c = corners(t);
      for (const Vec3& p : c) boxes[static_cast<std::size_t>(t)].extend(p);
      const Vec3 r0 = s.vertices.row(s.triangles(t, 0)).transpose(), r1 = s.vertices.row(s.triangles(t, 1)).transpose(),
                 r2 = s.vertices.row(s.triangles(t, 2)).transpose();
      const bool flat_in_material = geometry::collinear(r0, r1, r2) || twins(r0, r1) || twins(r1, r2) || twins(r2, r0);
      degenerate[static_cast<std::size_t>(t)] = geometry::collinear(c[0], c[1], c[2]) || flat_in_material ? 1 : 0;
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
        bool shared = closed_cut(a, b);
        for (int i = 0; i < 3 && !shared; ++i) {
          for (int j = 0; j < 3 && !shared; ++j) shared = weld[static_cast<std::size_t>(s.triangles(a, i))] == weld[static_cast<std::size_t>(s.triangles(b, j))];
        }
        if (shared) continue;
        const auto cb = corners(b);
        if (!triangles_intersect(ca, cb) || pressed_cut(a, b, ca, cb)) continue;
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
