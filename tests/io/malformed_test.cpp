// Malformed files: every reader names the file, the line (text formats) and the problem.

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "support/temp_dir.hpp"

namespace tetcut {
namespace {

using ::testing::HasSubstr;
using testing::TempDir;

struct BadFile {
  std::string name;
  std::string content;
  std::string expected;  // substring of the message
  std::int64_t line;     // 0: no line expected (binary data or whole-file checks)
  ErrorKind kind = ErrorKind::kInvalidInput;
};

std::ostream& operator<<(std::ostream& out, const BadFile& f) { return out << f.name << ": " << f.expected; }

class MalformedFile : public ::testing::TestWithParam<BadFile> {};

TEST_P(MalformedFile, GetsAClearError) {
  const BadFile& bad = GetParam();
  TempDir dir;
  const auto path = dir.write(bad.name, bad.content);
  try {
    if (file_kind(path) == FileKind::kTetMesh) {
      read_tet_mesh(path);
    } else {
      read_surface(path);
    }
    FAIL() << "no error for " << bad.name;
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), bad.kind) << e.what();
    EXPECT_THAT(e.what(), HasSubstr(bad.expected));
    EXPECT_EQ(e.line(), bad.line) << e.what();
    EXPECT_THAT(e.file(), HasSubstr(bad.name.substr(0, bad.name.find('.'))));
  }
}

const std::string kMeditHead = "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n";

INSTANTIATE_TEST_SUITE_P(
    Medit, MalformedFile,
    ::testing::Values(
        BadFile{"trunc.mesh", "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n", "unexpected end of file", 6},
        BadFile{"nan.mesh", "Dimension 3\nVertices\n1\n0 nan 0 0\n", "not a finite number", 4},
        BadFile{"range.mesh", kMeditHead + "Tetrahedra\n1\n1 2 3 9 0\nEnd\n", "refers to vertex 9", 11},
        BadFile{"count.mesh", "Vertices\n-3\n", "negative vertices count", 2},
        BadFile{"huge.mesh", "Vertices\n99999999\n0 0 0 0\n", "truncated file?", 2},
        BadFile{"keyword.mesh", kMeditHead + "Bogus\n", "unknown Medit keyword 'Bogus'", 9},
        BadFile{"notets.mesh", kMeditHead + "End\n", "no Tetrahedra section", 9},
        BadFile{"inverted.mesh", kMeditHead + "Tetrahedra\n2\n1 2 3 4 0\n1 3 2 4 0\nEnd\n", "tetrahedron 2 is inverted", 12},
        BadFile{"flat.mesh", kMeditHead + "Tetrahedra\n1\n1 2 3 3 0\nEnd\n", "uses node 3 twice", 11},
        BadFile{"word.mesh", "Vertices\n1\n0 zero 0 0\n", "expected vertex coordinate y (a number), found 'zero'", 3}));

const std::string kGmsh22Nodes = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";

INSTANTIATE_TEST_SUITE_P(
    Gmsh, MalformedFile,
    ::testing::Values(
        BadFile{"binary.msh", "$MeshFormat\n4.1 1 8\n$EndMeshFormat\n", "binary Gmsh files are not supported", 2,
                ErrorKind::kUnsupported},
        BadFile{"v3.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", "version 3.0 is not supported", 2,
                ErrorKind::kUnsupported},
        BadFile{"undefined.msh", kGmsh22Nodes + "$Elements\n1\n1 4 2 0 1 1 2 3 7\n$EndElements\n",
                "refers to node 7, which is not defined", 13},
        BadFile{"noend.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$Elements\n",
                "expected $EndNodes, found '$Elements'", 7},
        BadFile{"nan.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 inf\n$EndNodes\n", "not a finite number", 6},
        BadFile{"notets.msh", kGmsh22Nodes + "$Elements\n1\n1 2 2 0 1 1 2 3\n$EndElements\n", "holds no tetrahedra", 14},
        BadFile{"blocks.msh",
                "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n3 1 0 2\n1\n2\n0 0 0\n1 0 0\n$EndNodes\n",
                "announces 3 nodes, the blocks hold 2", 10}));

