// Cutting in world space on a deformed mesh, and cutting in batches: exact answers where the
// pulled-back geometry is known, the paper's Figure 3 (one tet cut through earlier cuts while its
// pieces move), and the rule for inverted tets.

#include <gtest/gtest.h>

#include <tetcut/blade.hpp>
#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/quality.hpp>

#include <algorithm>
#include <cmath>
#include <span>

#include "support/cut_invariants.hpp"

namespace tetcut {
namespace {

using testing::Triangle;

void expect_same_pieces(const CutResult& a, const CutResult& b, double tolerance) {
  ASSERT_EQ(a.mesh.num_pieces(), b.mesh.num_pieces());
  for (Index p = 0; p < a.mesh.num_pieces(); ++p) EXPECT_NEAR(a.mesh.piece_volumes[p], b.mesh.piece_volumes[p], tolerance);
}

// A cube sheared by x' = x + 0.5 z, cut by the world plane x' = 0.6: in rest space that is the
// plane x + 0.5 z = 0.6, which leaves 0.35 of the unit cube on its low side.
TEST(DeformedCut, ShearedCubeIsCutWhereThePlaneCrossesItInWorldSpace) {
  const TetMesh mesh = make_grid(Box{}, {4, 4, 4}, 5);
  Points sheared = mesh.rest();
  sheared.col(0) += 0.5 * mesh.rest().col(2);
  Cutter world(mesh);
  const CutBatchReport report = world.cut_deformed(figures::axis_square(0, 0.6, -1, 3), sheared);
  EXPECT_TRUE(report.skipped_inverted.empty());
  const CutResult r = world.result();
  EXPECT_EQ(testing::check_cut_invariants(mesh, r), "");
  ASSERT_EQ(r.mesh.num_pieces(), 2);
  EXPECT_NEAR(r.mesh.piece_volumes[0], 0.65, 1e-13);
  EXPECT_NEAR(r.mesh.piece_volumes[1], 0.35, 1e-13);
  // The same cut placed in rest space along the preimage plane gives the same pieces and mesh.
  Cutter rest(mesh);
  rest.cut(testing::soup({{Vec3(0.6, -1, 0), Vec3(0.6, 3, 0), Vec3(-0.4, -1, 2)},
                          {Vec3(0.6, 3, 0), Vec3(-0.4, 3, 2), Vec3(-0.4, -1, 2)}}));
  const CutResult expected = rest.result();
  expect_same_pieces(r, expected, 1e-13);
  EXPECT_EQ(r.mesh.mesh.num_tets(), expected.mesh.mesh.num_tets());
  EXPECT_EQ(r.mesh.mesh.num_nodes(), expected.mesh.mesh.num_nodes());
  // The world-space surface, moved by the shear, has the sheared cube's area plus both sides of
  // the unit-high cut square.
  const Points moved = r.surface.positions(r.mesh, r.mesh.mesh.current());
  TriangleSurface deformed_surface = r.surface.surface;
  deformed_surface.vertices = moved;
  const double sheared_area = 4 + 2 * std::sqrt(1.25);  // four unit faces, two stretched by the shear
  EXPECT_NEAR(measure_surface(deformed_surface).area, sheared_area + 2 * 1.0, 1e-12);
}

// Cutting in many small batches gives what one batch gives, in rest and in world space.
TEST(DeformedCut, BatchesGiveTheSameResultAsOneBatch) {
  const TetMesh mesh = make_bcc(Box{}, 0.25);
  Points bent = mesh.rest();
  for (Index n = 0; n < bent.rows(); ++n) bent(n, 2) += 0.2 * std::sin(3 * mesh.rest()(n, 0));
  const TriangleSurface sphere = figures::icosphere(Vec3(0.5, 0.45, 0.55), 0.3, 2);
  for (const bool deformed : {false, true}) {
    Cutter whole(mesh), pieces(mesh);
    if (deformed) {
      whole.cut_deformed(sphere, bent);
    } else {
      whole.cut(sphere);
    }
    for (Index first = 0; first < sphere.num_triangles(); first += 7) {
      TriangleSurface batch;
      batch.vertices = sphere.vertices;
      batch.triangles = sphere.triangles.middleRows(first, std::min<Index>(7, sphere.num_triangles() - first));
      if (deformed) {
        // New nodes start where their sources are: extend the positions as the report says.
        Points now = bent;
        now.conservativeResize(pieces.num_nodes(), 3);
        const std::vector<Index>& parent = pieces.node_parent();
        for (Eigen::Index n = bent.rows(); n < now.rows(); ++n) now.row(n) = bent.row(parent[n]);
        pieces.cut_deformed(batch, now);
      } else {
        pieces.cut(batch);
      }
    }
    const CutResult a = whole.result(), b = pieces.result();
    EXPECT_EQ(testing::check_cut_invariants(mesh, a), "");
    EXPECT_EQ(testing::check_cut_invariants(mesh, b), "");
    expect_same_pieces(a, b, 1e-12 * a.mesh.piece_volumes[0]);
    EXPECT_EQ(a.mesh.mesh.num_tets(), b.mesh.mesh.num_tets());
    EXPECT_EQ(a.mesh.mesh.num_nodes(), b.mesh.mesh.num_nodes());
    EXPECT_NEAR(measure_surface(a.surface.surface).area, measure_surface(b.surface.surface).area, 1e-12);
    ASSERT_EQ(a.mesh.num_pieces(), 2) << (deformed ? "deformed" : "rest");
  }
}

// Volume of {x < a} in the slab z0 <= z <= z1 of the corner tet x, y, z >= 0, x + y + z <= 1. The
// cross-section at height z is the triangle of legs L = 1 - z; its part with x < a has area
// a L - a^2 / 2 while L >= a, and all of L^2 / 2 above z = 1 - a.
double corner_slab_below(double a, double z0, double z1) {
  const auto partial = [a](double z) { return a * (z - z * z / 2) - a * a / 2 * z; };  // primitive while L >= a
  const auto whole = [](double z) { return -std::pow(1 - z, 3) / 6; };                  // primitive of L^2 / 2
  const double split = std::clamp(1 - a, z0, z1);
  return partial(split) - partial(z0) + whole(z1) - whole(split);
}

// The paper's Figure 3: one tet cut progressively, through its earlier cuts, while its pieces
// move between cuts.
TEST(DeformedCut, Figure3OneTetCutWhileItsPiecesMove) {
  const TetMesh tet = figures::figure2_tet();
  Cutter cutter(tet);
  // 1. z = 0.3 splits the tet; its two copies no longer share a node.
  CutBatchReport first = cutter.cut(figures::axis_square(2, 0.3, -1, 2));
  ASSERT_EQ(cutter.num_tets(), 2);
  ASSERT_EQ(cutter.num_nodes(), 8);
  EXPECT_EQ(first.first_new_tet, 1);
  EXPECT_EQ(first.new_tet_source, std::vector<Index>{0});
  EXPECT_EQ(first.new_node_source.size(), 4u);
  // 2. Move the piece above the cut by (0.5, 0, 0); cut in world space by x' = 0.7. Which copy
  //    holds the top is read from the rest volumes.
  const CutResult after_first = cutter.result();
  const Index top = after_first.mesh.tet_material_volume[0] < after_first.mesh.tet_material_volume[1] ? 0 : 1;
  Points now = after_first.mesh.mesh.current();
  for (int k = 0; k < 4; ++k) now.row(cutter.tet_nodes()[top][k]) += Vec3(0.5, 0, 0).transpose();
  const CutBatchReport second = cutter.cut_deformed(figures::axis_square(0, 0.7, -1, 2), now);
  EXPECT_TRUE(second.skipped_inverted.empty());
  // The top piece is cut along rest x = 0.2, the bottom one along x = 0.7.
  const CutResult r = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(tet, r), "");
  std::vector<double> expected = {corner_slab_below(0.7, 0, 0.3), 0, corner_slab_below(0.2, 0.3, 1), 0};
  const double bottom = 1.0 / 6 - std::pow(0.7, 3) / 6;
  const double top_volume = std::pow(0.7, 3) / 6;
  expected[1] = bottom - expected[0];
  expected[3] = top_volume - expected[2];
  std::sort(expected.rbegin(), expected.rend());
  ASSERT_EQ(r.mesh.num_pieces(), 4);
  for (int p = 0; p < 4; ++p) EXPECT_NEAR(r.mesh.piece_volumes[p], expected[p], 1e-14) << p;
  // 3. Turn everything a quarter turn about z, (x, y) -> (-y, x), and cut by y' = 0.1 across all
  //    earlier cuts: that is rest x = 0.1 in the bottom pieces, which it splits further.
  Points turned = r.mesh.mesh.current();
  for (Index n = 0; n < turned.rows(); ++n) turned.row(n) = Vec3(-turned(n, 1), turned(n, 0), turned(n, 2)).transpose();
  cutter.cut_deformed(figures::axis_square(1, 0.1, -3, 3), turned);
  const CutResult third = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(tet, third), "");
  EXPECT_GT(third.mesh.num_pieces(), 4);
}

