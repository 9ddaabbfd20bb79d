// VTK XML unstructured grid (.vtu) and polygon data (.vtp, surfaces). Reads every encoding VTK and ParaView write: ascii, inline
// base64 ("binary"), appended raw or base64, each optionally zlib-compressed, with 32- or 64-bit
// headers and either byte order. Tetrahedra (VTK cell type 10) are kept, other cells skipped.
// Writes inline base64 with 64-bit headers, uncompressed.

#include <pugixml.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>

#include "io/binary.hpp"
#include "io/formats.hpp"
#include "io/text_scanner.hpp"

namespace tetcut::io {
namespace {

enum class Scalar { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kInt64, kUInt64, kFloat32, kFloat64 };

struct ScalarInfo {
  const char* name;
  Scalar type;
  std::size_t size;
};
constexpr ScalarInfo kScalars[] = {
    {"Int8", Scalar::kInt8, 1},     {"UInt8", Scalar::kUInt8, 1},   {"Int16", Scalar::kInt16, 2},
    {"UInt16", Scalar::kUInt16, 2}, {"Int32", Scalar::kInt32, 4},   {"UInt32", Scalar::kUInt32, 4},
    {"Int64", Scalar::kInt64, 8},   {"UInt64", Scalar::kUInt64, 8}, {"Float32", Scalar::kFloat32, 4},
    {"Float64", Scalar::kFloat64, 8},
};

class VtuReader {
 public:
  VtuReader(std::string_view bytes, std::string source) : bytes_(bytes), source_(std::move(source)) {}

  TetMeshData read();
  /// A VTK XML PolyData file's polygons (.vtp), split into fans of triangles.
  TriangleSurface read_polydata();
  /// The Lines of a PolyData file, each as its points.
  std::vector<Points> read_polydata_lines();
  /// A ParaView collection's datasets (.pvd), in file order, with their paths as written.
  std::vector<SeriesEntry> read_collection();

 private:
  // Parses the XML (keeping appended data aside), checks the file type and reads the encoding
  // attributes; returns the <UnstructuredGrid> or <PolyData> element.
  pugi::xml_node open(pugi::xml_document* doc, const char* type);
  std::vector<double> point_coordinates(const pugi::xml_node& piece, std::int64_t num_points);
  // The cells of a PolyData block ("Polys", "Lines"): `count` lists of point ids, each checked
  // against the piece's points and holding at least `min_points`; `what` names one in errors.
  std::vector<std::vector<std::int64_t>> cell_block(const pugi::xml_node& piece, const char* block, const char* what,
                                                    std::int64_t count, std::int64_t min_points, std::int64_t num_points);
  [[noreturn]] void fail(const std::string& message, std::ptrdiff_t offset = -1) const {
    std::int64_t line = 0;
    if (offset >= 0) line = 1 + std::count(bytes_.begin(), bytes_.begin() + offset, '\n');
    throw Error(ErrorKind::kInvalidInput, message, source_, line);
  }
  std::ptrdiff_t offset_of(const pugi::xml_node& node) const { return node.offset_debug(); }
  // Fails unless `id`, used by `what` (a cell or polygon named with its 1-based number), numbers
  // one of the piece's points.
  void check_point_id(const char* what, std::int64_t element, std::int64_t id, std::int64_t num_points,
                      const pugi::xml_node& connectivity) const {
    if (id >= 0 && id < num_points) return;
    fail(std::string(what) + " " + std::to_string(element + 1) + " refers to point " + std::to_string(id) +
             ", but the piece has " + std::to_string(num_points) + " points (numbered from 0)",
         offset_of(connectivity));
  }

  const ScalarInfo& scalar_of(const pugi::xml_node& array) const {
    const std::string type = array.attribute("type").as_string();
    for (const ScalarInfo& info : kScalars) {
      if (type == info.name) return info;
    }
    fail("DataArray has unknown type '" + type + "'", offset_of(array));
  }

  std::uint64_t header_value(std::string_view block, std::size_t i) const {
    return header_bytes_ == 8 ? load<std::uint64_t>(block.data() + 8 * i, order_)
                              : load<std::uint32_t>(block.data() + 4 * i, order_);
  }

