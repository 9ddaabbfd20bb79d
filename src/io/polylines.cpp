// Polylines: the cuts of a planar mesh. OBJ `l` elements, legacy VTK POLYDATA (ASCII), VTK XML
// PolyData Lines, and plain lists of points.

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>

#include <array>
#include <cctype>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "io/files.hpp"
#include "io/formats.hpp"
#include "io/text_scanner.hpp"

namespace tetcut {
namespace io {
namespace {

Points to_rows(const std::vector<double>& xyz) {
  Points p(static_cast<Index>(xyz.size() / 3), 3);
  for (std::size_t i = 0; i < xyz.size(); ++i) p(static_cast<Index>(i / 3), static_cast<int>(i % 3)) = xyz[i];
  return p;
}

Points gather(const std::vector<double>& xyz, const std::vector<Index>& ids) {
  Points p(static_cast<Index>(ids.size()), 3);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    for (int j = 0; j < 3; ++j) p(static_cast<Index>(k), j) = xyz[3 * static_cast<std::size_t>(ids[k]) + j];
  }
  return p;
}

std::vector<Points> read_obj_lines(std::string_view text, const std::string& source) {
  TextScanner file(text, source, '\0');
  std::vector<double> xyz;
  std::vector<Points> lines;
  while (!file.at_end()) {
    const std::string_view line = file.rest_of_line();
    const std::int64_t line_number = file.line();
    TextScanner in(line, source, '#');
    const auto keyword = in.try_token();
    if (!keyword) continue;
    auto fail = [&](const std::string& message) { file.fail_at(line_number, message); };
    if (*keyword == "v") {
      read_obj_vertex(in, fail, &xyz);
    } else if (*keyword == "l") {
      std::vector<Index> ids;
      read_obj_indices(in, fail, "line point", "line", static_cast<std::int64_t>(xyz.size() / 3), &ids);
      if (ids.size() < 2) fail("line has fewer than 2 points");
      lines.push_back(gather(xyz, ids));
    }
  }
  return lines;
}

std::vector<Points> read_vtk_lines(std::string_view text, const std::string& source) {
  TextScanner in(text, source, '\0');
  // Header: version line, title line, then ASCII and DATASET POLYDATA.
  const std::string_view version = in.rest_of_line();
  if (version.find("# vtk DataFile") == std::string_view::npos) in.fail("not a legacy VTK file (no '# vtk DataFile' line)");
  in.rest_of_line();
  const std::string_view encoding = in.token("ASCII or BINARY");
  if (encoding == "BINARY") {
    throw Error(ErrorKind::kUnsupported, "binary legacy VTK polylines are not read; write them as ASCII or .vtp", source, in.line());
  }
  if (encoding != "ASCII") in.fail("expected ASCII or BINARY, found '" + std::string(encoding) + "'");
  in.expect("DATASET");
  const std::string_view dataset = in.token("the dataset type");
  if (dataset != "POLYDATA") in.fail("polylines need DATASET POLYDATA, found '" + std::string(dataset) + "'");
  std::vector<double> xyz;
  std::vector<Points> lines;
  while (const auto keyword = in.try_token()) {
    if (*keyword == "POINTS") {
      const std::int64_t n = in.integer_in("the number of points", 0, std::int64_t{1} << 31);
      in.token("the point type");
      xyz.clear();
      for (std::int64_t i = 0; i < 3 * n; ++i) xyz.push_back(in.real("a point coordinate"));
    } else if (*keyword == "LINES") {
      const std::int64_t n = in.integer_in("the number of lines", 0, std::int64_t{1} << 31);
      in.integer("the size of the line list");
      const auto defined = static_cast<std::int64_t>(xyz.size() / 3);
      for (std::int64_t l = 0; l < n; ++l) {
        const std::int64_t count = in.integer_in("the number of points of a line", 2, std::int64_t{1} << 31);
        std::vector<Index> ids;
        for (std::int64_t k = 0; k < count; ++k) ids.push_back(static_cast<Index>(in.integer_in("a point id", 0, defined - 1)));
        lines.push_back(gather(xyz, ids));
      }
    } else {
      break;  // point or cell data, which cuts do not need
    }
  }
  return lines;
}

std::vector<Points> read_point_lists(std::string_view text, const std::string& source) {
  std::vector<Points> lines;
  std::vector<double> xyz;
  std::int64_t line_number = 0;
  auto flush = [&] {
    if (xyz.empty()) return;
    if (xyz.size() < 6) throw Error(ErrorKind::kInvalidInput, "a polyline of a single point", source, line_number);
    lines.push_back(to_rows(xyz));
    xyz.clear();
  };
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string_view line = text.substr(pos, end - pos);
    ++line_number;
    pos = end + 1;
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    TextScanner in(line, source, '\0');
    std::array<double, 3> point = {0, 0, 0};
    int count = 0;
    while (const auto t = in.try_token()) {
      const auto v = parse_real(*t);
      if (!v || !std::isfinite(*v)) {
        throw Error(ErrorKind::kInvalidInput, "'" + std::string(*t) + "' is not a finite number", source, line_number);
      }
      if (count == 3) throw Error(ErrorKind::kInvalidInput, "a point has 2 or 3 coordinates, this line more", source, line_number);
      point[count++] = *v;
    }
    if (count == 0) {
      if (is_blank(line)) flush();
      continue;
    }
    if (count == 1) throw Error(ErrorKind::kInvalidInput, "a point has 2 or 3 coordinates, this line one", source, line_number);
    xyz.insert(xyz.end(), point.begin(), point.end());
  }
  flush();
  return lines;
}

std::string extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace
}  // namespace io