// A tet inverted in its current positions is not cut; the batch says so.
TEST(DeformedCut, InvertedTetsAreSkippedAndReported) {
  const TetMesh tet = figures::figure2_tet();
  Cutter cutter(tet);
  Points mirrored = tet.rest();
  mirrored.col(0) *= -1;  // a reflection inverts the tet
  const CutBatchReport report = cutter.cut_deformed(figures::axis_square(2, 0.3, -2, 2), mirrored);
  EXPECT_EQ(report.skipped_inverted, std::vector<Index>{0});
  EXPECT_EQ(report.tets_touched, 0);
  EXPECT_EQ(cutter.result().mesh.num_pieces(), 1);
  // A flat tet too.
  Points flat = tet.rest();
  flat(3, 2) = 0;
  EXPECT_EQ(cutter.cut_deformed(figures::axis_square(0, 0.3, -2, 2), flat).skipped_inverted, std::vector<Index>{0});
}

TEST(DeformedCut, WrongPositionsAreRejected) {
  Cutter cutter(figures::figure2_tet());
  EXPECT_THROW(cutter.cut_deformed(figures::axis_square(2, 0.3, -2, 2), Points(3, 3)), Error);
  Points bad = figures::figure2_tet().rest();
  bad(1, 1) = std::nan("");
  EXPECT_THROW(cutter.cut_deformed(figures::axis_square(2, 0.3, -2, 2), bad), Error);
}

