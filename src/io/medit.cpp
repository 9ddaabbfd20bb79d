// Medit / INRIA .mesh, ASCII. Sections are keywords followed by a count and that many records;
// only Vertices and Tetrahedra are kept, the other known sections are skipped.

#include <array>
#include <string>
#include <utility>

#include "io/formats.hpp"
#include "io/text_scanner.hpp"

namespace tetcut::io {
namespace {

// Sections we skip, with the number of fields in each record.
constexpr std::array<std::pair<std::string_view, int>, 16> kSkippedSections{{
    {"Edges", 3},         {"Triangles", 4},        {"Quadrilaterals", 5},   {"Hexahedra", 9},
    {"Prisms", 7},        {"Pyramids", 6},         {"Corners", 1},          {"Ridges", 1},
    {"RequiredVertices", 1}, {"RequiredEdges", 1}, {"RequiredTriangles", 1}, {"Normals", 3},
    {"Tangents", 3},      {"NormalAtVertices", 2}, {"TangentAtEdges", 3},   {"TetrahedraP2", 11},
}};

}  // namespace

TetMeshData read_medit(std::string_view text, const std::string& source) {
  TextScanner in(text, source);
  TetMeshData data;
  std::vector<double> xyz;
  std::vector<Index> ids;
  bool have_vertices = false;
  bool have_tets = false;
  bool ended = false;
  while (!ended && !in.at_end()) {
    const std::string_view keyword = in.token("a keyword");
    if (keyword == "MeshVersionFormatted") {
      in.integer_in("mesh version", 1, 4);
    } else if (keyword == "Dimension") {
      const std::int64_t dim = in.integer("dimension");
      if (dim != 3) in.fail("only 3D meshes can be read (Dimension is " + std::to_string(dim) + ")");
    } else if (keyword == "Vertices") {
      if (have_vertices) in.fail("a second Vertices section");
      have_vertices = true;
      const std::int64_t n = in.integer("vertex count");
      check_count(n, text.size(), 8, "vertices", source, in.line());
      xyz.reserve(static_cast<std::size_t>(n) * 3);
      for (std::int64_t i = 0; i < n; ++i) {
        for (const char* axis : {"x", "y", "z"}) xyz.push_back(in.real(std::string("vertex coordinate ") + axis));
        in.integer("vertex reference");
      }
    } else if (keyword == "Tetrahedra") {
      if (have_tets) in.fail("a second Tetrahedra section");
      have_tets = true;
      const std::int64_t n = in.integer("tetrahedron count");
      check_count(n, text.size(), 10, "tetrahedra", source, in.line());
      ids.reserve(static_cast<std::size_t>(n) * 4);
      data.tet_lines.reserve(static_cast<std::size_t>(n));
      for (std::int64_t i = 0; i < n; ++i) {
        for (int k = 0; k < 4; ++k) {
          const std::int64_t id = in.integer("tetrahedron vertex");
          if (k == 0) data.tet_lines.push_back(in.line());
          if (id < 1 || id > static_cast<std::int64_t>(xyz.size() / 3)) {
            in.fail("tetrahedron " + std::to_string(i + 1) + " refers to vertex " + std::to_string(id) +
                    ", but there are " + std::to_string(xyz.size() / 3) + " vertices (numbered from 1)");
          }
          ids.push_back(static_cast<Index>(id - 1));
        }
        in.integer("tetrahedron reference");
      }
    } else if (keyword == "End") {
      ended = true;
    } else {
      int fields = 0;
      for (const auto& [name, count] : kSkippedSections) {
        if (keyword == name) fields = count;
      }
      if (fields == 0) in.fail("unknown Medit keyword '" + std::string(keyword) + "'");
      const std::int64_t n = in.integer(std::string(keyword) + " count");
      check_count(n, text.size(), static_cast<std::size_t>(2 * fields), "records", source, in.line());
      for (std::int64_t i = 0; i < n * fields; ++i) in.token(std::string(keyword) + " data");
    }
  }
  if (!have_vertices) in.fail("no Vertices section");
  if (!have_tets) in.fail("no Tetrahedra section");
  data.points = to_points(xyz);
  data.tets = to_tets(ids);
  return data;
}

void write_medit(std::ostream& out, const Points& points, const Tets& tets, const std::vector<Index>& labels) {
  out << "MeshVersionFormatted 2\nDimension 3\n\nVertices\n" << points.rows() << '\n';
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    for (int k = 0; k < 3; ++k) {
      write_real(out, points(i, k));
      out << ' ';
    }
    out << "0\n";
  }
  out << "\nTetrahedra\n" << tets.rows() << '\n';
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    out << tets(t, 0) + 1 << ' ' << tets(t, 1) + 1 << ' ' << tets(t, 2) + 1 << ' ' << tets(t, 3) + 1 << ' '
        << (labels.empty() ? 0 : labels[t]) << '\n';
  }
  out << "\nEnd\n";
}

}  // namespace tetcut::io
