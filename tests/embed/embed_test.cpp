// Embedding: carving closed and open surfaces out of BCC lattices. Analytic shapes have known
// volumes, areas and piece counts; real scans are checked against the volume they enclose; every
// result passes the shared cut invariants (with the material's volume instead of the block's).

#include <gtest/gtest.h>

#include <tetcut/embed.hpp>
#include <tetcut/error.hpp>
#include <tetcut/figures.hpp>
#include <tetcut/io.hpp>
#include <tetcut/quality.hpp>

#include <cmath>
#include <numeric>
#include <string>

#include "support/cut_invariants.hpp"
#include "support/real_data.hpp"

namespace tetcut {
namespace {

using figures::box_surface;
using figures::concatenate;
using figures::icosphere;

struct Embedded {
  TetMesh lattice;
  EmbedReport report;
  CutResult result;
};

// Embeds and checks the invariants against the volume the surface encloses (or `volume`).
Embedded embed_checked(const TriangleSurface& surface, double spacing, const EmbedOptions& options = {},
                       double volume = std::nan("")) {
  Embedded e;
  e.lattice = embedding_lattice(surface, spacing);
  Cutter cutter = embed(e.lattice, surface, options, &e.report);
  e.result = cutter.result();
  if (std::isnan(volume)) volume = measure_surface(surface).enclosed_volume;
  EXPECT_EQ(testing::check_cut_invariants(e.lattice, e.result, volume), "");
  return e;
}

double total(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

// A surface's triangles turned inside out.
TriangleSurface reversed(TriangleSurface s) {
  s.triangles.col(1).swap(s.triangles.col(2));
  return s;
}

TEST(CheckSurface, CountsWeldsBoundariesAndOrientation) {
  const TriangleSurface box = box_surface(Box{Vec3::Zero(), Vec3::Ones()});
  SurfaceCheck c = check_surface(box);
  EXPECT_EQ(c.vertices, 8);
  EXPECT_TRUE(c.balanced());
  EXPECT_EQ(c.components, 1);
  EXPECT_EQ(c.nonmanifold_edges, 0);
  // As a soup (three vertices per triangle) it welds to the same surface.
  std::vector<testing::Triangle> triangles;
  for (Index t = 0; t < box.num_triangles(); ++t) {
    testing::Triangle tri;
    for (int k = 0; k < 3; ++k) tri[k] = box.vertices.row(box.triangles(t, k)).transpose();
    triangles.push_back(tri);
  }
  c = check_surface(testing::soup(triangles));
  EXPECT_EQ(c.vertices, 8);
  EXPECT_TRUE(c.balanced());
  // One triangle dropped: its three edges are boundary edges.
  TriangleSurface open = box;
  open.triangles.conservativeResize(11, 3);
  c = check_surface(open);
  EXPECT_EQ(c.unbalanced_edges, 3);
  EXPECT_EQ(c.misoriented_edges, 0);
  // One triangle flipped: its edges each run twice the same way.
  TriangleSurface flipped = box;
  std::swap(flipped.triangles(0, 1), flipped.triangles(0, 2));
  c = check_surface(flipped);
  EXPECT_EQ(c.unbalanced_edges, 3);
  EXPECT_EQ(c.misoriented_edges, 3);
  // Two boxes sharing an edge: closed, one non-manifold edge, one component.
  const TriangleSurface two = concatenate(box, box_surface(Box{Vec3(1, 1, 0), Vec3(2, 2, 1)}));
  c = check_surface(two);
  EXPECT_TRUE(c.balanced());
  EXPECT_EQ(c.nonmanifold_edges, 1);
  EXPECT_EQ(c.components, 1);
  // A sliver with collinear corners counts as degenerate.
  TriangleSurface sliver;
  sliver.vertices.resize(3, 3);
  sliver.vertices << 0, 0, 0, 1, 1, 1, 2, 2, 2;
  sliver.triangles.resize(1, 3);
  sliver.triangles << 0, 1, 2;
  EXPECT_EQ(check_surface(sliver).degenerate_triangles, 1);
}

// Scenes, the CLI and Python name the choices of material alike, through one table.
TEST(Embed, KeepMaterialNamesRoundTrip) {
  for (const KeepMaterial keep : {KeepMaterial::kInside, KeepMaterial::kLargest, KeepMaterial::kPoint}) {
    EXPECT_EQ(keep_material_from_name(keep_material_name(keep)), keep);
  }
  EXPECT_EQ(keep_material_name(KeepMaterial::kLargest), "largest");
  EXPECT_FALSE(keep_material_from_name("outside").has_value());
}

TEST(CheckSurface, RejectsNanAndMissingVertices) {
  TriangleSurface s = box_surface(Box{Vec3::Zero(), Vec3::Ones()});
  s.vertices(3, 1) = std::nan("");
  try {
    check_surface(s);
    FAIL() << "a NaN was accepted";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("not finite"), std::string::npos) << e.message();
  }
  s = box_surface(Box{Vec3::Zero(), Vec3::Ones()});
  s.triangles(5, 2) = 8;
  EXPECT_THROW(check_surface(s), Error);
}

TEST(Embed, SphereKeepsItsInsideOnly) {
  const TriangleSurface sphere = icosphere(Vec3(0.1, -0.2, 0.3), 0.5, 3);
  const Embedded e = embed_checked(sphere, 0.13);
  EXPECT_EQ(e.result.mesh.num_pieces(), 1);
  EXPECT_LT(e.report.tets_with_material, e.report.tets_in);
  // Every copy holds material, and the surface is the sphere (split at tet faces): its area.
  const SurfaceStats stats = measure_surface(e.result.surface.surface);
  EXPECT_NEAR(stats.area, measure_surface(sphere).area, 1e-9 * stats.area);
  // Every surface triangle lies on the input surface (no lattice face is exposed).
  for (const std::int64_t source : e.result.surface.triangle_source) EXPECT_GE(source, 0);
  // A convex shape much larger than the tets holds one part per tet: one copy each.
  EXPECT_EQ(e.report.tets_duplicated, 0);
  EXPECT_EQ(e.result.mesh.mesh.num_tets(), e.report.tets_with_material);
}

TEST(Embed, InsideOutSurfaceGivesTheSameMaterial) {
  // Winding -1 inside is still inside: orientation does not decide what is material.
  const TriangleSurface sphere = icosphere(Vec3(0, 0, 0), 1, 2);
  const Embedded a = embed_checked(sphere, 0.3);
  const Embedded b = embed_checked(reversed(sphere), 0.3, {}, measure_surface(sphere).enclosed_volume);
  EXPECT_EQ(a.result.mesh.mesh.num_tets(), b.result.mesh.mesh.num_tets());
  EXPECT_NEAR(total(a.result.mesh.piece_volumes), total(b.result.mesh.piece_volumes), 1e-12);
}

TEST(Embed, DisjointComponentsArePieces) {
  const TriangleSurface three =
      concatenate(concatenate(icosphere(Vec3(0, 0, 0), 0.4, 2), icosphere(Vec3(1.1, 0, 0), 0.3, 2)),
                  box_surface(Box{Vec3(-0.3, 0.7, -0.2), Vec3(1.3, 1.0, 0.25)}));
  ASSERT_EQ(check_surface(three).components, 3);
  const Embedded e = embed_checked(three, 0.1);
  EXPECT_EQ(e.result.mesh.num_pieces(), 3);
}

TEST(Embed, HollowShellIsOnePieceWithACavity) {
  // An outer sphere and an inner one turned inside out: material between them only.
  const TriangleSurface outer = icosphere(Vec3(0, 0, 0), 1, 3), inner = reversed(icosphere(Vec3(0.05, 0, 0), 0.6, 3));
  const TriangleSurface shell = concatenate(outer, inner);
  const Embedded e = embed_checked(shell, 0.17);
  EXPECT_EQ(e.result.mesh.num_pieces(), 1);
  EXPECT_NEAR(total(e.result.mesh.piece_volumes),
              measure_surface(outer).enclosed_volume + measure_surface(inner).enclosed_volume, 1e-12);
}

TEST(Embed, LipsWithinOneTetBecomeTwoPiecesWithDuplicatedTets) {
  // Two slabs whose gap (0.02) is far thinner than the lattice spacing (0.25): the tets across
  // the gap hold material of both, and each gets one copy per slab.
  const TriangleSurface lips = concatenate(box_surface(Box{Vec3(0, 0, 0.01), Vec3(1, 1, 0.4)}),
                                           box_surface(Box{Vec3(0, 0, -0.4), Vec3(1, 1, -0.01)}));
  const Embedded e = embed_checked(lips, 0.25);
  ASSERT_EQ(e.result.mesh.num_pieces(), 2);
  EXPECT_GT(e.report.tets_duplicated, 0);
  EXPECT_NEAR(e.result.mesh.piece_volumes[0], 0.39, 1e-12);
  EXPECT_NEAR(e.result.mesh.piece_volumes[1], 0.39, 1e-12);
  // The two pieces share no node.
  std::vector<Index> piece_of_node(static_cast<std::size_t>(e.result.mesh.mesh.num_nodes()), -1);
  for (Index c = 0; c < e.result.mesh.mesh.num_tets(); ++c) {
    for (int k = 0; k < 4; ++k) {
      Index& p = piece_of_node[e.result.mesh.mesh.tets()(c, k)];
      if (p < 0) p = e.result.mesh.tet_piece[c];
      EXPECT_EQ(p, e.result.mesh.tet_piece[c]) << "a node is shared by both lips";
    }
  }
}

TEST(Embed, SelfIntersectingSurfaceEmbedsTheUnion) {
  // Two overlapping boxes given as one surface that passes through itself.
  const Box a{Vec3(0, 0, 0), Vec3(1, 1, 1)}, b{Vec3(0.5, 0.3, 0.2), Vec3(1.6, 0.8, 0.7)};
  const TriangleSurface both = concatenate(box_surface(a), box_surface(b));
  const double overlap = 0.5 * 0.5 * 0.5;
  const double union_volume = 1 + 1.1 * 0.5 * 0.5 - overlap;
  const Embedded e = embed_checked(both, 0.15, {}, union_volume);
  EXPECT_EQ(e.result.mesh.num_pieces(), 1);
  EXPECT_GT(e.report.covered_facets_joined, 0);
  EXPECT_NEAR(total(e.result.mesh.piece_volumes), union_volume, 1e-12);
}

TEST(Embed, SurfaceOnLatticePlanesAndNodes) {
  // A box whose faces lie on lattice planes and whose corners are lattice nodes: every cut
  // polygon lies on tet faces.
  const double h = 0.25;
  const TriangleSurface box = box_surface(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)});
  const Embedded e = embed_checked(box, h);
  EXPECT_EQ(e.result.mesh.num_pieces(), 1);
  EXPECT_NEAR(total(e.result.mesh.piece_volumes), 1.0, 1e-12);
}

