// Cutting whole meshes: exact answers for plane arrangements, the paper's figures, and every
// degenerate configuration the issue names; each result also passes the shared invariants.

#include <gtest/gtest.h>

#include <tetcut/cutter.hpp>
#include <tetcut/error.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/quality.hpp>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "support/cut_invariants.hpp"

namespace tetcut {
namespace {

using testing::Triangle;


// The plane {x[axis] = value} over [-1, 2]^2, as two triangles.
std::vector<Triangle> plane(int axis, double value) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  Vec3 c[4];
  for (int k = 0; k < 4; ++k) {
    c[k][axis] = value;
    c[k][u] = (k == 1 || k == 2) ? 2 : -1;
    c[k][v] = (k >= 2) ? 2 : -1;
  }
  return {{c[0], c[1], c[2]}, {c[0], c[2], c[3]}};
}

std::vector<Triangle> operator+(std::vector<Triangle> a, const std::vector<Triangle>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

CutResult cut(const TetMesh& mesh, const std::vector<std::vector<Triangle>>& batches) {
  Cutter cutter(mesh);
  for (const auto& batch : batches) cutter.cut(testing::soup(batch));
  CutResult result = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(mesh, result), "");
  return result;
}

void expect_pieces(const CutResult& r, std::vector<double> expected, double tolerance = 1e-13) {
  std::sort(expected.rbegin(), expected.rend());
  ASSERT_EQ(r.mesh.num_pieces(), static_cast<Index>(expected.size()));
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(r.mesh.piece_volumes[i], expected[i], tolerance) << i;
}

const TetMesh& cube320() {
  static const TetMesh mesh = make_grid(Box{}, {4, 4, 4}, 5);
  return mesh;
}

TEST(Cutter, AMissedMeshIsUnchanged) {
  const TetMesh& mesh = cube320();
  const CutResult r = cut(mesh, {{{Vec3(5, 5, 5), Vec3(6, 5, 5), Vec3(5, 6, 5)}}});
  EXPECT_EQ(r.mesh.mesh.num_tets(), mesh.num_tets());
  EXPECT_EQ(r.mesh.mesh.num_nodes(), mesh.num_nodes());
  EXPECT_EQ(r.mesh.mesh.tets(), mesh.tets());
  expect_pieces(r, {1.0});
  const SurfaceStats s = measure_surface(r.surface.surface);
  EXPECT_TRUE(s.two_manifold);
  EXPECT_NEAR(s.area, 6.0, 1e-12);
}

TEST(Cutter, CubeCutByThreeAxisPlanesGivesEightBoxes) {
  const double x = 0.3, y = 0.55, z = 0.8;
  const CutResult r = cut(cube320(), {plane(0, x) + plane(1, y) + plane(2, z)});
  std::vector<double> boxes;
  for (const double a : {x, 1 - x}) {
    for (const double b : {y, 1 - y}) {
      for (const double c : {z, 1 - z}) boxes.push_back(a * b * c);
    }
  }
  expect_pieces(r, boxes);
  // Surface: the cube's six faces plus both sides of three unit squares.
  EXPECT_NEAR(measure_surface(r.surface.surface).area, 6.0 + 2 * 3, 1e-12);
}

TEST(Cutter, CutAlongMeshFacesSplitsNodesButNoTet) {
  // x = 0.5 runs along grid faces: every tet lies on one side, so no tet is copied, and the 25
  // nodes on the plane are duplicated.
  const CutResult r = cut(cube320(), {plane(0, 0.5)});
  expect_pieces(r, {0.5, 0.5});
  EXPECT_EQ(r.mesh.mesh.num_tets(), 320);
  EXPECT_EQ(r.mesh.mesh.num_nodes(), 125 + 25);
}

TEST(Cutter, CutsThroughMeshVerticesAndAlongMeshEdges) {
  // x + y + z = 1.5 passes through grid nodes and along face diagonals; x = y along cube diagonals.
  const TetMesh mesh = make_grid(Box{}, {2, 2, 2}, 5);
  const std::vector<Triangle> diagonal = {{Vec3(1.5, 0, 0), Vec3(0, 1.5, 0), Vec3(0, 0, 1.5)},
                                          {Vec3(3, -1.5, 0), Vec3(-1.5, 3, 0), Vec3(0, 0, 1.5)},
                                          {Vec3(3, 0, -1.5), Vec3(0, 3, -1.5), Vec3(-1.5, -1.5, 4.5)}};
  expect_pieces(cut(mesh, {diagonal}), {0.5, 0.5});
  expect_pieces(cut(mesh, {{{Vec3(-1, -1, -1), Vec3(2, 2, -1), Vec3(0.5, 0.5, 3)}}}), {0.5, 0.5});
  // Only touching a node or running along a boundary edge changes nothing.
  expect_pieces(cut(mesh, {{{Vec3(1, 1, 1), Vec3(2, 1, 2), Vec3(1, 2, 2)}}}), {1.0});
  expect_pieces(cut(mesh, {{{Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(-1, -1, 0.5)}}}), {1.0});
}

TEST(Cutter, CoplanarOverlappingAndRepeatedCuts) {
  const TetMesh mesh = make_grid(Box{}, {2, 2, 2}, 6);
  const std::vector<Triangle> half = plane(2, 0.4);
  // Repeated, reversed, and overlapping triangles: x + y <= 1.2 and x + y >= 0.6 only together
  // cover the section, and a small one overlaps both.
  const std::vector<Triangle> overlapping = {{Vec3(-1, -1, 0.4), Vec3(2.2, -1, 0.4), Vec3(-1, 2.2, 0.4)},
                                             {Vec3(2, 2, 0.4), Vec3(-1.4, 2, 0.4), Vec3(2, -1.4, 0.4)},
                                             {Vec3(0.2, 0.2, 0.4), Vec3(0.8, 0.2, 0.4), Vec3(0.2, 0.8, 0.4)}};
  expect_pieces(cut(mesh, {half + half + std::vector<Triangle>{{half[0][0], half[0][2], half[0][1]}}}), {0.4, 0.6});
  expect_pieces(cut(mesh, {overlapping}), {0.4, 0.6});
  // Without the second triangle a strip stays uncut: one piece.
  expect_pieces(cut(mesh, {{overlapping[0], overlapping[2]}}), {1.0});
}

TEST(Cutter, ACornerLyingExactlyOnAnotherCut) {
  const TetMesh mesh = make_grid(Box{}, {2, 2, 2}, 5);
  // z = 0.5 cuts through; a second triangle in x = 0.3 hangs from z = 2 down to one corner
  // exactly on the first cut, cutting the top half only partly: two pieces.
  const std::vector<Triangle> both = plane(2, 0.5) + std::vector<Triangle>{{Vec3(0.3, -1, 2), Vec3(0.3, 2, 2), Vec3(0.3, 0.5, 0.5)}};
  const CutResult r = cut(mesh, {both});
  expect_pieces(r, {0.5, 0.5});
  // Its corner exactly on the first cut's edge (the diagonal of the two triangles of z = 0.5).
  expect_pieces(cut(mesh, {plane(2, 0.5) + std::vector<Triangle>{{Vec3(0.3, -1, 2), Vec3(0.3, 2, 2), Vec3(0.3, 0.7, 0.5)}}}),
                {0.5, 0.5});
}

TEST(Cutter, ZeroAreaTrianglesAreSkippedAndReported) {
  const TetMesh mesh = make_grid(Box{}, {2, 2, 2}, 5);
  Cutter cutter(mesh);
  const CutBatchReport report = cutter.cut(testing::soup({{Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(0.5, 0.5, 0.5)},
                                                 {Vec3(0.2, 0.3, 0.1), Vec3(0.2, 0.3, 0.1), Vec3(0.9, 0.1, 0.5)},
                                                 {Vec3(-1, 0.5, 0.3), Vec3(2, 0.5, 0.3), Vec3(0.5, 0.5, 3)}}));
  EXPECT_EQ(report.degenerate, (std::vector<Index>{0, 1}));
  EXPECT_GT(report.tets_touched, 0);
  const CutResult r = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(mesh, r), "");
  EXPECT_EQ(r.mesh.num_pieces(), 1);  // the third triangle cuts only part of the cube
}