INSTANTIATE_TEST_SUITE_P(
    TetGen, MalformedFile,
    ::testing::Values(BadFile{"missing.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n", "cannot open for reading", 0,
                              ErrorKind::kIo},
                      BadFile{"dim.node", "4 2 0 0\n0 0 0\n1 1 0\n2 0 1\n3 1 1\n", "only 3D meshes", 1}));

INSTANTIATE_TEST_SUITE_P(
    Vtu, MalformedFile,
    ::testing::Values(
        BadFile{"xml.vtu", "<VTKFile type=\"UnstructuredGrid\">\n<UnstructuredGrid>\n<Piece>\n</VTKFile>\n",
                "not valid XML", 4},
        BadFile{"type.vtu", "<VTKFile type=\"PolyData\"/>", "expected UnstructuredGrid", 1},
        BadFile{"cells.vtu",
                "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid>\n<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\">"
                "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0</DataArray></Points>"
                "</Piece></UnstructuredGrid></VTKFile>",
                "Cells must hold connectivity, offsets and types", 2},
        BadFile{"count.vtu",
                "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid>\n<Piece NumberOfPoints=\"2\" NumberOfCells=\"0\">"
                "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0</DataArray></Points>"
                "</Piece></UnstructuredGrid></VTKFile>",
                "holds 3 values, expected 6", 3},
        BadFile{"base64.vtu",
                "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid>\n<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\">"
                "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">GAAAAA==AAAA</DataArray>"
                "</Points></Piece></UnstructuredGrid></VTKFile>",
                "binary data is truncated", 3},
        BadFile{"range.vtu",
                "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid>\n<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">"
                "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0 0 0 1"
                "</DataArray></Points><Cells>\n<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 4"
                "</DataArray><DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
                "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells></Piece>"
                "</UnstructuredGrid></VTKFile>",
                "refers to point 4, but the piece has 4 points", 3}));

INSTANTIATE_TEST_SUITE_P(
    VtkLegacy, MalformedFile,
    ::testing::Values(
        BadFile{"notvtk.vtk", "hello\n", "not a legacy VTK file", 1},
        BadFile{"poly.vtk", "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n", "POLYDATA is not supported", 4,
                ErrorKind::kUnsupported},
        BadFile{"range.vtk",
                "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\n"
                "CELLS 1 5\n4 0 1 2 5\nCELL_TYPES 1\n10\n",
                "refers to point 5", 7},
        BadFile{"binary.vtk", "# vtk DataFile Version 3.0\nt\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\nabc",
                "binary point coordinate data is truncated", 5}));

INSTANTIATE_TEST_SUITE_P(
    Surfaces, MalformedFile,
    ::testing::Values(
        BadFile{"range.obj", "v 0 0 0\nv 1 0 0\n# comment\nv 0 1 0\nf 1 2 4\n", "refers to vertex 4, but only 3", 5},
        BadFile{"nan.obj", "v 0 0 0\nv 1 NaN 0\n", "'NaN' is not a finite number", 2},
        BadFile{"two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "fewer than 3 corners", 3},
        BadFile{"header.off", "OBJ\n", "not an OFF file", 1},
        BadFile{"trunc.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", "unexpected end of file", 6},
        BadFile{"range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "refers to vertex 3", 6},
        BadFile{"header.ply", "ply\nformat ascii 1.0\nelement vertex 1\n", "no end_header line", 3},
        BadFile{"range.ply",
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n",
                "refers to vertex 5", 4},
        BadFile{"trunc.ply",
                "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                "property float z\nend_header\nabcd",
                "binary data ends early", 0},
        BadFile{"ascii.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\nendloop\n",
                "expected vertex z (a number), found 'endloop'", 6},
        BadFile{"trunc.stl", std::string(80, 'x') + std::string("\x05\0\0\0", 4) + std::string(60, '\0'),
                "announces 5 triangles", 0}));

}  // namespace
}  // namespace tetcut