TEST(Embed, OpenSurfaceNeedsAChoiceOfMaterial) {
  TriangleSurface open = icosphere(Vec3(0, 0, 0), 1, 2);
  open.triangles.conservativeResize(open.num_triangles() - 4, 3);
  try {
    embed(embedding_lattice(open, 0.3), open);
    FAIL() << "an open surface was embedded as closed";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInvalidInput);
    EXPECT_NE(e.message().find("not closed"), std::string::npos) << e.message();
    EXPECT_NE(e.message().find(std::to_string(check_surface(open).unbalanced_edges) + " edges"), std::string::npos)
        << e.message();
  }
}

TEST(Embed, OpenSheetKeepsTheLargestPieceOrThePieceAtAPoint) {
  // A sheet z = 0.3 across a block [0, 1]^3 (given as the mesh): the block falls in two.
  const TetMesh block = make_bcc(Box{Vec3::Zero(), Vec3::Ones()}, 0.2);
  const TriangleSurface sheet = figures::axis_square(2, 0.3, -0.5, 1.5);
  const double block_volume = measure_quality(block).volume;
  const double below = 0.3 * block_volume;  // the lattice fills its box exactly

  EmbedOptions largest;
  largest.keep = KeepMaterial::kLargest;
  Cutter a = embed(block, sheet, largest);
  const CutResult ra = a.result();
  EXPECT_EQ(testing::check_cut_invariants(block, ra, block_volume - below), "");
  EXPECT_EQ(ra.mesh.num_pieces(), 1);

  EmbedOptions point;
  point.keep = KeepMaterial::kPoint;
  point.point = Vec3(0.5, 0.5, 0.1);
  Cutter b = embed(block, sheet, point);
  const CutResult rb = b.result();
  EXPECT_EQ(testing::check_cut_invariants(block, rb, below), "");
  EXPECT_NEAR(total(rb.mesh.piece_volumes), below, 1e-12);

  // On the sheet, or outside the block: a clear error.
  point.point = Vec3(0.5, 0.5, 0.3);
  EXPECT_THROW(embed(block, sheet, point), Error);
  point.point = Vec3(0.5, 0.5, 3);
  EXPECT_THROW(embed(block, sheet, point), Error);
}

