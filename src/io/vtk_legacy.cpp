// Legacy VTK (.vtk), DATASET UNSTRUCTURED_GRID, ASCII or BINARY (big-endian), in both the classic
// CELLS layout (count, then ids, per cell) and the 5.1 layout (OFFSETS + CONNECTIVITY).
// Tetrahedra (cell type 10) are kept. Written as ASCII version 4.2, which every reader accepts.

#include <string>

#include "io/binary.hpp"
#include "io/formats.hpp"
#include "io/text_scanner.hpp"

namespace tetcut::io {
namespace {

struct LegacyReader {
  TextScanner& in;
  std::string_view bytes;
  bool binary;

  std::size_t type_size(std::string_view type) {
    if (type == "bit" || type == "char" || type == "unsigned_char") return 1;
    if (type == "short" || type == "unsigned_short") return 2;
    if (type == "int" || type == "unsigned_int" || type == "float" || type == "vtktypeint32" ||
        type == "vtktypeuint32")
      return 4;
    if (type == "long" || type == "unsigned_long" || type == "double" || type == "vtktypeint64" ||
        type == "vtktypeuint64")
      return 8;
    in.fail("unknown data type '" + std::string(type) + "'");
  }

  // Reads n values of `type`; ASCII as tokens, BINARY as big-endian bytes right after the header line.
  std::vector<double> read_values(std::int64_t n, std::string_view type, std::string_view what) {
    check_count(n, bytes.size(), binary ? 1 : 2, "values", in.source(), in.line());
    std::vector<double> out;
    out.reserve(static_cast<std::size_t>(n));
    if (!binary) {
      const bool integral = type != "float" && type != "double";
      for (std::int64_t i = 0; i < n; ++i) out.push_back(integral ? static_cast<double>(in.integer(what)) : in.real(what));
      return out;
    }
    in.rest_of_line();
    const std::size_t size = type_size(type);
    std::size_t pos = in.offset();
    if (pos + static_cast<std::size_t>(n) * size > bytes.size()) in.fail("binary " + std::string(what) + " data is truncated");
    const bool is_unsigned = type.starts_with("unsigned") || type.starts_with("vtktypeuint");
    for (std::int64_t i = 0; i < n; ++i, pos += size) {
      const char* p = bytes.data() + pos;
      double v = 0;
      if (type == "float") v = load<float>(p, ByteOrder::kBig);
      else if (type == "double") v = load<double>(p, ByteOrder::kBig);
      else if (size == 1) v = is_unsigned ? load<std::uint8_t>(p, ByteOrder::kBig) : load<std::int8_t>(p, ByteOrder::kBig);
      else if (size == 2) v = is_unsigned ? load<std::uint16_t>(p, ByteOrder::kBig) : load<std::int16_t>(p, ByteOrder::kBig);
      else if (size == 4) v = is_unsigned ? load<std::uint32_t>(p, ByteOrder::kBig) : load<std::int32_t>(p, ByteOrder::kBig);
      else v = static_cast<double>(is_unsigned ? load<std::uint64_t>(p, ByteOrder::kBig) : load<std::int64_t>(p, ByteOrder::kBig));
      out.push_back(v);
    }
    in.seek(pos);
    return out;
  }

  // FIELD name n, then per array: name components tuples type, values.
  void skip_field() {
    in.token("field name");
    const std::int64_t arrays = in.integer_in("number of field arrays", 0, 100000);
    for (std::int64_t a = 0; a < arrays; ++a) {
      in.token("array name");
      const std::int64_t components = in.integer_in("components", 0, 1 << 20);
      const std::int64_t tuples = in.integer("tuples");
      const std::string_view type = in.token("data type");
      read_values(components * tuples, type, "field value");
    }
  }

