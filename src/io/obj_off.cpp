// Wavefront OBJ and OFF surfaces. Only vertex positions and faces are read; polygons are split
// into fans; texture, normal, group and material statements are ignored.

#include <string>

#include "io/formats.hpp"
#include "io/text_scanner.hpp"

namespace tetcut::io {
namespace {

void add_fan(std::vector<Index>& triangles, const std::vector<Index>& polygon) {
  for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
    triangles.insert(triangles.end(), {polygon[0], polygon[k], polygon[k + 1]});
  }
}

void write_xyz_line(std::ostream& out, const char* prefix, const Points& v, Eigen::Index i) {
  out << prefix;
  write_real(out, v(i, 0));
  out << ' ';
  write_real(out, v(i, 1));
  out << ' ';
  write_real(out, v(i, 2));
  out << '\n';
}

}  // namespace

void read_obj_vertex(TextScanner& in, const std::function<void(const std::string&)>& fail, std::vector<double>* xyz) {
  for (const char* axis : {"x", "y", "z"}) {
    const auto t = in.try_token();
    if (!t) fail(std::string("vertex has no ") + axis + " coordinate");
    const auto v = parse_real(*t);
    if (!v) fail("vertex coordinate '" + std::string(*t) + "' is not a number");
    if (!std::isfinite(*v)) fail("vertex coordinate '" + std::string(*t) + "' is not a finite number");
    xyz->push_back(*v);
  }
}

void read_obj_indices(TextScanner& in, const std::function<void(const std::string&)>& fail, const std::string& item,
                      const std::string& element, std::int64_t defined, std::vector<Index>* ids) {
  while (const auto t = in.try_token()) {
    // "i", "i/t", "i//n" or "i/t/n": the position index comes first.
    const auto index = parse_integer(t->substr(0, t->find('/')));
    if (!index || *index == 0) fail(item + " '" + std::string(*t) + "' is not a valid vertex index");
    const std::int64_t resolved = *index > 0 ? *index - 1 : defined + *index;
    if (resolved < 0 || resolved >= defined) {
      fail(element + " refers to vertex " + std::to_string(*index) + ", but only " + std::to_string(defined) +
           " vertices are defined before it");
    }
    ids->push_back(static_cast<Index>(resolved));
  }
}

TriangleSurface read_obj(std::string_view text, const std::string& source) {
  TextScanner file(text, source, '\0');
  std::vector<double> xyz;
  std::vector<Index> triangles;
  std::vector<Index> polygon;
  while (!file.at_end()) {
    const std::string_view line = file.rest_of_line();
    const std::int64_t line_number = file.line();
    TextScanner in(line, source, '#');
    const auto keyword = in.try_token();
    if (!keyword) continue;
    // Keep the file's line numbers in messages from this line's scanner.
    auto fail = [&](const std::string& message) { file.fail_at(line_number, message); };
    if (*keyword == "v") {
      read_obj_vertex(in, fail, &xyz);
    } else if (*keyword == "f") {
      polygon.clear();
      read_obj_indices(in, fail, "face corner", "face", static_cast<std::int64_t>(xyz.size() / 3), &polygon);
      if (polygon.size() < 3) fail("face has fewer than 3 corners");
      add_fan(triangles, polygon);
    }
  }
  TriangleSurface surface;
  surface.vertices = to_points(xyz);
  surface.triangles = to_triangles(triangles);
  return surface;
}

void write_obj(std::ostream& out, const TriangleSurface& surface) {
  out << "# tetcut surface: " << surface.num_vertices() << " vertices, " << surface.num_triangles() << " triangles\n";
  for (Eigen::Index i = 0; i < surface.vertices.rows(); ++i) write_xyz_line(out, "v ", surface.vertices, i);
  for (Eigen::Index f = 0; f < surface.triangles.rows(); ++f) {
    out << "f " << surface.triangles(f, 0) + 1 << ' ' << surface.triangles(f, 1) + 1 << ' '
        << surface.triangles(f, 2) + 1 << '\n';
  }
}

TriangleSurface read_off(std::string_view text, const std::string& source) {
  TextScanner in(text, source);
  const std::string_view header = in.token("OFF header");
  if (header != "OFF" && header != "COFF" && header != "NOFF" && header != "CNOFF") {
    if (header.find("OFF") != std::string_view::npos) {
      throw Error(ErrorKind::kUnsupported, "OFF variant '" + std::string(header) + "' is not supported", source,
                  in.line());
    }
    in.fail("not an OFF file (first token is '" + std::string(header) + "')");
  }
  const std::int64_t num_vertices = in.integer("vertex count");
  const std::int64_t num_faces = in.integer("face count");
  in.integer("edge count");
  check_count(num_vertices, text.size(), 6, "vertices", source, in.line());
  check_count(num_faces, text.size(), 8, "faces", source, in.line());
  in.rest_of_line();
  std::vector<double> xyz;
  xyz.reserve(static_cast<std::size_t>(num_vertices) * 3);
  for (std::int64_t i = 0; i < num_vertices; ++i) {
    for (const char* axis : {"x", "y", "z"}) xyz.push_back(in.real(std::string("vertex ") + axis));
    in.rest_of_line();  // colours or normals
  }
  std::vector<Index> triangles;
  std::vector<Index> polygon;
  for (std::int64_t f = 0; f < num_faces; ++f) {
    const std::int64_t corners = in.integer_in("face corner count", 3, 1 << 20);
    polygon.clear();
    for (std::int64_t k = 0; k < corners; ++k) {
      const std::int64_t id = in.integer("face vertex index");
      if (id < 0 || id >= num_vertices) {
        in.fail("face " + std::to_string(f + 1) + " refers to vertex " + std::to_string(id) + ", but there are " +
                std::to_string(num_vertices) + " vertices (numbered from 0)");
      }
      polygon.push_back(static_cast<Index>(id));
    }
    in.rest_of_line();  // colour
    add_fan(triangles, polygon);
  }
  TriangleSurface surface;
  surface.vertices = to_points(xyz);
  surface.triangles = to_triangles(triangles);
  return surface;
}

void write_off(std::ostream& out, const TriangleSurface& surface) {
  out << "OFF\n" << surface.num_vertices() << ' ' << surface.num_triangles() << " 0\n";
  for (Eigen::Index i = 0; i < surface.vertices.rows(); ++i) write_xyz_line(out, "", surface.vertices, i);
  for (Eigen::Index f = 0; f < surface.triangles.rows(); ++f) {
    out << "3 " << surface.triangles(f, 0) << ' ' << surface.triangles(f, 1) << ' ' << surface.triangles(f, 2)
        << '\n';
  }
}

}  // namespace tetcut::io
