// The planar cutter on cases with exact answers, on degenerate input, and on random polyline soups.

#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/planar_cutter.hpp>

#include <gtest/gtest.h>

#include "support/planar_invariants.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

namespace tetcut {
namespace {

using testing::expect_planar_invariants;
using testing::polyline;
using testing::sorted_areas;

PlanarCutResult cut_all(const PlanarMesh& mesh, const std::vector<Polyline>& cuts) {
  PlanarCutter cutter(mesh);
  cutter.cut(cuts);
  return cutter.result();
}

TEST(PlanarCutter, UncutSquareIsOnePiece) {
  const PlanarMesh mesh = make_planar_grid(2);
  const PlanarCutResult r = cut_all(mesh, {});
  EXPECT_EQ(r.mesh.num_pieces(), 1);
  EXPECT_EQ(r.mesh.mesh.num_triangles(), 8);
  EXPECT_EQ(r.mesh.mesh.num_nodes(), 9);
  EXPECT_EQ(r.material.num_segments(), 8);
  expect_planar_invariants(mesh, r);
}

TEST(PlanarCutter, StraightCutAcrossTwoTriangles) {
  const PlanarMesh mesh = make_planar_grid(1);
  const PlanarCutResult r = cut_all(mesh, {polyline({{0.5, -1}, {0.5, 2}})});
  EXPECT_EQ(r.mesh.num_pieces(), 2);
  EXPECT_EQ(r.mesh.piece_areas[0], 0.5);
  EXPECT_EQ(r.mesh.piece_areas[1], 0.5);
  EXPECT_EQ(r.mesh.mesh.num_triangles(), 4);  // both triangles split
  EXPECT_EQ(r.mesh.mesh.num_nodes(), 8);      // each side has its own four corners
  expect_planar_invariants(mesh, r);
}

TEST(PlanarCutter, StripsHaveExactAreas) {
  const PlanarMesh mesh = make_planar_grid(4);
  const PlanarCutResult r =
      cut_all(mesh, {polyline({{-1, 0.375}, {2, 0.375}}), polyline({{2, 0.6875}, {-1, 0.6875}}), polyline({{-1, 0.125}, {2, 0.125}})});
  ASSERT_EQ(r.mesh.num_pieces(), 4);
  EXPECT_EQ(sorted_areas(r), (std::vector<double>{0.125, 0.25, 0.3125, 0.3125}));
  // Each cut crosses a row of 8 triangles and splits each in two; no two cuts share a triangle.
  EXPECT_EQ(r.mesh.mesh.num_triangles(), 32 + 3 * 8);
  expect_planar_invariants(mesh, r);
}

TEST(PlanarCutter, CutAlongEdgesThroughVerticesSplitsNoTriangle) {
  const PlanarMesh mesh = make_planar_grid(4);
  const PlanarCutResult r = cut_all(mesh, {polyline({{-1, 0.5}, {2, 0.5}})});
  ASSERT_EQ(r.mesh.num_pieces(), 2);
  EXPECT_EQ(r.mesh.piece_areas[0], 0.5);
  EXPECT_EQ(r.mesh.piece_areas[1], 0.5);
  EXPECT_EQ(r.mesh.mesh.num_triangles(), 32);  // the cut runs along edges: no triangle has two components
  EXPECT_EQ(r.mesh.mesh.num_nodes(), 25 + 5);  // the five nodes on the cut are doubled
  expect_planar_invariants(mesh, r);
}

TEST(PlanarCutter, DiagonalThroughVerticesAcrossTriangles) {
  // The grid's diagonals run from (i, j) to (i + 1, j + 1); this cut runs the other way, through
  // the vertices (i, n - i), splitting the triangles it crosses.
  const PlanarMesh mesh = make_planar_grid(4);
  const PlanarCutResult r = cut_all(mesh, {polyline({{-0.25, 1.25}, {1.25, -0.25}})});
  ASSERT_EQ(r.mesh.num_pieces(), 2);
  EXPECT_EQ(r.mesh.piece_areas[0], 0.5);
  EXPECT_EQ(r.mesh.piece_areas[1], 0.5);
  expect_planar_invariants(mesh, r);
}

TEST(PlanarCutter, TCut) {
  const PlanarMesh mesh = make_planar_grid(4);
  const PlanarCutResult r = cut_all(mesh, {polyline({{-1, 0.4375}, {2, 0.4375}}), polyline({{0.3125, 0.4375}, {0.3125, 3}})});
  ASSERT_EQ(r.mesh.num_pieces(), 3);
  EXPECT_EQ(sorted_areas(r), (std::vector<double>{0.3125 * 0.5625, 0.6875 * 0.5625, 0.4375}));
  expect_planar_invariants(mesh, r);
}

TEST(PlanarCutter, PartialCutSeparatesNothingButOpensASlit) {
  const PlanarMesh mesh = make_planar_grid(4);
  PlanarCutter cutter(mesh);
  cutter.cut(std::vector<Polyline>{polyline({{-1, 0.4375}, {0.6, 0.4375}})});
  const PlanarCutResult r = cutter.result();
  EXPECT_EQ(r.mesh.num_pieces(), 1);
  EXPECT_EQ(r.mesh.piece_areas[0], 1.0);
  // Both sides of the slit are boundary: its length twice, beside the square's perimeter.
  double length = 0;
  for (Index s = 0; s < r.material.num_segments(); ++s) {
    length += (r.material.rest.row(r.material.segments(s, 1)) - r.material.rest.row(r.material.segments(s, 0))).norm();
  }
  EXPECT_NEAR(length, 4 + 2 * 0.6, 1e-12);
  // The triangles the slit crosses completely have two copies; the one it ends in has one.
  EXPECT_GT(r.mesh.mesh.num_triangles(), 32);
  expect_planar_invariants(mesh, r);
}

TEST(PlanarCutter, ClosedLoopInsideOneTriangle) {
  PlanarMesh mesh;
  mesh.rest.resize(3, 2);
  mesh.rest << 0, 0, 4, 0, 0, 4;
  mesh.triangles.resize(1, 3);
  mesh.triangles << 0, 1, 2;
  const PlanarCutResult r = cut_all(mesh, {polyline({{0.5, 0.5}, {1.5, 0.5}, {1.5, 1.5}, {0.5, 1.5}}, true)});
  ASSERT_EQ(r.mesh.num_pieces(), 2);
  EXPECT_EQ(r.mesh.piece_areas[0], 7.0);
  EXPECT_EQ(r.mesh.piece_areas[1], 1.0);
  EXPECT_EQ(r.mesh.mesh.num_triangles(), 2);  // the ring and the square: one copy each
  EXPECT_EQ(r.mesh.mesh.num_nodes(), 6);
  expect_planar_invariants(mesh, r);
}

TEST(PlanarCutter, CutOfACutInLaterBatches) {
  const PlanarMesh mesh = make_planar_grid(4);
  PlanarCutter cutter(mesh);
  const PlanarCutReport first = cutter.cut(std::vector<Polyline>{polyline({{-1, 0.3}, {2, 0.7}})});
  EXPECT_EQ(cutter.result().mesh.num_pieces(), 2);
  const Index copies_before = cutter.num_triangles();
  const std::vector<std::array<Index, 3>> nodes_before = cutter.triangle_nodes();
  const PlanarCutReport second = cutter.cut(std::vector<Polyline>{polyline({{0.55, -1}, {0.45, 2}})});
  const PlanarCutResult r = cutter.result();
  EXPECT_EQ(r.mesh.num_pieces(), 4);
  expect_planar_invariants(mesh, r);
  // Ids stay: old copies keep their triangle, new ones follow and name where they came from.
  EXPECT_EQ(second.first_new_triangle, copies_before);
  ASSERT_EQ(static_cast<Index>(second.new_triangle_source.size()), cutter.num_triangles() - copies_before);
  for (std::size_t i = 0; i < second.new_triangle_source.size(); ++i) {
    EXPECT_EQ(cutter.triangle_parent()[copies_before + i], cutter.triangle_parent()[second.new_triangle_source[i]]);
  }
  for (Index c = 0; c < copies_before; ++c) {
    const bool changed = std::binary_search(second.changed_triangles.begin(), second.changed_triangles.end(), c);
    if (!changed) {
      EXPECT_EQ(cutter.triangle_nodes()[c], nodes_before[c]) << "copy " << c;
    }
  }
  // Only the triangles the second cut crosses change: two columns of the grid (16 triangles), in
  // one of which the cut runs along no edge.
  EXPECT_FALSE(second.touched.empty());
  EXPECT_LE(second.touched.size(), 16u);
  EXPECT_FALSE(first.touched.empty());
}

TEST(PlanarCutter, OverlappingAndRepeatedSegmentsCountOnce) {
  const PlanarMesh mesh = make_planar_grid(4);
  const PlanarCutResult once = cut_all(mesh, {polyline({{-1, 0.3}, {2, 0.3}})});
  const PlanarCutResult overlapping =
      cut_all(mesh, {polyline({{-1, 0.3}, {0.7, 0.3}}), polyline({{0.2, 0.3}, {2, 0.3}}), polyline({{2, 0.3}, {-1, 0.3}})});
  EXPECT_EQ(sorted_areas(once), sorted_areas(overlapping));
  EXPECT_EQ(once.mesh.mesh.num_triangles(), overlapping.mesh.mesh.num_triangles());
  EXPECT_EQ(once.mesh.mesh.num_nodes(), overlapping.mesh.mesh.num_nodes());
  EXPECT_EQ(once.material.num_segments() > 0, true);
  expect_planar_invariants(mesh, overlapping);
}

TEST(PlanarCutter, ZeroLengthSegmentsAreSkippedAndReported) {
  const PlanarMesh mesh = make_planar_grid(2);
  PlanarCutter cutter(mesh);
  const PlanarCutReport report = cutter.cut(std::vector<Polyline>{polyline({{0.3, 0.3}, {0.3, 0.3}, {0.7, 0.3}})});
  EXPECT_EQ(report.segments, 2);
  EXPECT_EQ(report.degenerate, std::vector<Index>{0});
  expect_planar_invariants(mesh, cutter.result());
}

TEST(PlanarCutter, BadInputIsRefusedAndChangesNothing) {
  PlanarMesh mesh = make_planar_grid(2);
  PlanarCutter cutter(mesh);
  Polyline bad = polyline({{0.1, 0.1}, {0.9, 0.9}});
  bad.points(1, 1) = std::nan("");
  const std::vector<Polyline> batch = {polyline({{-1, 0.5}, {2, 0.5}}), bad};
  try {
    cutter.cut(batch);
    FAIL() << "a NaN was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("polyline 1, point 1"), std::string::npos) << e.what();
  }
  EXPECT_EQ(cutter.result().mesh.num_pieces(), 1);
  EXPECT_EQ(cutter.num_cells(), 8);

  PlanarMesh clockwise = mesh;
  std::swap(clockwise.triangles(3, 1), clockwise.triangles(3, 2));
  EXPECT_THROW({ PlanarCutter c(clockwise); }, Error);
  PlanarMesh flat = mesh;
  flat.rest.row(4) = flat.rest.row(0);
  EXPECT_THROW({ PlanarCutter c(flat); }, Error);
  PlanarMesh out_of_range = mesh;
  out_of_range.triangles(0, 0) = 99;
  EXPECT_THROW({ PlanarCutter c(out_of_range); }, Error);
}

TEST(PlanarCutter, ToRestFollowsEachTriangleBackToRest) {
  // A cut square turned and moved in space: points on the moved copies map back to where they
  // came from in the rest plane, on both sides of the cut.
  const PlanarMesh mesh = make_planar_grid(4);
  PlanarCutter cutter(mesh);
  cutter.cut(std::vector<Polyline>{polyline({{-1, 0.5}, {2, 0.5}})});
  const PlanarCutResult r = cutter.result();
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.4, Vec3(1, 1, 0).normalized()).toRotationMatrix();
  Points nodes(r.mesh.mesh.num_nodes(), 3);
  for (Index n = 0; n < nodes.rows(); ++n) {
    const Vec3 flat(r.mesh.mesh.rest(n, 0), r.mesh.mesh.rest(n, 1), 0);
    nodes.row(n) = (rotation * flat + Vec3(3, -1, 2)).transpose();
  }
  Points2 rest(3, 2);
  rest << 0.3, 0.2, 0.9, 0.1, 0.6, 0.8;
  Points world(3, 3);
  for (Index i = 0; i < 3; ++i) world.row(i) = (rotation * Vec3(rest(i, 0), rest(i, 1), 0) + Vec3(3, -1, 2)).transpose();
  const Points2 back = cutter.to_rest(world, nodes);
  for (Index i = 0; i < 3; ++i) {
    EXPECT_NEAR(back(i, 0), rest(i, 0), 1e-12);
    EXPECT_NEAR(back(i, 1), rest(i, 1), 1e-12);
  }
  EXPECT_THROW(cutter.to_rest(world, Points(2, 3)), Error);
}

// Random polyline soups: segments between random points, grid nodes (through vertices), along
// grid lines (along edges), closed loops, and repeats. Whatever the order and however they are
// split into batches, the pieces are the same.
std::vector<Polyline> random_soup(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> coordinate(-0.2, 1.2);
  std::uniform_int_distribution<int> kind(0, 3), node(0, n), count(2, 5);
  auto point = [&]() -> std::array<double, 2> {
    switch (kind(rng)) {
      case 0:
      case 1: return {coordinate(rng), coordinate(rng)};
      case 2: return {static_cast<double>(node(rng)) / n, static_cast<double>(node(rng)) / n};
      default: return {static_cast<double>(node(rng)) / n, coordinate(rng)};
    }
  };
  std::vector<Polyline> soup;
  const int lines = count(rng);
  for (int l = 0; l < lines; ++l) {
    Polyline p;
    const int points = count(rng);
    p.points.resize(points, 2);
    for (int i = 0; i < points; ++i) {
      const auto x = point();
      p.points.row(i) << x[0], x[1];
    }
    p.closed = kind(rng) == 0;
    soup.push_back(p);
  }
  if (kind(rng) == 0) soup.push_back(soup.front());  // a repeated cut
  return soup;
}

// The soup as single segments, for reordering.
std::vector<Polyline> segments_of(const std::vector<Polyline>& soup) {
  std::vector<Polyline> out;
  for (const Polyline& p : soup) {
    for (Index i = 0; i < p.num_segments(); ++i) {
      const Index j = (i + 1) % static_cast<Index>(p.points.rows());
      out.push_back(polyline({{p.points(i, 0), p.points(i, 1)}, {p.points(j, 0), p.points(j, 1)}}));
    }
  }
  return out;
}

TEST(PlanarCutter, RandomSoupsKeepInvariantsAndIgnoreOrderAndBatches) {
  std::mt19937 rng(20261202);
  const int n = 4;
  const PlanarMesh mesh = make_planar_grid(n);
  for (int trial = 0; trial < 1000; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const std::vector<Polyline> soup = random_soup(rng, n);
    const PlanarCutResult whole = cut_all(mesh, soup);
    expect_planar_invariants(mesh, whole);
    if (HasFailure()) return;

    std::vector<Polyline> shuffled = segments_of(soup);
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    PlanarCutter batches(mesh);
    std::size_t begin = 0;
    while (begin < shuffled.size()) {
      const std::size_t end = std::min(shuffled.size(), begin + 1 + rng() % 3);
      batches.cut(std::span<const Polyline>(shuffled.data() + begin, end - begin));
      begin = end;
    }
    const PlanarCutResult split = batches.result();
    expect_planar_invariants(mesh, split);
    ASSERT_EQ(whole.mesh.num_pieces(), split.mesh.num_pieces());
    const std::vector<double> a = sorted_areas(whole), b = sorted_areas(split);
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-12);
    EXPECT_EQ(whole.mesh.mesh.num_triangles(), split.mesh.mesh.num_triangles());
    EXPECT_EQ(whole.mesh.mesh.num_nodes(), split.mesh.mesh.num_nodes());
    if (HasFailure()) return;
  }
}

}  // namespace
}  // namespace tetcut