  // METADATA blocks (VTK 9) run to the next blank line.
  void skip_metadata() {
    in.rest_of_line();  // the rest of the METADATA line itself
    while (in.offset() < bytes.size()) {
      if (is_blank(in.rest_of_line())) return;
    }
  }
};

}  // namespace

TetMeshData read_vtk_legacy(std::string_view bytes, const std::string& source) {
  TextScanner in(bytes, source, '\0');
  const std::string_view first = in.rest_of_line();
  if (!first.starts_with("# vtk DataFile Version")) in.fail("not a legacy VTK file (no '# vtk DataFile Version' line)");
  in.rest_of_line();  // title
  const std::string_view mode = in.token("ASCII or BINARY");
  if (mode != "ASCII" && mode != "BINARY") in.fail("expected ASCII or BINARY, found '" + std::string(mode) + "'");
  LegacyReader reader{in, bytes, mode == "BINARY"};
  in.expect("DATASET");
  const std::string_view dataset = in.token("dataset type");
  if (dataset != "UNSTRUCTURED_GRID") {
    throw Error(ErrorKind::kUnsupported, "dataset " + std::string(dataset) + " is not supported (UNSTRUCTURED_GRID is)",
                source, in.line());
  }
  std::vector<double> xyz;
  std::vector<std::int64_t> cell_start, cell_size, conn;
  std::vector<double> types;
  std::vector<std::int64_t> cell_lines;
  bool have_points = false, have_cells = false;
  while (auto keyword = in.try_token()) {
    if (*keyword == "FIELD") {
      reader.skip_field();
    } else if (*keyword == "METADATA") {
      reader.skip_metadata();
    } else if (*keyword == "POINTS") {
      const std::int64_t n = in.integer("point count");
      const std::string_view type = in.token("point data type");
      xyz = reader.read_values(3 * n, type, "point coordinate");
      for (std::size_t i = 0; i < xyz.size(); ++i) {
        if (!std::isfinite(xyz[i])) in.fail("point " + std::to_string(i / 3 + 1) + " has a coordinate that is not a finite number");
      }
      have_points = true;
    } else if (*keyword == "CELLS") {
      const std::int64_t a = in.integer("cell count");
      const std::int64_t b = in.integer("cell data size");
      const std::size_t after_header = in.offset();
      const std::int64_t header_line = in.line();
      const auto next = in.try_token();
      if (next && *next == "OFFSETS") {
        // 5.1 layout: a = number of offsets (cells + 1), b = connectivity length.
        const std::string_view offset_type = in.token("offset type");
        const auto offsets = reader.read_values(a, offset_type, "offset");
        in.expect("CONNECTIVITY");
        const std::string_view conn_type = in.token("connectivity type");
        const auto ids = reader.read_values(b, conn_type, "connectivity");
        for (std::int64_t c = 0; c + 1 < a; ++c) {
          const auto s = static_cast<std::int64_t>(offsets[static_cast<std::size_t>(c)]);
          const auto e = static_cast<std::int64_t>(offsets[static_cast<std::size_t>(c) + 1]);
          if (s < 0 || e < s || e > b) in.fail("cell " + std::to_string(c + 1) + " has offsets out of range");
          cell_start.push_back(s);
          cell_size.push_back(e - s);
          cell_lines.push_back(header_line);
        }
        for (const double v : ids) conn.push_back(static_cast<std::int64_t>(v));
      } else {
        in.seek(after_header);
        const std::vector<double> flat = reader.read_values(b, "int", "cell data");
        std::size_t pos = 0;
        for (std::int64_t c = 0; c < a; ++c) {
          if (pos >= flat.size()) in.fail("CELLS data ends before cell " + std::to_string(c + 1));
          const auto n = static_cast<std::int64_t>(flat[pos++]);
          if (n < 0 || pos + static_cast<std::size_t>(n) > flat.size()) in.fail("cell " + std::to_string(c + 1) + " overruns the CELLS data");
          cell_start.push_back(static_cast<std::int64_t>(conn.size()));
          cell_size.push_back(n);
          cell_lines.push_back(header_line);
          for (std::int64_t k = 0; k < n; ++k) conn.push_back(static_cast<std::int64_t>(flat[pos++]));
        }
      }
      have_cells = true;
    } else if (*keyword == "CELL_TYPES") {
      const std::int64_t n = in.integer("cell type count");
      if (n != static_cast<std::int64_t>(cell_size.size())) {
        in.fail("CELL_TYPES lists " + std::to_string(n) + " cells, CELLS has " + std::to_string(cell_size.size()));
      }
      types = reader.read_values(n, "int", "cell type");
      break;  // point and cell data that follow are not needed
    } else {
      in.fail("unexpected keyword '" + std::string(*keyword) + "'");
    }
  }
  if (!have_points) in.fail("no POINTS section");
  if (!have_cells) in.fail("no CELLS section");
  if (types.size() != cell_size.size()) in.fail("no CELL_TYPES section");
  TetMeshData data;
  std::vector<Index> ids;
  const std::int64_t num_points = static_cast<std::int64_t>(xyz.size() / 3);
  for (std::size_t c = 0; c < types.size(); ++c) {
    if (static_cast<int>(types[c]) != kVtkTetra) continue;
    if (cell_size[c] != 4) in.fail_at(cell_lines[c], "tetrahedral cell " + std::to_string(c + 1) + " does not have 4 points");
    for (int k = 0; k < 4; ++k) {
      const std::int64_t id = conn[static_cast<std::size_t>(cell_start[c] + k)];
      if (id < 0 || id >= num_points) {
        in.fail_at(cell_lines[c], "cell " + std::to_string(c + 1) + " refers to point " + std::to_string(id) +
                                      ", but there are " + std::to_string(num_points) + " points (numbered from 0)");
      }
      ids.push_back(static_cast<Index>(id));
    }
    data.tet_lines.push_back(cell_lines[c]);
  }
  if (ids.empty()) in.fail("the file holds no tetrahedra (VTK cell type 10)");
  data.points = to_points(xyz);
  data.tets = to_tets(ids);
  return data;
}

void write_vtk_legacy(std::ostream& out, const Points& points, const Tets& tets, const std::vector<CellField>& fields) {
  out << "# vtk DataFile Version 4.2\ntetcut mesh\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS " << points.rows()
      << " double\n";
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    write_real(out, points(i, 0));
    out << ' ';
    write_real(out, points(i, 1));
    out << ' ';
    write_real(out, points(i, 2));
    out << '\n';
  }
  out << "CELLS " << tets.rows() << ' ' << tets.rows() * 5 << '\n';
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    out << "4 " << tets(t, 0) << ' ' << tets(t, 1) << ' ' << tets(t, 2) << ' ' << tets(t, 3) << '\n';
  }
  out << "CELL_TYPES " << tets.rows() << '\n';
  for (Eigen::Index t = 0; t < tets.rows(); ++t) out << kVtkTetra << '\n';
  if (!fields.empty()) {
    out << "CELL_DATA " << tets.rows() << '\n';
    for (const CellField& field : fields) {
      out << "SCALARS " << field.name << (field.integer ? " long" : " double") << " 1\nLOOKUP_TABLE default\n";
      for (const double v : field.values) {
        if (field.integer) {
          out << static_cast<std::int64_t>(v);
        } else {
          write_real(out, v);
        }
        out << '\n';
      }
    }
  }
}

}  // namespace tetcut::io
