// PLY (ASCII, binary little- and big-endian) and STL (ASCII and binary) surfaces.

#include <array>
#include <cstring>
#include <string>
#include <unordered_map>

#include "io/binary.hpp"
#include "io/formats.hpp"
#include "io/text_scanner.hpp"

namespace tetcut::io {
namespace {

struct PlyProperty {
  std::string name;
  std::string type;        // value type (list entries for lists)
  std::string count_type;  // non-empty for list properties
};

struct PlyElement {
  std::string name;
  std::int64_t count = 0;
  std::vector<PlyProperty> properties;
};

std::size_t ply_type_size(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

double ply_load(const char* p, const std::string& type, ByteOrder order) {
  if (type == "char" || type == "int8") return load<std::int8_t>(p, order);
  if (type == "uchar" || type == "uint8") return load<std::uint8_t>(p, order);
  if (type == "short" || type == "int16") return load<std::int16_t>(p, order);
  if (type == "ushort" || type == "uint16") return load<std::uint16_t>(p, order);
  if (type == "int" || type == "int32") return load<std::int32_t>(p, order);
  if (type == "uint" || type == "uint32") return load<std::uint32_t>(p, order);
  if (type == "float" || type == "float32") return load<float>(p, order);
  return load<double>(p, order);
}

// Reads PLY values one at a time from ASCII tokens or binary bytes.
class PlyValues {
 public:
  PlyValues(std::string_view bytes, std::size_t start, const std::string& source, bool ascii, ByteOrder order)
      : bytes_(bytes), pos_(start), source_(source), ascii_(ascii), order_(order),
        text_(bytes.substr(start), source, '\0') {}

  double next(const std::string& type, const char* what) {
    if (ascii_) return text_.real(what);
    const std::size_t size = ply_type_size(type);
    if (pos_ + size > bytes_.size()) {
      throw Error(ErrorKind::kInvalidInput, std::string("binary data ends early, while reading ") + what, source_);
    }
    const double v = ply_load(bytes_.data() + pos_, type, order_);
    pos_ += size;
    return v;
  }
  [[noreturn]] void fail(const std::string& message) {
    if (ascii_) text_.fail(message);
    throw Error(ErrorKind::kInvalidInput, message, source_);
  }

 private:
  std::string_view bytes_;
  std::size_t pos_;
  const std::string& source_;
  bool ascii_;
  ByteOrder order_;
  TextScanner text_;  // line numbers count from the end of the header
};

}  // namespace

TriangleSurface read_ply(std::string_view bytes, const std::string& source) {
  TextScanner header(bytes, source, '\0');
  if (header.rest_of_line() != "ply") header.fail("not a PLY file (first line is not 'ply')");
  std::string format;
  std::vector<PlyElement> elements;
  while (true) {
    if (header.at_end()) header.fail("the header has no end_header line");
    const std::string_view line = header.rest_of_line();
    TextScanner words(line, source, '\0');
    const auto keyword = words.try_token();
    if (!keyword || *keyword == "comment" || *keyword == "obj_info") continue;
    if (*keyword == "end_header") break;
    if (*keyword == "format") {
      format = std::string(words.token("format"));
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") {
        header.fail("unknown PLY format '" + format + "'");
      }
    } else if (*keyword == "element") {
      PlyElement element;
      element.name = std::string(words.token("element name"));
      const auto count = parse_integer(words.token("element count"));
      if (!count) header.fail("element count is not an integer");
      check_count(*count, bytes.size(), 1, "elements", source, header.line());
      element.count = *count;
      elements.push_back(element);
    } else if (*keyword == "property") {
      if (elements.empty()) header.fail("property before any element");
      PlyProperty property;
      std::string type(words.token("property type"));
      if (type == "list") {
        property.count_type = std::string(words.token("list count type"));
        type = std::string(words.token("list value type"));
        if (ply_type_size(property.count_type) == 0) header.fail("unknown PLY type '" + property.count_type + "'");
      }
      if (ply_type_size(type) == 0) header.fail("unknown PLY type '" + type + "'");
      property.type = type;
      property.name = std::string(words.token("property name"));
      elements.back().properties.push_back(property);
    } else {
      header.fail("unknown PLY header keyword '" + std::string(*keyword) + "'");
    }
  }
  if (format.empty()) header.fail("the header has no format line");
  PlyValues values(bytes, header.offset(), source, format == "ascii",
                   format == "binary_big_endian" ? ByteOrder::kBig : ByteOrder::kLittle);

