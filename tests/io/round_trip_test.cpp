// Every writer's output reads back to the same mesh or surface, bit for bit.

#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "support/temp_dir.hpp"

namespace tetcut {
namespace {

using testing::TempDir;

// Coordinates like 0.1 * k are not exactly representable, so the text writers must print
// enough digits to round-trip.
TetMesh odd_mesh() { return make_bcc(Box{Vec3(-0.3, 0.1, 2.7), Vec3(1.9, 0.7, 3.3)}, 0.3); }

class TetMeshRoundTrip : public ::testing::TestWithParam<std::tuple<std::string, int>> {};

TEST_P(TetMeshRoundTrip, ReadsBackExactly) {
  const auto [name, gmsh_version] = GetParam();
  TempDir dir;
  const TetMesh mesh = odd_mesh();
  TetMeshWriteOptions options;
  options.gmsh_version = gmsh_version;
  write_tet_mesh(dir / name, mesh, options);
  const TetMesh back = read_tet_mesh(dir / name);
  ASSERT_EQ(back.num_nodes(), mesh.num_nodes());
  ASSERT_EQ(back.num_tets(), mesh.num_tets());
  EXPECT_EQ(back.rest(), mesh.rest());
  EXPECT_EQ(back.tets(), mesh.tets());
}

INSTANTIATE_TEST_SUITE_P(Formats, TetMeshRoundTrip,
                         ::testing::Values(std::make_tuple("m.mesh", 41), std::make_tuple("m.msh", 41),
                                           std::make_tuple("m.msh", 22), std::make_tuple("m.node", 41),
                                           std::make_tuple("m.ele", 41), std::make_tuple("m.vtu", 41),
                                           std::make_tuple("m.vtk", 41)));

TEST(TetMeshIo, TetgenWritesBothFiles) {
  TempDir dir;
  write_tet_mesh(dir / "out.node", odd_mesh());
  EXPECT_TRUE(std::filesystem::exists(dir / "out.node"));
  EXPECT_TRUE(std::filesystem::exists(dir / "out.ele"));
}

TEST(TetMeshIo, CurrentPositionsCanBeWritten) {
  TempDir dir;
  TetMesh mesh = odd_mesh();
  Points moved = mesh.rest() * 2.0;
  mesh.set_current(moved);
  TetMeshWriteOptions options;
  options.current_positions = true;
  write_tet_mesh(dir / "moved.vtu", mesh, options);
  EXPECT_EQ(read_tet_mesh(dir / "moved.vtu").rest(), moved);
}

TEST(TetMeshIo, FailedWriteLeavesExistingFileAndNoTemporaries) {
  TempDir dir;
  const auto target = dir.write("keep.vtu", "precious");
  TetMeshWriteOptions options;
  options.cell_fields.push_back({"bad", {1.0, 2.0}, false});  // wrong length
  EXPECT_THROW(write_tet_mesh(target, odd_mesh(), options), Error);
  std::ifstream in(target);
  std::stringstream content;
  content << in.rdbuf();
  EXPECT_EQ(content.str(), "precious");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator()), 1);
}

TEST(TetMeshIo, UnwritableDirectoryIsAnIoError) {
  try {
    write_tet_mesh("/nonexistent-dir/x.vtu", odd_mesh());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIo);
    EXPECT_EQ(e.file(), "/nonexistent-dir/x.vtu");
  }
}

TEST(TetMeshIo, UnknownExtension) {
  TempDir dir;
  EXPECT_THROW(write_tet_mesh(dir / "x.abc", odd_mesh()), Error);
  EXPECT_THROW(read_tet_mesh(dir.write("x.abc", "")), Error);
  EXPECT_EQ(file_kind("a.VTU"), FileKind::kTetMesh);
  EXPECT_EQ(file_kind("a.Stl"), FileKind::kSurface);
  EXPECT_EQ(file_kind("a.txt"), FileKind::kUnknown);
}

TriangleSurface odd_surface() {
  // A closed octahedron with non-representable coordinates.
  TriangleSurface s;
  s.vertices.resize(6, 3);
  s.vertices << 0.1, 0, 0, -0.1, 0, 0, 0, 0.3, 0, 0, -0.3, 0, 0, 0, 0.7, 0, 0, -0.7;
  s.triangles.resize(8, 3);
  s.triangles << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  return s;
}

// Same triangles with the same corner coordinates; vertex numbering may differ (STL has none).
void expect_same_corners(const TriangleSurface& actual, const TriangleSurface& expected) {
  ASSERT_EQ(actual.num_triangles(), expected.num_triangles());
  EXPECT_EQ(actual.num_vertices(), expected.num_vertices());
  for (Index f = 0; f < expected.num_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(Vec3(actual.vertices.row(actual.triangles(f, k))), Vec3(expected.vertices.row(expected.triangles(f, k))));
    }
  }
}

class SurfaceRoundTrip : public ::testing::TestWithParam<std::tuple<std::string, bool>> {};

