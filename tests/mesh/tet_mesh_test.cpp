#include <tetcut/error.hpp>
#include <tetcut/quality.hpp>
#include <tetcut/surface.hpp>
#include <tetcut/tet_mesh.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

namespace tetcut {
namespace {

using ::testing::HasSubstr;

// Two tets sharing the face (1, 2, 3).
TetMesh two_tets() {
  Points p(5, 3);
  p << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  Tets t(2, 4);
  t << 0, 1, 2, 3, 4, 1, 3, 2;
  return TetMesh(p, t, "two.mesh");
}

std::string error_of(const Points& p, const Tets& t, std::vector<std::int64_t> lines = {}) {
  try {
    TetMesh mesh(p, t, "bad.mesh", lines);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInvalidInput);
    return e.what();
  }
  return "no error";
}

TEST(TetMesh, AdjacencyOfTwoTets) {
  const TetMesh mesh = two_tets();
  const TetAdjacency& adj = mesh.adjacency();
  EXPECT_EQ(adj.num_faces(), 7);
  EXPECT_EQ(adj.num_boundary_faces(), 6);
  EXPECT_EQ(adj.num_overshared_faces(), 0);
  EXPECT_EQ(adj.num_edges(), 9);
  EXPECT_EQ(adj.neighbor(0, 0), 1);  // face opposite node 0 is (1, 2, 3)
  EXPECT_EQ(adj.neighbor(1, 0), 0);
  EXPECT_EQ(adj.neighbor(0, 1), -1);
  EXPECT_EQ(mesh.current(), mesh.rest());
}

TEST(TetMesh, BoundarySurfaceIsClosedAndOutward) {
  const TetMesh mesh = two_tets();
  const TriangleSurface surface = boundary_surface(mesh);
  EXPECT_EQ(surface.num_triangles(), 6);
  const SurfaceStats s = measure_surface(surface);
  EXPECT_TRUE(s.two_manifold);
  // Outward orientation makes the enclosed volume positive and equal to the mesh volume.
  EXPECT_DOUBLE_EQ(s.enclosed_volume, measure_quality(mesh).volume);
  EXPECT_GT(s.enclosed_volume, 0);
}

TEST(TetMesh, BoundarySurfaceSaysWhichTetFaceEachTriangleIs) {
  const TetMesh mesh = two_tets();
  std::vector<BoundaryFace> faces;
  const TriangleSurface surface = boundary_surface(mesh, &faces);
  ASSERT_EQ(faces.size(), static_cast<std::size_t>(surface.num_triangles()));
  std::vector<Index> new_id(static_cast<std::size_t>(mesh.num_nodes()), -1);
  for (Index t = 0; t < surface.num_triangles(); ++t) {
    const BoundaryFace& from = faces[t];
    // The named face is on the boundary, and the triangle is that face's corners in its order.
    EXPECT_EQ(mesh.adjacency().tets_of_face(mesh.adjacency().tet_faces(from.tet, from.local_face)).size(), 1u);
    for (int k = 0; k < 3; ++k) {
      const Index node = mesh.tets()(from.tet, kTetFaces[from.local_face][k]);
      EXPECT_EQ(surface.vertices.row(surface.triangles(t, k)), mesh.rest().row(node));
      Index& id = new_id[node];
      if (id < 0) id = surface.triangles(t, k);
      EXPECT_EQ(surface.triangles(t, k), id);  // one surface vertex per node
    }
  }
  // Both tets have three boundary faces; the face they share (local face 0 of each) is not one.
  for (const BoundaryFace& from : faces) EXPECT_NE(from.local_face, 0);
}

TEST(TetMesh, RejectsInvertedTetNamingElementAndLine) {
  Points p(4, 3);
  p << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Tets t(2, 4);
  t << 0, 1, 2, 3, 0, 2, 1, 3;
  const std::string message = error_of(p, t, {7, 8});
  EXPECT_THAT(message, HasSubstr("bad.mesh:8"));
  EXPECT_THAT(message, HasSubstr("tetrahedron 2"));
  EXPECT_THAT(message, HasSubstr("inverted"));
}

TEST(TetMesh, RejectsZeroVolumeTetExactly) {
  // Coplanar in exact arithmetic although the naive double determinant is not zero.
  Points p(4, 3);
  p << 0.1, 0.2, 0.3, 1.1, 0.7, 0.3, 0.3, 1.9, 0.3, 0.7, 0.6, 0.3;
  Tets t(1, 4);
  t << 0, 1, 2, 3;
  EXPECT_THAT(error_of(p, t), HasSubstr("zero volume"));
}

TEST(TetMesh, RejectsBadIndicesRepeatsAndNaN) {
  Points p(4, 3);
  p << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Tets t(1, 4);
  t << 0, 1, 2, 4;
  EXPECT_THAT(error_of(p, t), HasSubstr("refers to node 5, but there are only 4 nodes"));
  t << 0, 1, 1, 3;
  EXPECT_THAT(error_of(p, t), HasSubstr("uses node 2 twice"));
  t << 0, 1, 2, 3;
  p(2, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(error_of(p, t), HasSubstr("node 3 has a coordinate that is not a finite number"));
}

TEST(TetMesh, SetCurrentChecksShape) {
  TetMesh mesh = two_tets();
  EXPECT_THROW(mesh.set_current(Points(3, 3)), Error);
  Points moved = mesh.rest();
  moved.col(0).array() += 2;
  mesh.set_current(moved);
  EXPECT_EQ(mesh.current()(0, 0), 2);
  EXPECT_EQ(mesh.rest()(0, 0), 0);
}

}  // namespace
}  // namespace tetcut