TEST(Embed, PartialSheetInsideTheKeptPieceStaysACut) {
  // A closed box with a flap (an open square) inside it: in kLargest mode the flap stays a cut
  // through the kept material; the closed box has no inside mode here (the flap is open).
  const TetMesh block = make_bcc(Box{Vec3::Zero(), Vec3::Ones()}, 0.2);
  const TriangleSurface flap = figures::axis_square(2, 0.5, 0.2, 0.7);
  EmbedOptions largest;
  largest.keep = KeepMaterial::kLargest;
  Cutter cutter = embed(block, flap, largest);
  const CutResult r = cutter.result();
  EXPECT_EQ(r.mesh.num_pieces(), 1);
  EXPECT_EQ(testing::check_cut_invariants(block, r, measure_quality(block).volume), "");
  // Both sides of the flap are surface: twice its area plus the block's skin.
  EXPECT_NEAR(measure_surface(r.surface.surface).area, 6 + 2 * 0.25, 1e-12);
}

TEST(Embed, NothingInsideTheMeshIsAnError) {
  const TetMesh block = make_bcc(Box{Vec3::Zero(), Vec3::Ones()}, 0.25);
  EXPECT_THROW(embed(block, icosphere(Vec3(5, 5, 5), 0.5, 1)), Error);
}

