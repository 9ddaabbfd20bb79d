// The planar cutter in world space (PlanarCutter::cut_deformed): cuts placed on the deformed cloth,
// pulled back per copy. Exact answers where the deformation makes them known (an affine map, a
// fold along a grid line, pieces moved apart), and random blades on a crumpled cloth checked for
// the invariants and for independence of order and batching.

#include <tetcut/blade.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/planar_cutter.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <random>
#include <vector>

#include "support/planar_invariants.hpp"

namespace tetcut {
namespace {

using testing::expect_planar_invariants;
using testing::polyline;
using testing::sorted_areas;

// The cutter's nodes placed by a map of their rest positions.
Points place(const PlanarCutter& cutter, const std::function<Vec3(double, double)>& map) {
  Points x(cutter.num_nodes(), 3);
  for (Index n = 0; n < cutter.num_nodes(); ++n) {
    const Index parent = cutter.node_parent()[n];
    x.row(n) = map(cutter.input().rest(parent, 0), cutter.input().rest(parent, 1)).transpose();
  }
  return x;
}

// Positions after a batch: new nodes start where the nodes they were split from are.
Points carried_over(const Points& before, const PlanarCutReport& report) {
  Points x(before.rows() + static_cast<Index>(report.new_node_source.size()), 3);
  x.topRows(before.rows()) = before;
  for (std::size_t i = 0; i < report.new_node_source.size(); ++i) {
    x.row(report.first_new_node + static_cast<Index>(i)) = before.row(report.new_node_source[i]);
  }
  return x;
}

TriangleSurface soup(const std::vector<std::array<Vec3, 3>>& triangles) {
  TriangleSurface s;
  s.vertices.resize(3 * static_cast<Index>(triangles.size()), 3);
  s.triangles.resize(static_cast<Index>(triangles.size()), 3);
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      s.vertices.row(3 * static_cast<Index>(i) + k) = triangles[i][k].transpose();
      s.triangles(static_cast<Index>(i), k) = 3 * static_cast<Index>(i) + k;
    }
  }
  return s;
}

// Two cuts agree: pieces and their areas, copies, nodes. Made in the same order, also their cells
// and the material's boundary (a segment ending inside a cell splits it along its whole chord, so
// cells depend on the order).
void expect_same_cut(const PlanarCutter& a, const PlanarCutter& b, bool same_order) {
  const PlanarCutResult ra = a.result(), rb = b.result();
  ASSERT_EQ(ra.mesh.num_pieces(), rb.mesh.num_pieces());
  const std::vector<double> x = sorted_areas(ra), y = sorted_areas(rb);
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(x[i], y[i], 1e-12) << "piece " << i;
  EXPECT_EQ(a.num_triangles(), b.num_triangles());
  EXPECT_EQ(a.num_nodes(), b.num_nodes());
  if (!same_order) return;
  EXPECT_EQ(a.num_cells(), b.num_cells());
  EXPECT_EQ(ra.material.num_vertices(), rb.material.num_vertices());
  EXPECT_EQ(ra.material.num_segments(), rb.material.num_segments());
}

// An affine placement of the plane in space, x = M (u, v) + t, with dyadic entries so that every
// image of a dyadic point is exact.
struct Affine {
  Eigen::Matrix<double, 3, 2> m;
  Vec3 t;
  Vec3 operator()(double u, double v) const { return m * Eigen::Vector2d(u, v) + t; }
  Vec3 normal() const { return m.col(0).cross(m.col(1)); }
};

Affine skewed() {
  Affine a;
  a.m << 1, 0.5, 0.25, 1, 0.5, -0.75;
  a.t = Vec3(0.5, -0.25, 2);
  return a;
}

// A world triangle meeting the placed plane exactly in the image of rest segment (p, q): its apex
// above the segment's middle, its other corners as far below the plane beyond p and q, so that
// its two edges from the apex cross the plane at p and q.
std::array<Vec3, 3> blade_through(const Affine& phi, const std::array<double, 2>& p, const std::array<double, 2>& q) {
  const Vec3 apex = phi(0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])) + phi.normal();
  return {apex, 2 * phi(p[0], p[1]) - apex, 2 * phi(q[0], q[1]) - apex};
}

