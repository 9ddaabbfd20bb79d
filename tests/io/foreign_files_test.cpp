// Files in the dialects other tools write: Gmsh with entities, physical names, parametric nodes
// and mixed elements; Medit with extra sections; TetGen numbered from 1 with attributes; VTK 9's
// legacy 5.1 layout; VTU with appended raw zlib-compressed data. Each holds the same unit cube
// split into 5 tets.

#include <tetcut/io.hpp>
#include <tetcut/quality.hpp>

#include <gtest/gtest.h>

#include <zlib.h>

#include <cstring>
#include <string>

#include "support/invariants.hpp"
#include "support/temp_dir.hpp"

namespace tetcut {
namespace {

void expect_unit_cube_of_five(const TetMesh& mesh) {
  EXPECT_EQ(mesh.num_nodes(), 8);
  EXPECT_EQ(mesh.num_tets(), 5);
  EXPECT_EQ(testing::exact_volume(mesh), 1);
  EXPECT_EQ(testing::check_positive_and_conforming(mesh), "");
  EXPECT_EQ(mesh.adjacency().num_boundary_faces(), 12);
}

class ForeignFile : public ::testing::TestWithParam<std::string> {};

TEST_P(ForeignFile, ReadsTheCube) {
  expect_unit_cube_of_five(read_tet_mesh(std::string(TETCUT_TEST_DATA) + "/" + GetParam()));
}

INSTANTIATE_TEST_SUITE_P(Dialects, ForeignFile,
                         ::testing::Values("cube5_gmsh41.msh", "cube5_gmsh22.msh", "cube5.mesh", "cube5.node",
                                           "cube5.ele", "cube5_v51.vtk"));

// Builds a .vtu the way ParaView saves by default: appended raw data, zlib-compressed blocks,
// 32-bit headers, Float32 points and Int32 connectivity.
std::string compressed_block(const std::string& data) {
  uLongf size = compressBound(static_cast<uLong>(data.size()));
  std::string out(size, '\0');
  compress(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(data.data()),
           static_cast<uLong>(data.size()));
  out.resize(size);
  std::string header(16, '\0');
  const std::uint32_t fields[4] = {1, static_cast<std::uint32_t>(data.size()), static_cast<std::uint32_t>(data.size()),
                                   static_cast<std::uint32_t>(out.size())};
  std::memcpy(header.data(), fields, 16);
  return header + out;
}

template <typename T>
std::string raw_bytes(std::initializer_list<T> values) {
  std::string out;
  for (const T v : values) out.append(reinterpret_cast<const char*>(&v), sizeof v);
  return out;
}

TEST(ForeignVtu, AppendedRawZlib) {
  const std::string points = raw_bytes<float>({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1});
  const std::string connectivity =
      raw_bytes<std::int32_t>({1, 2, 4, 7, 0, 1, 2, 4, 3, 1, 7, 2, 5, 1, 4, 7, 6, 2, 7, 4, 0, 1, 2});
  const std::string offsets = raw_bytes<std::int32_t>({4, 8, 12, 16, 20, 23});
  const std::string types = raw_bytes<std::uint8_t>({10, 10, 10, 10, 10, 5});
  std::string appended;
  std::string xml =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\" "
      "compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"8\" NumberOfCells=\"6\">\n";
  auto array = [&](const char* type, const char* name, int components, const std::string& data) {
    xml += std::string("<DataArray type=\"") + type + "\" Name=\"" + name + "\" NumberOfComponents=\"" +
           std::to_string(components) + "\" format=\"appended\" offset=\"" + std::to_string(appended.size()) + "\"/>\n";
    appended += compressed_block(data);
  };
  xml += "<Points>\n";
  array("Float32", "Points", 3, points);
  xml += "</Points>\n<Cells>\n";
  array("Int32", "connectivity", 1, connectivity);
  array("Int32", "offsets", 1, offsets);
  array("UInt8", "types", 1, types);
  xml += "</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_" + appended +
         "\n</AppendedData>\n</VTKFile>\n";
  testing::TempDir dir;
  expect_unit_cube_of_five(read_tet_mesh(dir.write("paraview.vtu", xml)));
}

TEST(ForeignVtu, AsciiWithTwoPieces) {
  const std::string piece =
      "<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\"><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" "
      "format=\"ascii\">0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points><Cells>"
      "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>"
      "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells></Piece>\n";
  testing::TempDir dir;
  const TetMesh mesh = read_tet_mesh(dir.write(
      "pieces.vtu", "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid>" + piece + piece +
                        "</UnstructuredGrid></VTKFile>"));
  EXPECT_EQ(mesh.num_nodes(), 8);
  EXPECT_EQ(mesh.num_tets(), 2);
  EXPECT_EQ(mesh.tets()(1, 0), 4);  // the second piece's ids are offset
}

TEST(ForeignSurface, ObjWithNormalsTexturesNegativeIndicesAndQuads) {
  testing::TempDir dir;
  const TriangleSurface s = read_surface(dir.write("quad.obj",
                                                   "mtllib x.mtl\no square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                                   "vt 0 0\nvn 0 0 1\ng side\ns off\nf 1/1/1 2/1/1 -2/1/1 -1//1\n"));
  EXPECT_EQ(s.num_vertices(), 4);
  ASSERT_EQ(s.num_triangles(), 2);
  EXPECT_EQ(s.triangles.row(1), Eigen::RowVector3i(0, 2, 3));
  EXPECT_DOUBLE_EQ(measure_surface(s).area, 1.0);
}

TEST(ForeignSurface, BigEndianPlyWithExtraProperties) {
  auto be = [](auto v) {
    std::string bytes(reinterpret_cast<const char*>(&v), sizeof v);
    return std::string(bytes.rbegin(), bytes.rend());
  };
  std::string ply =
      "ply\nformat binary_big_endian 1.0\ncomment scanner output\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nproperty uchar red\nelement face 1\n"
      "property list uchar uint vertex_index\nproperty float quality\nend_header\n";
  const float xyz[3][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
  for (const auto& v : xyz) ply += be(v[0]) + be(v[1]) + be(v[2]) + std::string(1, '\x7f');
  ply += std::string(1, '\x03') + be(std::uint32_t{0}) + be(std::uint32_t{1}) + be(std::uint32_t{2}) + be(0.5f);
  testing::TempDir dir;
  const TriangleSurface s = read_surface(dir.write("be.ply", ply));
  ASSERT_EQ(s.num_triangles(), 1);
  EXPECT_DOUBLE_EQ(measure_surface(s).area, 2.0);
}

TEST(ForeignSurface, MultiSolidAsciiStl) {
  testing::TempDir dir;
  const std::string facet = "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n endloop\nendfacet\n";
  const TriangleSurface s =
      read_surface(dir.write("two.stl", "solid a\n" + facet + "endsolid a\nsolid b\n" + facet + "endsolid b\n"));
  EXPECT_EQ(s.num_triangles(), 2);
  EXPECT_EQ(s.num_vertices(), 3);  // identical corners are welded
}

}  // namespace
}  // namespace tetcut