TEST(Embed, CuttingTheEmbeddedModelFurther) {
  // A lip-like incision: a plane through the middle of an embedded sphere splits it in two, and
  // the volume stays the sphere's.
  const TriangleSurface sphere = icosphere(Vec3(0, 0, 0), 1, 3);
  const TetMesh lattice = embedding_lattice(sphere, 0.2);
  Cutter cutter = embed(lattice, sphere);
  const Index copies_before = cutter.num_tets();
  const CutBatchReport batch = cutter.cut(figures::axis_square(1, 0.013, -2, 2));
  EXPECT_GT(batch.tets_touched, 0);
  EXPECT_GT(cutter.num_tets(), copies_before);
  const CutResult r = cutter.result();
  const double volume = measure_surface(sphere).enclosed_volume;
  EXPECT_EQ(testing::check_cut_invariants(lattice, r, volume), "");
  ASSERT_EQ(r.mesh.num_pieces(), 2);
  EXPECT_NEAR(total(r.mesh.piece_volumes), volume, 1e-12);
  // The incision's two sides join the sphere's surface.
  const double disc = measure_surface(r.surface.surface).area - measure_surface(sphere).area;
  EXPECT_NEAR(disc, 2 * M_PI * (1 - 0.013 * 0.013), 0.1);  // the icosphere's section is a polygon
  EXPECT_GT(disc, 0);
}

using testing::scan;

class EmbedScan : public ::testing::TestWithParam<const char*> {};

TEST_P(EmbedScan, EnclosedVolumeAndAreaAreKept) {
  const TriangleSurface surface = scan(GetParam());
  const SurfaceCheck check = check_surface(surface);
  ASSERT_TRUE(check.balanced());
  const SurfaceStats stats = measure_surface(surface);
  Embedded e;
  e.lattice = embedding_lattice(surface, spacing_for_cubes(surface, 12));
  Cutter cutter = embed(e.lattice, surface, {}, &e.report);
  e.result = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(e.lattice, e.result, total(e.result.mesh.piece_volumes)), "");
  EXPECT_NEAR(total(e.result.mesh.piece_volumes), stats.enclosed_volume, 1e-9 * stats.enclosed_volume);
  EXPECT_EQ(e.result.mesh.num_pieces(), check.components);
  EXPECT_NEAR(measure_surface(e.result.surface.surface).area, stats.area, 1e-9 * stats.area);
}

INSTANTIATE_TEST_SUITE_P(Closed, EmbedScan, ::testing::Values("femur", "knot1"));

TEST(EmbedScanOpen, FaceScanIsRefusedAsClosedAndKeptAsACut) {
  // Nefertiti is an open face. As a closed embedding it is refused. Kept as the largest piece of a
  // block around it, its boundary stays inside the block, so the block does not fall apart: the
  // face is a cut through it, both sides exposed.
  const TriangleSurface face = scan("nefertiti");
  const SurfaceCheck check = check_surface(face);
  ASSERT_FALSE(check.balanced());
  const TetMesh lattice = embedding_lattice(face, spacing_for_cubes(face, 8));
  EXPECT_THROW(embed(lattice, face), Error);
  EmbedOptions largest;
  largest.keep = KeepMaterial::kLargest;
  Cutter cutter = embed(lattice, face, largest);
  const CutResult r = cutter.result();
  EXPECT_EQ(r.mesh.num_pieces(), 1);
  const double block = measure_quality(lattice).volume;
  EXPECT_EQ(testing::check_cut_invariants(lattice, r, block), "");
  const Vec3 size = lattice.rest().colwise().maxCoeff() - lattice.rest().colwise().minCoeff();
  const double skin = 2 * (size[0] * size[1] + size[1] * size[2] + size[2] * size[0]);
  const double area = measure_surface(face).area;
  EXPECT_NEAR(measure_surface(r.surface.surface).area, skin + 2 * area, 1e-9 * skin);
}

}  // namespace
}  // namespace tetcut