TEST(PlanarDeformedCut, AffinelyPlacedClothCutInWorldEqualsTheRestCut) {
  // Straight across triangles, a T ending on it, through vertices, along edges ending at an
  // edge's middle, and a slit ending inside triangles: in rest space, and the same segments
  // drawn on the cloth placed affinely in space.
  const std::vector<std::array<std::array<double, 2>, 2>> segments = {
      {{{-0.25, 0.4375}, {1.25, 0.4375}}}, {{{0.3125, 0.4375}, {0.3125, 1.25}}},  {{{-0.25, 1.25}, {1.25, -0.25}}},
      {{{0.5, -0.25}, {0.5, 0.375}}},      {{{0.875, 0.8125}, {0.5625, 0.6875}}}};
  const PlanarMesh mesh = make_planar_grid(4);
  const Affine phi = skewed();
  PlanarCutter rest(mesh), world(mesh);
  std::vector<Polyline> lines;
  std::vector<std::array<Vec3, 3>> blades;
  for (const auto& [p, q] : segments) {
    lines.push_back(polyline({p, q}));
    blades.push_back(blade_through(phi, p, q));
  }
  rest.cut(lines);
  const PlanarCutReport report = world.cut_deformed(soup(blades), place(world, [&](double u, double v) { return phi(u, v); }));
  EXPECT_EQ(report.segments, 5);
  EXPECT_TRUE(report.degenerate.empty());
  EXPECT_TRUE(report.skipped_coplanar.empty());
  EXPECT_EQ(report.first_new_node, 25);
  EXPECT_EQ(static_cast<Index>(report.new_node_source.size()), world.num_nodes() - 25);
  expect_same_cut(rest, world, true);
  expect_planar_invariants(mesh, world.result());
  // The cross and the diagonal make four regions; the T, from the cross to the top edge, splits
  // both upper ones; the cut along edges and the slit separate nothing.
  EXPECT_EQ(world.result().mesh.num_pieces(), 6);
}

TEST(PlanarDeformedCut, ACutOfACutInWorldSpace) {
  // The first cut in rest space, the second on the cloth placed in space, and a blade whose edge
  // lies on the cloth (it meets it along that edge): as both in rest space.
  const PlanarMesh mesh = make_planar_grid(4);
  const Affine phi = skewed();
  PlanarCutter rest(mesh), world(mesh);
  const std::vector<Polyline> first = {polyline({{-1, 0.3}, {2, 0.7}})};
  rest.cut(first);
  world.cut(first);
  rest.cut(std::vector<Polyline>{polyline({{0.5625, -0.25}, {0.4375, 1.25}}), polyline({{0.125, 0.875}, {0.375, 0.875}})});
  const Vec3 p = phi(0.125, 0.875), q = phi(0.375, 0.875);
  world.cut_deformed(soup({blade_through(phi, {0.5625, -0.25}, {0.4375, 1.25}), {p, q, p + phi.normal()}}),
                     place(world, [&](double u, double v) { return phi(u, v); }));
  expect_same_cut(rest, world, true);
  expect_planar_invariants(mesh, world.result());
}

TEST(PlanarDeformedCut, ClothFoldedAlongAGridLine) {
  // Folded at right angles along x = 1/2 (a grid line, so each triangle moves affinely): the
  // plane y - z / 5 = 0.3 crosses the flat half along y = 0.3 and the raised half along
  // y = 0.3 + (x - 1/2) / 5. The triangles on the fold agree where the cut crosses it.
  const PlanarMesh mesh = make_planar_grid(4);
  PlanarCutter cutter(mesh);
  const Points folded = place(cutter, [](double x, double y) { return x <= 0.5 ? Vec3(x, y, 0) : Vec3(0.5, y, x - 0.5); });
  cutter.cut_deformed(soup({{Vec3(-1, 0.1, -1), Vec3(3, 0.1, -1), Vec3(-1, 0.9, 3)}}), folded);
  const PlanarCutResult r = cutter.result();
  ASSERT_EQ(r.mesh.num_pieces(), 2);
  EXPECT_NEAR(r.mesh.piece_areas[0], 0.675, 1e-12);
  EXPECT_NEAR(r.mesh.piece_areas[1], 0.325, 1e-12);
  expect_planar_invariants(mesh, r);
}

TEST(PlanarDeformedCut, EachCopyIsCutThroughItsOwnMotion) {
  // Cut across triangles at y = 7/16, then lift the upper piece 10 above the lower one: a blade
  // near z = 0 cuts the lower piece only, even in triangles holding a copy of each piece.
  const PlanarMesh mesh = make_planar_grid(4);
  PlanarCutter cutter(mesh);
  cutter.cut(std::vector<Polyline>{polyline({{-1, 0.4375}, {2, 0.4375}})});
  const PlanarCutResult before = cutter.result();
  Points x = place(cutter, [](double u, double v) { return Vec3(u, v, 0); });
  for (Index c = 0; c < before.mesh.mesh.num_triangles(); ++c) {
    if (before.mesh.triangle_piece[c] != 0) continue;  // piece 0: the larger, upper one
    for (int k = 0; k < 3; ++k) x(before.mesh.mesh.triangles(c, k), 2) = 10;
  }
  const PlanarCutReport report = cutter.cut_deformed(soup({{Vec3(0.25, -1, -1), Vec3(0.25, 3, -1), Vec3(0.25, -1, 1)}}), x);
  const PlanarCutResult r = cutter.result();
  ASSERT_EQ(r.mesh.num_pieces(), 3);
  EXPECT_EQ(sorted_areas(r), (std::vector<double>{0.109375, 0.328125, 0.5625}));
  expect_planar_invariants(mesh, r);
  // Only triangles of the lower rows changed.
  for (const Index t : report.touched) EXPECT_LT(t, 16) << "triangle " << t;
}