TEST_P(SurfaceRoundTrip, ReadsBackExactly) {
  const auto [name, binary] = GetParam();
  TempDir dir;
  const TriangleSurface s = odd_surface();
  write_surface(dir / name, s, SurfaceWriteOptions{binary});
  const TriangleSurface back = read_surface(dir / name);
  expect_same_corners(back, s);
}

INSTANTIATE_TEST_SUITE_P(Formats, SurfaceRoundTrip,
                         ::testing::Values(std::make_tuple("s.obj", false), std::make_tuple("s.off", false),
                                           std::make_tuple("s.ply", false), std::make_tuple("s.ply", true),
                                           std::make_tuple("s.stl", false), std::make_tuple("s.vtp", false)));

TEST(SurfaceIo, VtpPolygonsBecomeFansAndBadIdsAreRefused) {
  // A quad and a triangle, as ParaView writes them: ascii arrays, 32-bit headers.
  TempDir dir;
  const std::string vtp = R"(<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
<PolyData><Piece NumberOfPoints="5" NumberOfPolys="2">
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 1 1 0 0 1 0 0.5 0.5 1</DataArray></Points>
<Polys><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 0 1 4</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">4 7</DataArray></Polys>
</Piece></PolyData></VTKFile>
)";
  write_text_file(dir / "q.vtp", vtp);
  const TriangleSurface s = read_surface(dir / "q.vtp");
  ASSERT_EQ(s.num_triangles(), 3);
  EXPECT_EQ(s.num_vertices(), 5);
  EXPECT_EQ(s.triangles.row(0), Eigen::RowVector3i(0, 1, 2));
  EXPECT_EQ(s.triangles.row(1), Eigen::RowVector3i(0, 2, 3));
  EXPECT_EQ(s.triangles.row(2), Eigen::RowVector3i(0, 1, 4));
  std::string bad = vtp;
  bad.replace(bad.find("0 1 4"), 5, "0 1 9");
  write_text_file(dir / "bad.vtp", bad);
  try {
    read_surface(dir / "bad.vtp");
    FAIL() << "a polygon with a missing point was read";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("refers to point 9"), std::string::npos) << e.message();
    EXPECT_EQ(e.line(), 5);  // the connectivity array
  }
}

TEST(SurfaceIo, BinaryStlKeepsSinglePrecisionCoordinatesAndWeldsCorners) {
  TempDir dir;
  TriangleSurface s = odd_surface();
  // Binary STL stores floats: use coordinates that are exact in single precision.
  s.vertices = (s.vertices * 8.0).array().round().matrix() / 8.0;
  write_surface(dir / "s.stl", s, SurfaceWriteOptions{true});
  // 24 stored corners are welded back to 6 vertices.
  expect_same_corners(read_surface(dir / "s.stl"), s);
}

TEST(SeriesIo, ReadsBackTimesAndResolvesFilesAgainstItsFolder) {
  TempDir dir;
  std::filesystem::create_directories(dir / "run");
  // Times that need all 17 digits, and one file given with an absolute path.
  const std::vector<SeriesEntry> written = {{0.1, "a_0000.vtp"}, {1.0 / 3, "sub/a_0001.vtp"}, {2.5, dir / "elsewhere.vtp"}};
  write_series(dir / "run" / "a.pvd", written);
  const std::vector<SeriesEntry> read = read_series(dir / "run" / "a.pvd");
  ASSERT_EQ(read.size(), 3u);
  EXPECT_EQ(read[0].time, 0.1);
  EXPECT_EQ(read[1].time, 1.0 / 3);
  EXPECT_EQ(read[0].file, dir / "run" / "a_0000.vtp");
  EXPECT_EQ(read[1].file, dir / "run" / "sub/a_0001.vtp");
  EXPECT_EQ(read[2].file, dir / "elsewhere.vtp");
}

TEST(SeriesIo, MalformedCollectionsNameTheLine) {
  TempDir dir;
  const auto expect_error = [&](const std::string& body, const std::string& message, std::int64_t line) {
    std::ofstream(dir / "s.pvd") << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\">\n<Collection>\n" << body
                                 << "</Collection>\n</VTKFile>\n";
    try {
      read_series(dir / "s.pvd");
      FAIL() << "read: " << body;
    } catch (const Error& e) {
      EXPECT_NE(e.message().find(message), std::string::npos) << e.message();
      EXPECT_EQ(e.line(), line) << body;
      EXPECT_NE(std::string(e.what()).find("s.pvd"), std::string::npos) << e.what();
    }
  };
  expect_error("<DataSet timestep=\"0\" file=\"a.vtp\"/>\n<DataSet timestep=\"nan\" file=\"b.vtp\"/>\n",
               "timestep 'nan' is not a finite number", 5);
  expect_error("<DataSet timestep=\"1\"/>\n", "DataSet has no file attribute", 4);
  expect_error("", "no <DataSet> elements", 3);
  expect_error("<DataSet timestep=\"1\" file=\"a.vtp\">\n", "not valid XML", 5);
}

}  // namespace
}  // namespace tetcut