  std::vector<double> xyz;
  std::vector<Index> triangles;
  std::vector<Index> polygon;
  std::int64_t num_vertices = -1;
  for (const PlyElement& element : elements) {
    const bool is_vertex = element.name == "vertex";
    const bool is_face = element.name == "face";
    int axis_of[3] = {-1, -1, -1};
    int face_list = -1;
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& property = element.properties[p];
      if (is_vertex && property.count_type.empty()) {
        if (property.name == "x") axis_of[0] = static_cast<int>(p);
        if (property.name == "y") axis_of[1] = static_cast<int>(p);
        if (property.name == "z") axis_of[2] = static_cast<int>(p);
      }
      if (is_face && !property.count_type.empty() &&
          (property.name == "vertex_indices" || property.name == "vertex_index")) {
        face_list = static_cast<int>(p);
      }
    }
    if (is_vertex) {
      if (axis_of[0] < 0 || axis_of[1] < 0 || axis_of[2] < 0) values.fail("vertex element lacks x, y or z");
      num_vertices = element.count;
      xyz.reserve(static_cast<std::size_t>(element.count) * 3);
    }
    if (is_face) {
      if (face_list < 0) values.fail("face element has no vertex_indices list");
      if (num_vertices < 0) values.fail("face element comes before the vertex element");
    }
    for (std::int64_t i = 0; i < element.count; ++i) {
      double position[3] = {0, 0, 0};
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (property.count_type.empty()) {
          const double v = values.next(property.type, "a property value");
          for (int k = 0; k < 3; ++k) {
            if (static_cast<int>(p) == axis_of[k]) position[k] = v;
          }
          continue;
        }
        const double count = values.next(property.count_type, "a list count");
        if (count < 0 || count > (1 << 20)) values.fail("list count " + std::to_string(count) + " is out of range");
        const bool keep = is_face && static_cast<int>(p) == face_list;
        if (keep) polygon.clear();
        for (int k = 0; k < static_cast<int>(count); ++k) {
          const double v = values.next(property.type, "a list entry");
          if (!keep) continue;
          if (v < 0 || v >= static_cast<double>(num_vertices) || v != static_cast<double>(static_cast<std::int64_t>(v))) {
            values.fail("face " + std::to_string(i + 1) + " refers to vertex " + std::to_string(v) +
                        ", but there are " + std::to_string(num_vertices) + " vertices (numbered from 0)");
          }
          polygon.push_back(static_cast<Index>(v));
        }
        if (keep) {
          if (polygon.size() < 3) values.fail("face " + std::to_string(i + 1) + " has fewer than 3 corners");
          for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
            triangles.insert(triangles.end(), {polygon[0], polygon[k], polygon[k + 1]});
          }
        }
      }
      if (is_vertex) {
        for (int k = 0; k < 3; ++k) {
          if (!std::isfinite(position[k])) {
            values.fail("vertex " + std::to_string(i + 1) + " has a coordinate that is not a finite number");
          }
          xyz.push_back(position[k]);
        }
      }
    }
  }
  if (num_vertices < 0) values.fail("no vertex element");
  TriangleSurface surface;
  surface.vertices = to_points(xyz);
  surface.triangles = to_triangles(triangles);
  return surface;
}

void write_ply(std::ostream& out, const TriangleSurface& surface, bool binary) {
  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\ncomment written by tetcut\n"
      << "element vertex " << surface.num_vertices() << "\nproperty double x\nproperty double y\nproperty double z\n"
      << "element face " << surface.num_triangles() << "\nproperty list uchar int vertex_indices\nend_header\n";
  if (binary) {
    std::string bytes;
    for (Eigen::Index i = 0; i < surface.vertices.rows(); ++i) {
      for (int k = 0; k < 3; ++k) store_le<double>(bytes, surface.vertices(i, k));
    }
    for (Eigen::Index f = 0; f < surface.triangles.rows(); ++f) {
      store_le<std::uint8_t>(bytes, 3);
      for (int k = 0; k < 3; ++k) store_le<std::int32_t>(bytes, surface.triangles(f, k));
    }
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return;
  }
  for (Eigen::Index i = 0; i < surface.vertices.rows(); ++i) {
    write_real(out, surface.vertices(i, 0));
    out << ' ';
    write_real(out, surface.vertices(i, 1));
    out << ' ';
    write_real(out, surface.vertices(i, 2));
    out << '\n';
  }
  for (Eigen::Index f = 0; f < surface.triangles.rows(); ++f) {
    out << "3 " << surface.triangles(f, 0) << ' ' << surface.triangles(f, 1) << ' ' << surface.triangles(f, 2) << '\n';
  }
}

namespace {

// STL stores every corner separately; corners with bit-identical coordinates become one vertex.
// Exact equality (with -0 folded onto +0) merges only true copies, never nearby points.
class VertexWelder {
 public:
  Index add(double x, double y, double z) {
    const std::array<double, 3> key{x + 0.0, y + 0.0, z + 0.0};
    std::string bytes(reinterpret_cast<const char*>(key.data()), sizeof key);
    const auto [it, inserted] = ids_.emplace(std::move(bytes), static_cast<Index>(xyz_.size() / 3));
    if (inserted) xyz_.insert(xyz_.end(), key.begin(), key.end());
    return it->second;
  }
  const std::vector<double>& xyz() const { return xyz_; }

 private:
  std::unordered_map<std::string, Index> ids_;
  std::vector<double> xyz_;
};

constexpr std::size_t kStlHeaderBytes = 80;
constexpr std::size_t kStlTriangleBytes = 50;

}  // namespace