std::string supported_polyline_extensions() { return ".obj (l elements), .vtk (POLYDATA LINES, ASCII), .vtp (Lines), .txt/.xy/.xyz (points)"; }

std::vector<Points> read_polylines(const std::filesystem::path& path) {
  const std::string ext = io::extension(path);
  const std::string source = path.string();
  std::vector<Points> lines;
  if (ext == ".obj") {
    lines = io::read_obj_lines(io::read_file(path), source);
  } else if (ext == ".vtk") {
    lines = io::read_vtk_lines(io::read_file(path), source);
  } else if (ext == ".vtp") {
    lines = io::read_vtp_lines(io::read_file(path), source);
  } else if (ext == ".txt" || ext == ".xy" || ext == ".xyz") {
    lines = io::read_point_lists(io::read_file(path), source);
  } else {
    throw Error(ErrorKind::kInvalidArgument,
                "unknown polyline extension '" + ext + "' (supported: " + supported_polyline_extensions() + ")", source);
  }
  if (lines.empty()) throw Error(ErrorKind::kInvalidInput, "the file holds no polyline", source);
  return lines;
}

void write_polylines(const std::filesystem::path& path, const Points& points, const Edges& segments) {
  const std::string ext = io::extension(path);
  std::ostringstream out;
  out.precision(17);
  if (ext == ".obj") {
    out << "# tetcut polylines: " << points.rows() << " points, " << segments.rows() << " segments\n";
    for (Index i = 0; i < points.rows(); ++i) out << "v " << points(i, 0) << ' ' << points(i, 1) << ' ' << points(i, 2) << '\n';
    for (Index s = 0; s < segments.rows(); ++s) out << "l " << segments(s, 0) + 1 << ' ' << segments(s, 1) + 1 << '\n';
  } else if (ext == ".vtk") {
    out << "# vtk DataFile Version 4.2\ntetcut polylines\nASCII\nDATASET POLYDATA\nPOINTS " << points.rows() << " double\n";
    for (Index i = 0; i < points.rows(); ++i) out << points(i, 0) << ' ' << points(i, 1) << ' ' << points(i, 2) << '\n';
    out << "LINES " << segments.rows() << ' ' << 3 * segments.rows() << '\n';
    for (Index s = 0; s < segments.rows(); ++s) out << "2 " << segments(s, 0) << ' ' << segments(s, 1) << '\n';
  } else {
    throw Error(ErrorKind::kInvalidArgument, "polylines are written as .obj or .vtk, not '" + ext + "'", path.string());
  }
  write_text_file(path, out.str());
}

}  // namespace tetcut