TEST(Cutter, NonFiniteCornersAreRejectedWithoutChangingAnything) {
  Cutter cutter(make_grid(Box{}, {1, 1, 1}, 5));
  TriangleSurface bad = testing::soup(plane(2, 0.5));
  bad.vertices(4, 1) = std::nan("");
  EXPECT_THROW(cutter.cut(bad), Error);
  EXPECT_EQ(cutter.result().mesh.num_pieces(), 1);
}

TEST(Cutter, ClosedSurfaceWhollyInsideOneTetFloats) {
  const TetMesh mesh = make_grid(Box{}, {1, 1, 1}, 5);
  // The central tet of the 5-tet cube has corners (1,0,0), (0,1,0), (0,0,1), (1,1,1); its centroid is the cube's centre.
  const Vec3 o(0.5, 0.5, 0.5);
  const double r = 0.05;
  const Vec3 px = o + Vec3(r, 0, 0), nx = o - Vec3(r, 0, 0), py = o + Vec3(0, r, 0), ny = o - Vec3(0, r, 0),
             pz = o + Vec3(0, 0, r), nz = o - Vec3(0, 0, r);
  const std::vector<Triangle> octahedron = {{px, py, pz}, {py, nx, pz}, {nx, ny, pz}, {ny, px, pz},
                                            {py, px, nz}, {nx, py, nz}, {ny, nx, nz}, {px, ny, nz}};
  const CutResult result = cut(mesh, {octahedron});
  const double inner = 4.0 / 3.0 * r * r * r;
  expect_pieces(result, {1 - inner, inner});
  EXPECT_EQ(result.mesh.mesh.num_tets(), 6);  // the central tet holds two components
  EXPECT_EQ(result.mesh.mesh.num_nodes(), 8 + 4);
}