  // The decoded bytes of a binary or appended array (after decompression), header removed.
  std::string binary_payload(const pugi::xml_node& array, bool appended);
  // Values of an array converted to double, and the count checked against `expected` (if >= 0).
  template <typename T>
  std::vector<T> values(const pugi::xml_node& array, std::int64_t expected);

  std::string_view bytes_;
  std::string source_;
  ByteOrder order_ = ByteOrder::kLittle;
  std::size_t header_bytes_ = 4;
  bool compressed_ = false;
  std::string_view appended_;   // what follows the '_' marker of <AppendedData>
  bool appended_base64_ = false;
  std::string_view xml_text_;
};

std::string VtuReader::binary_payload(const pugi::xml_node& array, bool appended) {
  const std::ptrdiff_t where = offset_of(array);
  // `fetch(n)` returns the first n decoded bytes of this array's encoded stream.
  std::string inline_bytes;
  std::string scratch;
  std::string_view stream;
  std::size_t array_offset = 0;
  if (appended) {
    const auto offset_attr = array.attribute("offset");
    if (!offset_attr) fail("appended DataArray has no offset attribute", where);
    array_offset = offset_attr.as_ullong();
    if (array_offset > appended_.size()) fail("DataArray offset lies past the end of the appended data", where);
    stream = appended_.substr(array_offset);
  } else {
    if (!base64_decode(array.text().get(), SIZE_MAX, inline_bytes)) fail("DataArray holds invalid base64", where);
  }
  const bool base64_stream = appended && appended_base64_;
  auto fetch = [&](std::size_t n) -> std::string_view {
    if (base64_stream) {
      scratch.clear();
      if (!base64_decode(stream, n, scratch) || scratch.size() < n) fail("appended base64 data is truncated", where);
      return scratch;
    }
    const std::string_view all = appended ? stream : std::string_view(inline_bytes);
    if (all.size() < n) fail("binary data is truncated", where);
    return all.substr(0, n);
  };

  if (!compressed_) {
    const std::uint64_t size = header_value(fetch(header_bytes_), 0);
    if (size > bytes_.size() * 4 + 1024) fail("DataArray announces more bytes than the file can hold", where);
    return std::string(fetch(header_bytes_ + size).substr(header_bytes_));
  }
  const std::uint64_t blocks = header_value(fetch(3 * header_bytes_), 0);
  if (blocks > bytes_.size()) fail("compressed DataArray announces more blocks than the file can hold", where);
  const std::size_t header_size = (3 + blocks) * header_bytes_;
  std::string header(fetch(header_size));
  const std::uint64_t block_size = header_value(header, 1);
  const std::uint64_t last_size = header_value(header, 2);
  std::uint64_t total_compressed = 0;
  for (std::uint64_t b = 0; b < blocks; ++b) total_compressed += header_value(header, 3 + b);
  if (total_compressed > bytes_.size()) fail("compressed sizes exceed the file size", where);
  const std::string_view all = fetch(header_size + total_compressed);
  std::string out;
  std::size_t pos = header_size;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t csize = header_value(header, 3 + b);
    const std::uint64_t usize = (b + 1 == blocks && last_size != 0) ? last_size : block_size;
    if (usize > (std::uint64_t{1} << 34)) fail("compressed block size is implausible", where);
    if (!zlib_inflate(all.substr(pos, csize), usize, out)) fail("corrupt zlib data in DataArray", where);
    pos += csize;
  }
  return out;
}

template <typename T>
std::vector<T> VtuReader::values(const pugi::xml_node& array, std::int64_t expected) {
  const std::ptrdiff_t where = offset_of(array);
  const ScalarInfo& scalar = scalar_of(array);
  const std::string format = array.attribute("format").as_string("ascii");
  const std::string name = array.attribute("Name").as_string("(unnamed)");
  std::vector<T> out;
  if (format == "ascii") {
    const std::string_view text = array.text().get();
    TextScanner in(text, source_, '\0');
    while (auto token = in.try_token()) {
      if constexpr (std::is_floating_point_v<T>) {
        const auto v = parse_real(*token);
        if (!v) fail("DataArray '" + name + "' holds '" + std::string(*token) + "', not a number", where);
        out.push_back(*v);
      } else {
        const auto v = parse_integer(*token);
        if (!v) fail("DataArray '" + name + "' holds '" + std::string(*token) + "', not an integer", where);
        out.push_back(static_cast<T>(*v));
      }
    }
  } else if (format == "binary" || format == "appended") {
    const std::string payload = binary_payload(array, format == "appended");
    if (payload.size() % scalar.size != 0) fail("DataArray '" + name + "' has a partial value", where);
    const std::size_t n = payload.size() / scalar.size;
    out.resize(n);
    const char* p = payload.data();
    for (std::size_t i = 0; i < n; ++i, p += scalar.size) {
      switch (scalar.type) {
        case Scalar::kInt8: out[i] = static_cast<T>(load<std::int8_t>(p, order_)); break;
        case Scalar::kUInt8: out[i] = static_cast<T>(load<std::uint8_t>(p, order_)); break;
        case Scalar::kInt16: out[i] = static_cast<T>(load<std::int16_t>(p, order_)); break;
        case Scalar::kUInt16: out[i] = static_cast<T>(load<std::uint16_t>(p, order_)); break;
        case Scalar::kInt32: out[i] = static_cast<T>(load<std::int32_t>(p, order_)); break;
        case Scalar::kUInt32: out[i] = static_cast<T>(load<std::uint32_t>(p, order_)); break;
        case Scalar::kInt64: out[i] = static_cast<T>(load<std::int64_t>(p, order_)); break;
        case Scalar::kUInt64: out[i] = static_cast<T>(load<std::uint64_t>(p, order_)); break;
        case Scalar::kFloat32: out[i] = static_cast<T>(load<float>(p, order_)); break;
        case Scalar::kFloat64: out[i] = static_cast<T>(load<double>(p, order_)); break;
      }
    }
  } else {
    fail("DataArray '" + name + "' has unknown format '" + format + "'", where);
  }
  if (expected >= 0 && static_cast<std::int64_t>(out.size()) != expected) {
    fail("DataArray '" + name + "' holds " + std::to_string(out.size()) + " values, expected " +
             std::to_string(expected),
         where);
  }
  return out;
}

pugi::xml_node VtuReader::open(pugi::xml_document* doc, const char* type) {
  // Appended raw data is not XML; parse only what precedes it.
  xml_text_ = bytes_;
  std::string xml_copy;
  const std::size_t appended_tag = bytes_.find("<AppendedData");
  if (appended_tag != std::string_view::npos) {
    const std::size_t tag_end = bytes_.find('>', appended_tag);
    const std::size_t marker = bytes_.find('_', tag_end);
    if (tag_end == std::string_view::npos || marker == std::string_view::npos) {
      fail("malformed <AppendedData> element", static_cast<std::ptrdiff_t>(appended_tag));
    }
    const std::string_view tag = bytes_.substr(appended_tag, tag_end - appended_tag);
    appended_base64_ = tag.find("base64") != std::string_view::npos;
    appended_ = bytes_.substr(marker + 1);
    xml_copy = std::string(bytes_.substr(0, appended_tag)) + "</VTKFile>";
    xml_text_ = xml_copy;
  }
  const pugi::xml_parse_result parsed = doc->load_buffer(xml_text_.data(), xml_text_.size());
  if (!parsed) fail(std::string("not valid XML: ") + parsed.description(), parsed.offset);
  const pugi::xml_node file = doc->child("VTKFile");
  if (!file) fail("no <VTKFile> element");
  if (std::string(file.attribute("type").as_string()) != type) {
    fail("VTKFile type is '" + std::string(file.attribute("type").as_string()) + "', expected " + type, offset_of(file));
  }
  order_ = std::string(file.attribute("byte_order").as_string("LittleEndian")) == "BigEndian" ? ByteOrder::kBig
                                                                                            : ByteOrder::kLittle;
  header_bytes_ = std::string(file.attribute("header_type").as_string("UInt32")) == "UInt64" ? 8 : 4;
  const std::string compressor = file.attribute("compressor").as_string();
  compressed_ = !compressor.empty();
  if (compressed_ && compressor != "vtkZLibDataCompressor") {
    throw Error(ErrorKind::kUnsupported, "compressor " + compressor + " is not supported (zlib is)", source_);
  }
  const pugi::xml_node grid = file.child(type);
  if (!grid) fail(std::string("no <") + type + "> element", offset_of(file));
  return grid;
}

std::vector<double> VtuReader::point_coordinates(const pugi::xml_node& piece, std::int64_t num_points) {
  const pugi::xml_node points = piece.child("Points").child("DataArray");
  if (!points) fail("Piece has no <Points> DataArray", offset_of(piece));
  if (points.attribute("NumberOfComponents").as_int(1) != 3) fail("Points must have 3 components", offset_of(points));
  std::vector<double> coords = values<double>(points, num_points * 3);
  for (std::size_t i = 0; i < coords.size(); ++i) {
    if (!std::isfinite(coords[i])) {
      fail("point " + std::to_string(i / 3 + 1) + " has a coordinate that is not a finite number", offset_of(points));
    }
  }
  return coords;
}

TetMeshData VtuReader::read() {
  pugi::xml_document doc;
  const pugi::xml_node grid = open(&doc, "UnstructuredGrid");

  TetMeshData data;
  std::vector<double> xyz;
  std::vector<Index> ids;
  for (const pugi::xml_node& piece : grid.children("Piece")) {
    const std::int64_t num_points = piece.attribute("NumberOfPoints").as_llong(-1);
    const std::int64_t num_cells = piece.attribute("NumberOfCells").as_llong(-1);
    if (num_points < 0 || num_cells < 0) fail("Piece lacks NumberOfPoints or NumberOfCells", offset_of(piece));
    const std::vector<double> coords = point_coordinates(piece, num_points);
    const Index base = static_cast<Index>(xyz.size() / 3);
    xyz.insert(xyz.end(), coords.begin(), coords.end());

    pugi::xml_node connectivity, offsets, types;
    for (const pugi::xml_node& array : piece.child("Cells").children("DataArray")) {
      const std::string name = array.attribute("Name").as_string();
      if (name == "connectivity") connectivity = array;
      if (name == "offsets") offsets = array;
      if (name == "types") types = array;
    }
    if (!connectivity || !offsets || !types) {
      fail("Cells must hold connectivity, offsets and types arrays", offset_of(piece));
    }
    const auto conn = values<std::int64_t>(connectivity, -1);
    const auto offs = values<std::int64_t>(offsets, num_cells);
    const auto kinds = values<std::int64_t>(types, num_cells);
    std::int64_t start = 0;
    for (std::int64_t c = 0; c < num_cells; ++c) {
      const std::int64_t end = offs[static_cast<std::size_t>(c)];
      if (end < start || end > static_cast<std::int64_t>(conn.size())) {
        fail("cell " + std::to_string(c + 1) + " has an offset out of range", offset_of(offsets));
      }
      if (kinds[static_cast<std::size_t>(c)] == kVtkTetra) {
        if (end - start != 4) fail("tetrahedral cell " + std::to_string(c + 1) + " does not have 4 points",
                                   offset_of(connectivity));
        for (std::int64_t k = start; k < end; ++k) {
          const std::int64_t id = conn[static_cast<std::size_t>(k)];
          check_point_id("cell", c, id, num_points, connectivity);
          ids.push_back(base + static_cast<Index>(id));
        }
      }
      start = end;
    }
  }
  if (ids.empty()) fail("the file holds no tetrahedra (VTK cell type 10)");
  data.points = to_points(xyz);
  data.tets = to_tets(ids);
  return data;
}

std::vector<std::vector<std::int64_t>> VtuReader::cell_block(const pugi::xml_node& piece, const char* block, const char* what,
                                                               std::int64_t count, std::int64_t min_points, std::int64_t num_points) {
  std::vector<std::vector<std::int64_t>> cells;
  if (count == 0) return cells;
  pugi::xml_node connectivity, offsets;
  for (const pugi::xml_node& array : piece.child(block).children("DataArray")) {
    const std::string name = array.attribute("Name").as_string();
    if (name == "connectivity") connectivity = array;
    if (name == "offsets") offsets = array;
  }
  if (!connectivity || !offsets) fail(std::string(block) + " must hold connectivity and offsets arrays", offset_of(piece));
  const auto conn = values<std::int64_t>(connectivity, -1);
  const auto offs = values<std::int64_t>(offsets, count);
  std::int64_t start = 0;
  for (std::int64_t c = 0; c < count; ++c) {
    const std::int64_t end = offs[static_cast<std::size_t>(c)];
    if (end < start + min_points || end > static_cast<std::int64_t>(conn.size())) {
      fail(std::string(what) + " " + std::to_string(c + 1) + " has fewer than " + std::to_string(min_points) +
               " points or an offset out of range",
           offset_of(offsets));
    }
    std::vector<std::int64_t>& cell = cells.emplace_back();
    for (std::int64_t k = start; k < end; ++k) {
      check_point_id(what, c, conn[static_cast<std::size_t>(k)], num_points, connectivity);
      cell.push_back(conn[static_cast<std::size_t>(k)]);
    }
    start = end;
  }
  return cells;
}

TriangleSurface VtuReader::read_polydata() {
  pugi::xml_document doc;
  const pugi::xml_node poly = open(&doc, "PolyData");
  std::vector<double> xyz;
  std::vector<Index> corners;
  for (const pugi::xml_node& piece : poly.children("Piece")) {
    const std::int64_t num_points = piece.attribute("NumberOfPoints").as_llong(-1);
    const std::int64_t num_polys = piece.attribute("NumberOfPolys").as_llong(0);
    if (num_points < 0) fail("Piece lacks NumberOfPoints", offset_of(piece));
    const std::vector<double> coords = point_coordinates(piece, num_points);
    const Index base = static_cast<Index>(xyz.size() / 3);
    xyz.insert(xyz.end(), coords.begin(), coords.end());
    for (const auto& polygon : cell_block(piece, "Polys", "polygon", num_polys, 3, num_points)) {
      // A fan around the first corner.
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
        for (const std::int64_t id : {polygon[0], polygon[k], polygon[k + 1]}) corners.push_back(base + static_cast<Index>(id));
      }
    }
  }
  TriangleSurface surface;
  surface.vertices = to_points(xyz);
  surface.triangles.resize(static_cast<Index>(corners.size() / 3), 3);
  for (std::size_t i = 0; i < corners.size(); ++i) surface.triangles(static_cast<Index>(i / 3), static_cast<int>(i % 3)) = corners[i];
  return surface;
}