// Positions set once, then many world-space batches: copies made by one batch are found by the
// next through the cutter's own record of where new nodes are.
TEST(DeformedCut, PositionsSetOnceServeManyBatches) {
  const TetMesh mesh = make_bcc(Box{}, 0.25);
  Points lifted = mesh.rest();
  lifted.col(2).array() += 0.3 * lifted.col(0).array();
  const TriangleSurface sphere = figures::icosphere(Vec3(0.5, 0.5, 0.6), 0.3, 2);
  Cutter whole(mesh), steps(mesh);
  whole.cut_deformed(sphere, lifted);
  steps.set_current(lifted);
  for (Index first = 0; first < sphere.num_triangles(); first += 5) {
    TriangleSurface batch;
    batch.vertices = sphere.vertices;
    batch.triangles = sphere.triangles.middleRows(first, std::min<Index>(5, sphere.num_triangles() - first));
    steps.cut_deformed(batch);
  }
  const CutResult a = whole.result(), b = steps.result();
  EXPECT_EQ(testing::check_cut_invariants(mesh, b), "");
  expect_same_pieces(a, b, 1e-12);
  EXPECT_EQ(a.mesh.mesh.num_tets(), b.mesh.mesh.num_tets());
  EXPECT_EQ(b.mesh.num_pieces(), 2);
}

// A blade swept along a path makes a strip with no gaps; a blade that goes right through a block
// and across it separates the block, step by step.
TEST(SweptBlade, StripAreaAndAScalpelCut) {
  // A vertical blade from z = -0.5 to z = 1.5, moved along x at y = 0.45 in 10 steps.
  std::vector<BladePose> poses;
  for (int i = 0; i <= 10; ++i) {
    const double x = -0.25 + 1.5 * i / 10.0;
    poses.push_back({Vec3(x, 0.45, -0.5), Vec3(x, 0.45, 1.5)});
  }
  poses.push_back(poses.back());  // the blade stopped: no zero-area triangles come of it
  const TriangleSurface strip = swept_blade(poses);
  EXPECT_EQ(strip.num_triangles(), 20);
  EXPECT_NEAR(measure_surface(strip).area, 1.5 * 2.0, 1e-12);
  // Cutting a block with it, two steps per batch.
  const TetMesh block = make_grid(Box{}, {3, 3, 3}, 6);
  Cutter cutter(block);
  for (std::size_t i = 0; i + 1 < poses.size(); i += 2) {
    const std::size_t end = std::min(poses.size(), i + 3);
    cutter.cut(swept_blade(std::span<const BladePose>(poses.data() + i, end - i)));
    // Until the blade has gone all the way across, the block holds together.
    if (poses[end - 1].a[0] < 1) {
      ASSERT_EQ(cutter.result().mesh.num_pieces(), 1) << i;
    }
  }
  const CutResult r = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(block, r), "");
  ASSERT_EQ(r.mesh.num_pieces(), 2);
  EXPECT_NEAR(r.mesh.piece_volumes[1], 0.45, 1e-13);
}