TEST(PlanarDeformedCut, CopiesInTheBladesPlaneAreReportedNotCut) {
  const PlanarMesh mesh = make_planar_grid(2);
  PlanarCutter cutter(mesh);
  const PlanarCutReport report =
      cutter.cut_deformed(soup({{Vec3(-1, -1, 0), Vec3(3, -1, 0), Vec3(-1, 3, 0)}}), place(cutter, [](double u, double v) { return Vec3(u, v, 0); }));
  EXPECT_EQ(report.skipped_coplanar.size(), 8u);
  EXPECT_TRUE(report.touched.empty());
  EXPECT_EQ(cutter.num_cells(), 8);
  EXPECT_EQ(cutter.result().mesh.num_pieces(), 1);
}

TEST(PlanarDeformedCut, BadInputIsRefusedAndChangesNothing) {
  const PlanarMesh mesh = make_planar_grid(2);
  PlanarCutter cutter(mesh);
  const Points flat = place(cutter, [](double u, double v) { return Vec3(u, v, 0); });
  const TriangleSurface blade = soup({{Vec3(0.5, -1, -1), Vec3(0.5, 3, -1), Vec3(0.5, -1, 1)}});
  EXPECT_THROW(cutter.cut_deformed(blade, Points(3, 3)), Error);
  Points nan = flat;
  nan(4, 2) = std::nan("");
  EXPECT_THROW(cutter.cut_deformed(blade, nan), Error);
  TriangleSurface bad = blade;
  bad.vertices(1, 0) = std::nan("");
  try {
    cutter.cut_deformed(bad, flat);
    FAIL() << "a NaN corner was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 0"), std::string::npos) << e.what();
  }
  EXPECT_EQ(cutter.num_cells(), 8);
  const PlanarCutReport degenerate = cutter.cut_deformed(soup({{Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2)}}), flat);
  EXPECT_EQ(degenerate.degenerate, std::vector<Index>{0});
  EXPECT_EQ(cutter.result().mesh.num_pieces(), 1);
}

// Random world-space blades on a crumpled cloth (every node at its own height): triangles at
// random, blade strips (which share edges), and blades through nodes' current positions.
std::vector<std::array<Vec3, 3>> random_blades(std::mt19937& rng, const Points& x) {
  std::uniform_real_distribution<double> coordinate(-0.2, 1.2), height(-0.5, 0.5);
  std::uniform_int_distribution<int> kind(0, 2), node(0, static_cast<int>(x.rows()) - 1), count(1, 4);
  auto random_point = [&] { return Vec3(coordinate(rng), coordinate(rng), height(rng)); };
  std::vector<std::array<Vec3, 3>> blades;
  const int n = count(rng);
  for (int i = 0; i < n; ++i) {
    switch (kind(rng)) {
      case 0: blades.push_back({random_point(), random_point(), random_point()}); break;
      case 1: {
        std::vector<BladePose> poses;
        for (int k = 0; k < 3; ++k) {
          const Vec3 a(coordinate(rng), coordinate(rng), -1);
          poses.push_back({a, a + Vec3(0, 0, 2)});
        }
        const TriangleSurface strip = swept_blade(poses);
        for (Index t = 0; t < strip.num_triangles(); ++t) {
          blades.push_back({strip.vertices.row(strip.triangles(t, 0)).transpose(), strip.vertices.row(strip.triangles(t, 1)).transpose(),
                            strip.vertices.row(strip.triangles(t, 2)).transpose()});
        }
        break;
      }
      default: {
        // Through a node: it is the middle of the first edge.
        const Vec3 at = x.row(node(rng)).transpose(), up(0, 0, 1), other = x.row(node(rng)).transpose();
        blades.push_back({at + up, at - up, other + up + Vec3(0.01, 0, 0)});
      }
    }
  }
  return blades;
}

TEST(PlanarDeformedCut, RandomBladesOnACrumpledClothKeepInvariantsAndIgnoreOrderAndBatches) {
  std::mt19937 rng(20261203);
  std::uniform_real_distribution<double> height(-0.15, 0.15);
  const PlanarMesh mesh = make_planar_grid(4);
  for (int trial = 0; trial < 1000; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    PlanarCutter whole(mesh);
    const Points crumpled = place(whole, [&](double u, double v) { return Vec3(u, v, height(rng)); });
    const std::vector<std::array<Vec3, 3>> blades = random_blades(rng, crumpled);
    whole.cut_deformed(soup(blades), crumpled);
    expect_planar_invariants(mesh, whole.result());
    if (HasFailure()) return;

    std::vector<std::array<Vec3, 3>> shuffled = blades;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    PlanarCutter batches(mesh);
    Points x = crumpled;
    std::size_t begin = 0;
    while (begin < shuffled.size()) {
      const std::size_t end = std::min(shuffled.size(), begin + 1 + rng() % 3);
      const PlanarCutReport report =
          batches.cut_deformed(soup(std::vector<std::array<Vec3, 3>>(shuffled.begin() + static_cast<std::ptrdiff_t>(begin),
                                                                     shuffled.begin() + static_cast<std::ptrdiff_t>(end))),
                               x);
      x = carried_over(x, report);
      begin = end;
    }
    expect_planar_invariants(mesh, batches.result());
    expect_same_cut(whole, batches, false);
    if (HasFailure()) return;
  }
}

}  // namespace
}  // namespace tetcut
