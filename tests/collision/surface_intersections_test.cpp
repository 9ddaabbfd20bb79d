// Counting self-intersections of the material surface: a block cut in two, its halves pushed
// into each other, pulled apart, and moved by less than any epsilon.

#include <tetcut/collision.hpp>
#include <tetcut/error.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

namespace tetcut {
namespace {

struct CutBlock {
  CutResult result;
  std::vector<std::array<Index, 4>> copies;
  std::vector<std::uint8_t> right_node;  // nodes of the piece at x > 0.5
};

CutBlock halves() {
  Cutter cutter(make_grid(Box{}, {3, 3, 3}, 5));
  cutter.cut(figures::axis_square(0, 0.5, -1, 2));
  CutBlock b{cutter.result(), cutter.tet_nodes(), {}};
  const CutMesh& m = b.result.mesh;
  EXPECT_EQ(m.num_pieces(), 2);
  b.right_node.assign(static_cast<std::size_t>(m.mesh.num_nodes()), 0);
  // The right piece: the one holding the corner (1, 1, 1); pieces share no node.
  Index corner = 0;
  for (Index n = 0; n < m.mesh.num_nodes(); ++n) {
    if (m.mesh.rest().row(n) == Eigen::RowVector3d(1, 1, 1)) corner = n;
  }
  Index right = -1;
  for (Index t = 0; t < m.mesh.num_tets(); ++t) {
    for (int k = 0; k < 4; ++k) right = m.mesh.tets()(t, k) == corner ? m.tet_piece[static_cast<std::size_t>(t)] : right;
  }
  for (Index t = 0; t < m.mesh.num_tets(); ++t) {
    if (m.tet_piece[static_cast<std::size_t>(t)] != right) continue;
    for (int k = 0; k < 4; ++k) b.right_node[static_cast<std::size_t>(m.mesh.tets()(t, k))] = 1;
  }
  return b;
}

// The surface's vertices with the right piece moved by `move`.
Points moved(const CutBlock& b, const Vec3& move) {
  Points nodes = b.result.mesh.mesh.rest();
  for (Index n = 0; n < nodes.rows(); ++n) {
    if (b.right_node[static_cast<std::size_t>(n)]) nodes.row(n) += move.transpose();
  }
  return b.result.surface.positions(b.result.mesh, nodes);
}

// The surface's vertices with the right piece moved by `shift` along x.
Points shifted(const CutBlock& b, double shift) { return moved(b, Vec3(shift, 0, 0)); }

TEST(SurfaceIntersections, AFreshCutIsNotACollision) {
  const CutBlock b = halves();
  const SurfaceIntersections r = count_surface_intersections(b.result.surface, b.copies, shifted(b, 0));
  EXPECT_EQ(r.intersecting_pairs, 0);
  EXPECT_GT(r.candidate_pairs, 0);  // the two cut faces, face to face, were looked at
  EXPECT_EQ(r.degenerate_triangles, 0);
}

TEST(SurfaceIntersections, HalvesPushedTogetherIntersectAndPulledApartDoNot) {
  const CutBlock b = halves();
  const SurfaceIntersections pushed = count_surface_intersections(b.result.surface, b.copies, shifted(b, -0.2));
  EXPECT_GT(pushed.intersecting_pairs, 10);
  ASSERT_FALSE(pushed.examples.empty());
  EXPECT_LE(pushed.examples.size(), 16u);
  for (const auto& [t, u] : pushed.examples) {
    EXPECT_LT(t, u);
    EXPECT_NE(b.result.surface.triangle_tet[static_cast<std::size_t>(t)], b.result.surface.triangle_tet[static_cast<std::size_t>(u)]);
  }
  EXPECT_EQ(count_surface_intersections(b.result.surface, b.copies, shifted(b, 0.2)).intersecting_pairs, 0);
}

TEST(SurfaceIntersections, OnceOpenedTheSidesOfACutCountAsSoonAsTheyCross) {
  const CutBlock b = halves();
  // Apart by 1e-12: parallel faces, no common point. Across by 1e-12: the halves overlap.
  EXPECT_EQ(count_surface_intersections(b.result.surface, b.copies, shifted(b, 1e-12)).intersecting_pairs, 0);
  EXPECT_GT(count_surface_intersections(b.result.surface, b.copies, shifted(b, -1e-12)).intersecting_pairs, 0);
}

// The right half pressed 1e-3 into the left one and slid as far along the cut: pressed within
// what is allowed, not counted; allowed less, or pressed deeper, counted.
TEST(SurfaceIntersections, SidesOfACutPressedAndSlidCountOnlyDeeperThanAllowed) {
  const CutBlock b = halves();
  const double pressed = 1e-3;
  const Points slid = moved(b, Vec3(-pressed, -pressed, pressed));
  EXPECT_EQ(count_surface_intersections(b.result.surface, b.copies, slid, 2 * pressed).intersecting_pairs, 0);
  EXPECT_GT(count_surface_intersections(b.result.surface, b.copies, slid, pressed / 2).intersecting_pairs, 0);
  EXPECT_GT(count_surface_intersections(b.result.surface, b.copies, moved(b, Vec3(-0.2, -0.1, 0.1)), 2 * pressed).intersecting_pairs, 10);
}

// Two triangles of two copies (a cut's triangle, then an outer face's), corners given row by row,
// and the corners of the first moved by `move`.
struct TwoTriangles {
  MaterialSurface surface;
  std::vector<std::array<Index, 4>> copies = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  explicit TwoTriangles(const Eigen::Matrix<double, 6, 3, Eigen::RowMajor>& corners) {
    surface.surface.vertices = corners;
    surface.surface.triangles.resize(2, 3);
    surface.surface.triangles << 0, 1, 2, 3, 4, 5;
    surface.triangle_tet = {0, 1};
    surface.triangle_source = {0, -1};
  }
  Points first_moved(const Vec3& move) const {
    Points at = surface.surface.vertices;
    for (Index v = 0; v < 3; ++v) at.row(v) += move.transpose();
    return at;
  }
  Index crossing(const Points& at, double opened) const { return count_surface_intersections(surface, copies, at, opened).intersecting_pairs; }
};

// Where a cut's rim meets the outer surface: a wall (plane x = 0, material at x > 0) and the top
// face beside it of another copy (plane z = 0, material below), 2e-4 apart in the material, as the
// two sides' fans over their polygons may leave them. The wall moved 3e-4 to -x and 1e-4 up
// pierces the top face, whose edge then reaches 1e-4 behind the wall: within an allowance that
// covers both the gap and the depth, not counted; with less allowed, or pressed 0.01 in, counted.
TEST(SurfaceIntersections, ARimApartInTheMaterialByLessThanAllowedCountsOnlyPressedDeeper) {
  constexpr double kGap = 2e-4;
  Eigen::Matrix<double, 6, 3, Eigen::RowMajor> corners;
  corners << 0, 0, 0, 0, 1, 0, 0, 0.5, -1,  // the wall, normal -x
      -kGap, 0.2, 0, -kGap, 0.8, 0, -1, 0.2, 0;  // the top face, normal +z
  const TwoTriangles t(corners);
  const auto pressed = [&](double by) { return t.first_moved(Vec3(-kGap - by, 0, 1e-4)); };
  EXPECT_EQ(t.crossing(t.surface.surface.vertices, 1e-3), 0);
  EXPECT_EQ(t.crossing(pressed(1e-4), 1e-3), 0);
  EXPECT_EQ(t.crossing(pressed(1e-4), 5e-5), 1);
  EXPECT_EQ(t.crossing(pressed(1e-2), 1e-3), 1);
}

// The same rim and top face 2e-3 apart in the material, farther than the allowance (1e-3): the
// sides of a cut pressed together and slid along each other, a rim now pressed into the face
// beside it (a slinky's slit, pressed shut, its upper lip 3e-5 into the lower lip's rim 0.0017
// from it along the cut). Counted unless they lie within `slid` of each other there; pressed 0.01
// in, counted whatever `slid` is.
TEST(SurfaceIntersections, ARimSlidAlongACutWithinSlidCountsOnlyPressedDeeper) {
  constexpr double kGap = 2e-3, kAllowed = 1e-3;
  Eigen::Matrix<double, 6, 3, Eigen::RowMajor> corners;
  corners << 0, 0, 0, 0, 1, 0, 0, 0.5, -1,  // the wall, normal -x
      -kGap, 0.2, 0, -kGap, 0.8, 0, -1, 0.2, 0;  // the top face, normal +z
  const TwoTriangles t(corners);
  const auto pressed = [&](double by) { return t.first_moved(Vec3(-kGap - by, 0, 1e-4)); };
  const auto crossing = [&](const Points& at, double slid) {
    return count_surface_intersections(t.surface, t.copies, at, kAllowed, slid).intersecting_pairs;
  };
  EXPECT_EQ(crossing(pressed(1e-4), 0), 1);
  EXPECT_EQ(crossing(pressed(1e-4), kGap / 2), 1);
  EXPECT_EQ(crossing(pressed(1e-4), 2 * kGap), 0);
  EXPECT_EQ(crossing(pressed(1e-2), 2 * kGap), 1);
  EXPECT_EQ(crossing(t.surface.surface.vertices, 0), 0);
}

// Two triangles of copies that share a node, apart in the material (a vertical one 0.3 beyond the
// first's corner), the first moved through the second. Such pairs were left out as neighbours in
// the material whose surfaces meet by construction; but where a cut runs between two copies that
// share a node (near an incision's end, the folded flap's hinge, a slinky's neighbouring coils),
// their sides pass through each other as any others' do (the flap's sides, pressed together where
// the cut ends, crossed unseen in 18 pairs). They count as pairs of copies apart do.
TEST(SurfaceIntersections, CopiesSharingANodeCountAsAnyOthers) {
  Eigen::Matrix<double, 6, 3, Eigen::RowMajor> corners;
  corners << 0, 0, 0, 1, 0, 0, 0, 1, 0,  // z = 0
      2.3, 0.3, -0.5, 2.3, 1.5, 0, 2.3, 0.3, 0.5;  // x = 2.3
  TwoTriangles apart(corners), sharing(corners);
  sharing.copies = {{0, 1, 2, 3}, {3, 4, 5, 6}};
  const Points through = apart.first_moved(Vec3(2, 0, 0));
  for (const TwoTriangles* pair : {&apart, &sharing}) {
    EXPECT_EQ(pair->crossing(pair->surface.surface.vertices, 0), 0);
    EXPECT_EQ(pair->crossing(through, 0), 1);
    EXPECT_EQ(pair->crossing(apart.first_moved(Vec3(1, 0, 0)), 0), 0);  // short of it
  }
}

// Where a third face meets a cut: a stick's side (plane y = 0, material at y > 0, x > 0) and its
// neighbour's top face (plane z = 0, material below, x < 0), which touch at one point in the
// material (Figure 4's sticks). Pressed p into the neighbour and slid 3p along the cut (so that
// their corners, one point in the material, are apart by more than the allowance), the side
// crosses the top face in a strip p wide along both rims, though either triangle reaches nearly
// its whole size behind the other: within an allowance of 2p, not counted; allowed p / 2, or
// pressed 0.1 in, counted.
TEST(SurfaceIntersections, AFacePressedAcrossARimCountsByHowFarFromTheRimsItCrosses) {
  Eigen::Matrix<double, 6, 3, Eigen::RowMajor> corners;
  corners << 0, 0, -1, 1, 0, 0, 0, 0, 0,  // the side, normal -y
      0, 0, 0, 0, 1, 0, -1, 1, 0;          // the top face, normal +z
  const TwoTriangles t(corners);
  const auto pressed = [&](double by) { return t.first_moved(Vec3(-by, 3 * by, 3 * by)); };
  constexpr double kPressed = 1e-3;
  EXPECT_EQ(t.crossing(t.surface.surface.vertices, 2 * kPressed), 0);
  EXPECT_EQ(t.crossing(pressed(kPressed), 2 * kPressed), 0);
  EXPECT_EQ(t.crossing(pressed(kPressed), kPressed / 2), 1);
  EXPECT_EQ(t.crossing(pressed(0.1), 2 * kPressed), 1);
}

// The two sides of one flat cut (plane z = 0), apart along it in the material by more than the
// allowance, as the sides' fans over the cut polygon can leave them (the folded flap's floor:
// 0.0016 apart): the upper side (normal -z) slid 0.3 over the lower (normal +z), one corner
// pressed into it by 1e-6, grazes it as two sides that touched would, and is not counted within an
// allowance of 1e-4; pressed in by 1e-3, or turned out of the plane in the material (a wall), it is.
TEST(SurfaceIntersections, TwoSidesOfOneCutApartAlongItCountOnlyPressedDeeperThanAllowed) {
  constexpr double kGap = 0.0016;
  Eigen::Matrix<double, 6, 3, Eigen::RowMajor> corners;
  corners << 0, 0, 0, 0, 1, 0, 1, 0, 0,  // the upper side, normal -z
      1 + kGap, 0, 0, 2, 0, 0, 1 + kGap, 1, 0;  // the lower side, normal +z
  const TwoTriangles t(corners);
  const auto slid = [&](double pressed) {
    Points at = t.first_moved(Vec3(0.3, 0.05, 3 * pressed));  // tilted: it meets z = 0 at x = 1.05
    at(2, 2) = -pressed;
    return at;
  };
  EXPECT_EQ(t.crossing(t.surface.surface.vertices, 1e-4), 0);
  EXPECT_EQ(t.crossing(slid(1e-6), 1e-4), 0);
  EXPECT_EQ(t.crossing(slid(1e-3), 1e-4), 1);
  // The lower triangle turned up by 0.01 in the material: not one plane with the upper.
  Eigen::Matrix<double, 6, 3, Eigen::RowMajor> turned = corners;
  turned(5, 2) = 0.01;
  const TwoTriangles wall(turned);
  EXPECT_EQ(wall.crossing(slid(1e-6), 1e-4), 1);
}

// A sliver of the material surface: two of its corners are one material point, embedded twice
// (in two copies sharing the nodes it hangs on, with weights an ulp apart). Placed, the two come
// out an ulp apart and the sliver opens into a needle, here through a triangle of another copy:
// no material there, not a crossing. Flat now, or in the material, a triangle is skipped.
TEST(SurfaceIntersections, ASliverOfTheMaterialIsNotACrossingWhenItsTwinCornersPartByAnUlp) {
  Eigen::Matrix<double, 6, 3, Eigen::RowMajor> corners;
  corners << 0, 0, 0, 0, 0, 0, 1, 0, 0,  // the sliver: corners 0 and 1 one point, from x = 0 to 1
      0.5, -1, -1, 0.5, 1, -1, 0.5, 0, 1;  // a triangle of another copy across it at x = 0.5
  const TwoTriangles t(corners);
  Points now = t.surface.surface.vertices;
  now(1, 1) = 4 * std::numeric_limits<double>::epsilon();
  now(1, 2) = 4 * std::numeric_limits<double>::epsilon();
  const SurfaceIntersections r = count_surface_intersections(t.surface, t.copies, now);
  EXPECT_EQ(r.intersecting_pairs, 0);
  EXPECT_EQ(r.degenerate_triangles, 1);
  // The twin corners an ulp apart in the material too (each copy rounds the point it places):
  // still a needle there, skipped (Figure 4 at 0.9 s).
  TwoTriangles rounded(corners);
  rounded.surface.surface.vertices(1, 2) = std::numeric_limits<double>::epsilon();
  const SurfaceIntersections needle = count_surface_intersections(rounded.surface, rounded.copies, now);
  EXPECT_EQ(needle.intersecting_pairs, 0);
  EXPECT_EQ(needle.degenerate_triangles, 1);
  // The same needle with a rest shape of its own (not flat in the material) is a crossing.
  TwoTriangles solid(corners);
  solid.surface.surface.vertices.row(1) = Eigen::RowVector3d(0, 0.1, 0.1);
  EXPECT_EQ(count_surface_intersections(solid.surface, solid.copies, now).intersecting_pairs, 1);
}

// One piece: an incision x = 0.5 from the top down to z = 0.3. Its right lip, pushed left far
// from the incision's end, passes through the left lip: parts of one piece, seen.
TEST(SurfaceIntersections, LipsOfAnIncisionCrossingAreSeen) {
  Cutter cutter(make_grid(Box{}, {6, 6, 6}, 5));
  TriangleSurface incision;
  incision.vertices.resize(4, 3);
  incision.vertices << 0.5, -1, 0.3, 0.5, 2, 0.3, 0.5, 2, 2, 0.5, -1, 2;
  incision.triangles.resize(2, 3);
  incision.triangles << 0, 1, 2, 0, 2, 3;
  cutter.cut(incision);
  const CutResult r = cutter.result();
  ASSERT_EQ(r.mesh.num_pieces(), 1);
  const MaterialSurface& surface = r.surface;
  // The right lip's copies: those whose cut faces look to -x.
  std::vector<std::uint8_t> moved(static_cast<std::size_t>(r.mesh.mesh.num_nodes()), 0);
  const auto& copies = cutter.tet_nodes();
  for (Index t = 0; t < surface.surface.num_triangles(); ++t) {
    if (surface.triangle_source[static_cast<std::size_t>(t)] < 0) continue;
    const Vec3 a = surface.surface.vertices.row(surface.surface.triangles(t, 0)).transpose();
    const Vec3 b = surface.surface.vertices.row(surface.surface.triangles(t, 1)).transpose();
    const Vec3 c = surface.surface.vertices.row(surface.surface.triangles(t, 2)).transpose();
    if ((b - a).cross(c - a).x() >= 0 || a.z() < 0.75) continue;
    for (const Index n : copies[static_cast<std::size_t>(surface.triangle_tet[static_cast<std::size_t>(t)])]) {
      if (r.mesh.mesh.rest()(n, 2) > 0.7) moved[static_cast<std::size_t>(n)] = 1;
    }
  }
  Points nodes = r.mesh.mesh.rest();
  EXPECT_EQ(count_surface_intersections(surface, copies, surface.positions(r.mesh, nodes)).intersecting_pairs, 0);
  for (Index n = 0; n < nodes.rows(); ++n) {
    if (moved[static_cast<std::size_t>(n)]) nodes(n, 0) -= 0.1;
  }
  EXPECT_GT(count_surface_intersections(surface, copies, surface.positions(r.mesh, nodes)).intersecting_pairs, 0);
}

TEST(SurfaceIntersections, FlatTrianglesAreSkippedAndSizesChecked) {
  const CutBlock b = halves();
  Points flat = shifted(b, 0);
  flat.col(2).setZero();  // everything squashed onto z = 0
  const SurfaceIntersections r = count_surface_intersections(b.result.surface, b.copies, flat);
  EXPECT_GT(r.degenerate_triangles, 0);
  EXPECT_THROW(count_surface_intersections(b.result.surface, b.copies, Points(3, 3)), Error);
}

}  // namespace
}  // namespace tetcut