TEST(Cutter, PartialCutKeepsOnePieceAndHasBothSidesOnTheSurface) {
  // A square slit x in [-1, 0.6], y in [-1, 2] at z = 0.4 (between grid planes): it enters the
  // cube but does not cross it.
  const std::vector<Triangle> slit = {{Vec3(-1, -1, 0.4), Vec3(0.6, -1, 0.4), Vec3(0.6, 2, 0.4)},
                                      {Vec3(-1, -1, 0.4), Vec3(0.6, 2, 0.4), Vec3(-1, 2, 0.4)}};
  const CutResult r = cut(cube320(), {slit});
  expect_pieces(r, {1.0});
  EXPECT_NEAR(measure_surface(r.surface.surface).area, 6.0 + 2 * 0.6, 1e-12);
  // Tets the slit crosses completely hold two components each and are copied, though the piece
  // stays whole: the material around the slit's end joins them.
  EXPECT_GT(r.mesh.mesh.num_tets(), 320);
}

TEST(Cutter, TCutGivesThreePieces) {
  // x = 0.5 through the cube, and y = 0.25 only where x > 0.5, ending exactly on the first cut.
  const std::vector<Triangle> stem = {{Vec3(0.5, 0.25, -1), Vec3(2, 0.25, -1), Vec3(2, 0.25, 2)},
                                      {Vec3(0.5, 0.25, -1), Vec3(2, 0.25, 2), Vec3(0.5, 0.25, 2)}};
  const CutResult r = cut(cube320(), {plane(0, 0.5) + stem});
  expect_pieces(r, {0.5, 0.375, 0.125});
  // The same with the stem first, and in two batches (a cut of a cut).
  expect_pieces(cut(cube320(), {stem + plane(0, 0.5)}), {0.5, 0.375, 0.125});
  expect_pieces(cut(cube320(), {plane(0, 0.5), stem}), {0.5, 0.375, 0.125});
}

// Building the result runs in parallel; it must not depend on how the work is scheduled.
TEST(Cutter, ResultIsTheSameOnOneThreadAndOnAll) {
  const TetMesh mesh = make_bcc(Box{}, 0.2);
  Cutter cutter(mesh);
  cutter.cut(figures::icosphere(Vec3(0.45, 0.5, 0.55), 0.3, 2));
  CutResult serial;
  {
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    serial = cutter.result();
  }
  const CutResult parallel = cutter.result();
  EXPECT_EQ(serial.mesh.mesh.tets(), parallel.mesh.mesh.tets());
  EXPECT_EQ(serial.mesh.tet_piece, parallel.mesh.tet_piece);
  EXPECT_EQ(serial.mesh.tet_material_volume, parallel.mesh.tet_material_volume);
  EXPECT_EQ(serial.surface.surface.triangles, parallel.surface.surface.triangles);
  EXPECT_EQ(serial.surface.surface.vertices, parallel.surface.surface.vertices);
  EXPECT_EQ(serial.surface.vertex_weights, parallel.surface.vertex_weights);
}

// The paper's Figure 4: 16 + 16 planes slice the 320-tet cube into 17 x 17 sticks.
TEST(Cutter, Figure4ThirtyTwoPlanesGive289Sticks) {
  const TetMesh mesh = figures::figure4_cube();
  Cutter cutter(mesh);
  cutter.cut(figures::figure4_planes());
  const CutResult r = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(mesh, r), "");
  std::vector<double> at = {0};
  for (int i = 1; i <= 16; ++i) at.push_back(i / 17.0);
  at.push_back(1);
  std::vector<double> sticks;
  for (int i = 0; i < 17; ++i) {
    for (int j = 0; j < 17; ++j) sticks.push_back((at[i + 1] - at[i]) * (at[j + 1] - at[j]));
  }
  expect_pieces(r, sticks, 1e-15);
  // Surface: the cube and both sides of 32 unit squares.
  EXPECT_NEAR(measure_surface(r.surface.surface).area, 6 + 2 * 32, 1e-10);
  ::testing::Test::RecordProperty("figure4_tets", r.mesh.mesh.num_tets());
}

// The paper's Figure 2: one tet cut into more than a thousand pieces by 50 random triangles.
TEST(Cutter, Figure2OneTetIntoMoreThanAThousandPieces) {
  const TetMesh mesh = figures::figure2_tet();
  Cutter cutter(mesh);
  cutter.cut(figures::figure2_triangles());
  const CutResult r = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(mesh, r), "");
  EXPECT_GT(r.mesh.num_pieces(), 1000);
  EXPECT_EQ(r.mesh.mesh.num_tets(), r.mesh.num_pieces());  // one tet: every piece is one copy
  ::testing::Test::RecordProperty("figure2_pieces", r.mesh.num_pieces());
}

}  // namespace
}  // namespace tetcut