std::vector<Points> VtuReader::read_polydata_lines() {
  pugi::xml_document doc;
  const pugi::xml_node poly = open(&doc, "PolyData");
  std::vector<Points> lines;
  for (const pugi::xml_node& piece : poly.children("Piece")) {
    const std::int64_t num_points = piece.attribute("NumberOfPoints").as_llong(-1);
    const std::int64_t num_lines = piece.attribute("NumberOfLines").as_llong(0);
    if (num_points < 0) fail("Piece lacks NumberOfPoints", offset_of(piece));
    const std::vector<double> coords = point_coordinates(piece, num_points);
    for (const auto& line : cell_block(piece, "Lines", "line", num_lines, 2, num_points)) {
      Points& points = lines.emplace_back(static_cast<Index>(line.size()), 3);
      for (std::size_t k = 0; k < line.size(); ++k) {
        for (int j = 0; j < 3; ++j) points(static_cast<Index>(k), j) = coords[3 * static_cast<std::size_t>(line[k]) + j];
      }
    }
  }
  return lines;
}

void write_binary_array(std::ostream& out, const char* type, const char* name, int components, const std::string& bytes) {
  out << "<DataArray type=\"" << type << "\" Name=\"" << name << "\"";
  if (components != 1) out << " NumberOfComponents=\"" << components << "\"";
  out << " format=\"binary\">\n";
  std::string header;
  store_le<std::uint64_t>(header, bytes.size());
  // Header and data are encoded as two base64 streams, as VTK itself writes them.
  out << base64_encode(header) << base64_encode(bytes) << "\n</DataArray>\n";
}

