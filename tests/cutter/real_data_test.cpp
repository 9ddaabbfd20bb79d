// Cutting BCC lattices by real scanned surfaces (Debian's libcgal-demo): a closed scan cuts the
// block into its inside and outside, with volumes matching the scan's enclosed volume; an open
// scan leaves one piece. Every result passes the shared invariants.

#include <gtest/gtest.h>

#include <tetcut/cutter.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>
#include <tetcut/quality.hpp>

#include <string>

#include "support/cut_invariants.hpp"
#include "support/real_data.hpp"

namespace tetcut {
namespace {

using testing::scan;

// A BCC lattice over the scan's bounding box, grown by a margin, with about `cells` cubes along
// the longest side.
TetMesh block_around(const TriangleSurface& surface, double cells) {
  const SurfaceStats s = measure_surface(surface);
  const Vec3 extent = s.bbox_max - s.bbox_min;
  const double margin = 0.1 * extent.maxCoeff();
  return make_bcc(Box{s.bbox_min - Vec3::Constant(margin), s.bbox_max + Vec3::Constant(margin)},
                  (extent.maxCoeff() + 2 * margin) / cells);
}

CutResult cut(const TetMesh& mesh, const TriangleSurface& surface) {
  Cutter cutter(mesh);
  const CutBatchReport report = cutter.cut(surface);
  EXPECT_TRUE(report.degenerate.empty());
  CutResult result = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(mesh, result), "");
  return result;
}

double mesh_volume(const TetMesh& mesh) { return measure_quality(mesh).volume; }

class ClosedScan : public ::testing::TestWithParam<const char*> {};

TEST_P(ClosedScan, CutsTheBlockIntoInsideAndOutside) {
  const TriangleSurface surface = scan(GetParam());
  const SurfaceStats stats = measure_surface(surface);
  ASSERT_TRUE(stats.two_manifold);
  const TetMesh mesh = block_around(surface, 16);
  const CutResult r = cut(mesh, surface);
  ASSERT_EQ(r.mesh.num_pieces(), 2);
  const double inside = r.mesh.piece_volumes[1], outside = r.mesh.piece_volumes[0];
  EXPECT_NEAR(inside, stats.enclosed_volume, 1e-9 * stats.enclosed_volume);
  EXPECT_NEAR(inside + outside, mesh_volume(mesh), 1e-12 * mesh_volume(mesh));
  // The material surface is the scan twice (inside and outside) plus the block's skin.
  const SurfaceStats material = measure_surface(r.surface.surface);
  const Vec3 box = mesh.rest().colwise().maxCoeff() - mesh.rest().colwise().minCoeff();
  const double skin = 2 * (box[0] * box[1] + box[1] * box[2] + box[2] * box[0]);
  EXPECT_NEAR(material.area, 2 * stats.area + skin, 1e-9 * material.area);
}

INSTANTIATE_TEST_SUITE_P(Scans, ClosedScan, ::testing::Values("femur", "knot1"));

TEST(OpenScan, LeavesOnePieceButBothSidesOnTheSurface) {
  // The lion head is open at the neck, so inside and outside stay connected through the hole.
  const TriangleSurface surface = scan("lion-head");
  const SurfaceStats stats = measure_surface(surface);
  ASSERT_FALSE(stats.two_manifold);
  const TetMesh mesh = block_around(surface, 12);
  const CutResult r = cut(mesh, surface);
  EXPECT_EQ(r.mesh.num_pieces(), 1);
  const Vec3 box = mesh.rest().colwise().maxCoeff() - mesh.rest().colwise().minCoeff();
  const double skin = 2 * (box[0] * box[1] + box[1] * box[2] + box[2] * box[0]);
  EXPECT_NEAR(measure_surface(r.surface.surface).area, 2 * stats.area + skin, 1e-9 * (2 * stats.area + skin));
}

}  // namespace
}  // namespace tetcut