TriangleSurface read_stl(std::string_view bytes, const std::string& source) {
  VertexWelder welder;
  std::vector<Index> triangles;
  bool binary = false;
  if (bytes.size() >= kStlHeaderBytes + 4) {
    const std::uint32_t count = load<std::uint32_t>(bytes.data() + kStlHeaderBytes, ByteOrder::kLittle);
    binary = bytes.size() == kStlHeaderBytes + 4 + std::size_t{count} * kStlTriangleBytes;
  }
  const bool starts_solid = bytes.substr(0, 5) == "solid";
  if (binary) {
    const std::uint32_t count = load<std::uint32_t>(bytes.data() + kStlHeaderBytes, ByteOrder::kLittle);
    for (std::uint32_t f = 0; f < count; ++f) {
      const char* p = bytes.data() + kStlHeaderBytes + 4 + std::size_t{f} * kStlTriangleBytes + 12;  // skip normal
      for (int k = 0; k < 3; ++k, p += 12) {
        double v[3];
        for (int a = 0; a < 3; ++a) {
          v[a] = load<float>(p + 4 * a, ByteOrder::kLittle);
          if (!std::isfinite(v[a])) {
            throw Error(ErrorKind::kInvalidInput,
                        "triangle " + std::to_string(f + 1) + " has a coordinate that is not a finite number", source);
          }
        }
        triangles.push_back(welder.add(v[0], v[1], v[2]));
      }
    }
  } else if (starts_solid) {
    TextScanner in(bytes, source, '\0');
    in.expect("solid");
    in.rest_of_line();  // solid name
    while (auto keyword = in.try_token()) {
      if (*keyword == "endsolid") {
        in.rest_of_line();
        continue;
      }
      if (*keyword == "solid") {
        in.rest_of_line();
        continue;
      }
      if (*keyword != "facet") in.fail("expected 'facet' or 'endsolid', found '" + std::string(*keyword) + "'");
      in.expect("normal");
      for (int a = 0; a < 3; ++a) in.real("normal component");
      in.expect("outer");
      in.expect("loop");
      for (int k = 0; k < 3; ++k) {
        in.expect("vertex");
        const double x = in.real("vertex x"), y = in.real("vertex y"), z = in.real("vertex z");
        triangles.push_back(welder.add(x, y, z));
      }
      in.expect("endloop");
      in.expect("endfacet");
    }
  } else if (bytes.size() >= kStlHeaderBytes + 4) {
    const std::uint32_t count = load<std::uint32_t>(bytes.data() + kStlHeaderBytes, ByteOrder::kLittle);
    throw Error(ErrorKind::kInvalidInput,
                "binary STL announces " + std::to_string(count) + " triangles, which need " +
                    std::to_string(kStlHeaderBytes + 4 + std::size_t{count} * kStlTriangleBytes) +
                    " bytes, but the file has " + std::to_string(bytes.size()) + " (truncated?)",
                source);
  } else {
    throw Error(ErrorKind::kInvalidInput, "too short to be an STL file", source);
  }
  TriangleSurface surface;
  surface.vertices = to_points(welder.xyz());
  surface.triangles = to_triangles(triangles);
  return surface;
}

void write_stl(std::ostream& out, const TriangleSurface& surface, bool binary) {
  const auto normal_of = [&](Eigen::Index f) -> Eigen::Vector3d {
    const Vec3 a = surface.vertices.row(surface.triangles(f, 0));
    const Vec3 b = surface.vertices.row(surface.triangles(f, 1));
    const Vec3 c = surface.vertices.row(surface.triangles(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    const double length = n.norm();
    return length > 0 ? Vec3(n / length) : Vec3::Zero();
  };
  if (binary) {
    std::string bytes(kStlHeaderBytes, ' ');
    const char title[] = "binary STL written by tetcut";
    std::memcpy(bytes.data(), title, sizeof title - 1);
    store_le<std::uint32_t>(bytes, static_cast<std::uint32_t>(surface.num_triangles()));
    for (Eigen::Index f = 0; f < surface.triangles.rows(); ++f) {
      const Vec3 n = normal_of(f);
      for (int a = 0; a < 3; ++a) store_le<float>(bytes, static_cast<float>(n[a]));
      for (int k = 0; k < 3; ++k) {
        for (int a = 0; a < 3; ++a) store_le<float>(bytes, static_cast<float>(surface.vertices(surface.triangles(f, k), a)));
      }
      store_le<std::uint16_t>(bytes, 0);
    }
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return;
  }
  out << "solid tetcut\n";
  for (Eigen::Index f = 0; f < surface.triangles.rows(); ++f) {
    const Vec3 n = normal_of(f);
    out << "facet normal ";
    write_real(out, n[0]);
    out << ' ';
    write_real(out, n[1]);
    out << ' ';
    write_real(out, n[2]);
    out << "\nouter loop\n";
    for (int k = 0; k < 3; ++k) {
      out << "vertex ";
      for (int a = 0; a < 3; ++a) {
        write_real(out, surface.vertices(surface.triangles(f, k), a));
        out << (a < 2 ? ' ' : '\n');
      }
    }
    out << "endloop\nendfacet\n";
  }
  out << "endsolid tetcut\n";
}

}  // namespace tetcut::io