// The Points element's array: coordinates as Float64 triples.
void write_points_array(std::ostream& out, const Points& points) {
  std::string bytes;
  bytes.reserve(static_cast<std::size_t>(points.size()) * 8);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    for (int k = 0; k < 3; ++k) store_le<double>(bytes, points(i, k));
  }
  write_binary_array(out, "Float64", "Points", 3, bytes);
}

// Connectivity and offsets of cells that each list cells.cols() point ids (one row per cell).
template <typename Cells>
void write_connectivity(std::ostream& out, const Cells& cells) {
  std::string bytes;
  for (Eigen::Index c = 0; c < cells.rows(); ++c) {
    for (Eigen::Index k = 0; k < cells.cols(); ++k) store_le<std::int64_t>(bytes, cells(c, k));
  }
  write_binary_array(out, "Int64", "connectivity", 1, bytes);
  bytes.clear();
  for (Eigen::Index c = 0; c < cells.rows(); ++c) store_le<std::int64_t>(bytes, cells.cols() * (c + 1));
  write_binary_array(out, "Int64", "offsets", 1, bytes);
}

std::vector<SeriesEntry> VtuReader::read_collection() {
  pugi::xml_document doc;
  const pugi::xml_node collection = open(&doc, "Collection");
  std::vector<SeriesEntry> entries;
  for (const pugi::xml_node& dataset : collection.children("DataSet")) {
    const std::string file = dataset.attribute("file").as_string();
    if (file.empty()) fail("DataSet has no file attribute", offset_of(dataset));
    const std::string time_text = dataset.attribute("timestep").as_string("0");
    char* end = nullptr;
    const double time = std::strtod(time_text.c_str(), &end);
    if (end == time_text.c_str() || *end != '\0' || !std::isfinite(time)) {
      fail("DataSet timestep '" + time_text + "' is not a finite number", offset_of(dataset));
    }
    entries.push_back({time, file});
  }
  if (entries.empty()) fail("the collection has no <DataSet> elements", offset_of(collection));
  return entries;
}

}  // namespace