// A blade crossing a block that twists a little more every frame. Strips placed in world space
// meet there but not in the material: between two frames the material drifts across the blade, so
// consecutive strips pull back to sheets offset sideways, and slivers of material stay uncut.
// Following the blade in the material (its poses mapped to rest space when reached) makes
// consecutive strips share their edge exactly, and the block is cut in two.
TEST(SweptBlade, OnAMovingMeshTheBladeIsFollowedInTheMaterial) {
  const TetMesh block = make_bcc(Box{}, 0.25);
  const auto twist = [](const Vec3& x, double t) -> Vec3 {
    const double angle = 0.5 * t * x[2], u = x[0] - 0.5, v = x[1] - 0.5;
    return {0.5 + std::cos(angle) * u - std::sin(angle) * v, 0.5 + std::sin(angle) * u + std::cos(angle) * v, x[2]};
  };
  const auto blade_at = [](double t) {
    Points ends(2, 3);
    ends << -0.3 + 1.6 * t, 0.45, -0.2, -0.3 + 1.6 * t, 0.45, 1.2;
    return ends;
  };
  for (const bool follow : {false, true}) {
    Cutter cutter(block);
    std::vector<BladePose> poses;
    for (int frame = 0; frame <= 16; ++frame) {
      const double t = frame / 16.0;
      Points now(cutter.num_nodes(), 3);
      for (Index n = 0; n < cutter.num_nodes(); ++n) now.row(n) = twist(block.rest().row(cutter.node_parent()[n]).transpose(), t).transpose();
      cutter.set_current(now);
      const Points pose = follow ? cutter.to_rest(blade_at(t)) : blade_at(t);
      poses.push_back({pose.row(0).transpose(), pose.row(1).transpose()});
      if (frame == 0) continue;
      const TriangleSurface strip = swept_blade(std::span<const BladePose>(poses.data() + frame - 1, 2));
      if (follow) {
        cutter.cut(strip);
      } else {
        cutter.cut_deformed(strip);
      }
    }
    const CutResult r = cutter.result();
    EXPECT_EQ(testing::check_cut_invariants(block, r), "");
    EXPECT_EQ(r.mesh.num_pieces(), follow ? 2 : 1) << (follow ? "followed in the material" : "placed in world space");
  }
}

// to_rest inverts the current motion: a point mapped to rest space, then moved by the copy's motion,
// is where it was; points outside the mesh go through the nearest copy's motion.
TEST(DeformedCut, ToRestInvertsTheMotion) {
  const TetMesh mesh = make_grid(Box{}, {2, 2, 2}, 5);
  Cutter cutter(mesh);
  Points moved = mesh.rest();
  moved.col(0) += 0.3 * mesh.rest().col(1);  // an affine shear: every copy moves alike
  cutter.set_current(moved);
  Points world(3, 3);
  world << 0.5, 0.5, 0.5, 0.9, 0.1, 0.7, 1.6, 0.5, 0.5;  // the last is outside the sheared block
  const Points rest = cutter.to_rest(world);
  for (Index i = 0; i < 3; ++i) {
    EXPECT_NEAR(rest(i, 0) + 0.3 * rest(i, 1), world(i, 0), 1e-12);
    EXPECT_NEAR(rest(i, 1), world(i, 1), 1e-12);
    EXPECT_NEAR(rest(i, 2), world(i, 2), 1e-12);
  }
}

}  // namespace
}  // namespace tetcut