std::vector<SeriesEntry> read_pvd(std::string_view bytes, const std::string& source) {
  return VtuReader(bytes, source).read_collection();
}

void write_pvd(std::ostream& out, const std::vector<SeriesEntry>& entries) {
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\">\n<Collection>\n";
  out.precision(17);
  for (const SeriesEntry& entry : entries) {
    out << "<DataSet timestep=\"" << entry.time << "\" part=\"0\" file=\"" << entry.file.generic_string() << "\"/>\n";
  }
  out << "</Collection>\n</VTKFile>\n";
}

TetMeshData read_vtu(std::string_view bytes, const std::string& source) { return VtuReader(bytes, source).read(); }
TriangleSurface read_vtp(std::string_view bytes, const std::string& source) { return VtuReader(bytes, source).read_polydata(); }

std::vector<Points> read_vtp_lines(std::string_view bytes, const std::string& source) {
  return VtuReader(bytes, source).read_polydata_lines();
}


void write_vtu(std::ostream& out, const Points& points, const Tets& tets, const std::vector<CellField>& fields) {
  out << "<?xml version=\"1.0\"?>\n"
         "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
         "<UnstructuredGrid>\n<Piece NumberOfPoints=\""
      << points.rows() << "\" NumberOfCells=\"" << tets.rows() << "\">\n<Points>\n";
  write_points_array(out, points);
  out << "</Points>\n<Cells>\n";
  write_connectivity(out, tets);
  std::string bytes;
  bytes.assign(static_cast<std::size_t>(tets.rows()), static_cast<char>(kVtkTetra));
  write_binary_array(out, "UInt8", "types", 1, bytes);
  out << "</Cells>\n";
  if (!fields.empty()) {
    out << "<CellData>\n";
    for (const CellField& field : fields) {
      if (static_cast<Eigen::Index>(field.values.size()) != tets.rows()) {
        throw Error(ErrorKind::kInvalidArgument, "cell field '" + field.name + "' has " +
                                                     std::to_string(field.values.size()) + " values for " +
                                                     std::to_string(tets.rows()) + " cells");
      }
      bytes.clear();
      for (const double v : field.values) {
        if (field.integer) {
          store_le<std::int64_t>(bytes, static_cast<std::int64_t>(v));
        } else {
          store_le<double>(bytes, v);
        }
      }
      write_binary_array(out, field.integer ? "Int64" : "Float64", field.name.c_str(), 1, bytes);
    }
    out << "</CellData>\n";
  }
  out << "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
}

void write_vtp(std::ostream& out, const Points& points, const Triangles& triangles) {
  out << "<?xml version=\"1.0\"?>\n"
         "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
         "<PolyData>\n<Piece NumberOfPoints=\""
      << points.rows() << "\" NumberOfPolys=\"" << triangles.rows() << "\">\n<Points>\n";
  write_points_array(out, points);
  out << "</Points>\n<Polys>\n";
  write_connectivity(out, triangles);
  out << "</Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n";
}

}  // namespace tetcut::io
