// Gmsh .msh, ASCII, versions 2.2 and 4.1. Linear tetrahedra (element type 4) are kept; every other
// element type is skipped, and so are sections other than $MeshFormat, $Nodes and $Elements.

#include <algorithm>
#include <string>
#include <unordered_map>

#include "io/formats.hpp"
#include "io/text_scanner.hpp"

namespace tetcut::io {
namespace {

constexpr std::int64_t kGmshTetrahedron = 4;

struct GmshReader {
  TextScanner& in;
  std::size_t file_size;
  std::vector<double> xyz;
  std::unordered_map<std::int64_t, Index> node_of_tag;
  std::vector<Index> ids;
  std::vector<std::int64_t> tet_lines;

  void add_node(std::int64_t tag, double x, double y, double z) {
    if (!node_of_tag.emplace(tag, static_cast<Index>(xyz.size() / 3)).second) {
      in.fail("node " + std::to_string(tag) + " is defined twice");
    }
    xyz.insert(xyz.end(), {x, y, z});
  }

  void add_tet_node(std::int64_t tag, std::int64_t element) {
    const auto it = node_of_tag.find(tag);
    if (it == node_of_tag.end()) {
      in.fail("element " + std::to_string(element) + " refers to node " + std::to_string(tag) + ", which is not defined");
    }
    ids.push_back(it->second);
  }

  void end_section(std::string_view name) {
    const std::string end = "$End" + std::string(name.substr(1));
    const std::string_view t = in.token(end);
    if (t != end) in.fail("expected " + end + ", found '" + std::string(t) + "'");
  }

  void read_nodes_v2() {
    const std::int64_t n = in.integer("node count");
    check_count(n, file_size, 8, "nodes", in.source(), in.line());
    xyz.reserve(static_cast<std::size_t>(n) * 3);
    for (std::int64_t i = 0; i < n; ++i) {
      const std::int64_t tag = in.integer("node number");
      const double x = in.real("node x"), y = in.real("node y"), z = in.real("node z");
      add_node(tag, x, y, z);
    }
  }

  void read_elements_v2() {
    const std::int64_t n = in.integer("element count");
    check_count(n, file_size, 8, "elements", in.source(), in.line());
    in.rest_of_line();
    for (std::int64_t i = 0; i < n; ++i) {
      const std::int64_t element = in.integer("element number");
      const std::int64_t type = in.integer("element type");
      if (type != kGmshTetrahedron) {
        in.rest_of_line();
        continue;
      }
      tet_lines.push_back(in.line());
      const std::int64_t tags = in.integer_in("number of tags", 0, 100);
      for (std::int64_t k = 0; k < tags; ++k) in.integer("element tag");
      for (int k = 0; k < 4; ++k) add_tet_node(in.integer("tetrahedron node"), element);
      if (!is_blank(in.rest_of_line())) in.fail("element " + std::to_string(element) + " has more than 4 nodes");
    }
  }

  void read_nodes_v4() {
    const std::int64_t blocks = in.integer("number of node blocks");
    const std::int64_t n = in.integer("node count");
    check_count(n, file_size, 8, "nodes", in.source(), in.line());
    check_count(blocks, file_size, 8, "node blocks", in.source(), in.line());
    in.integer("minimum node tag");
    in.integer("maximum node tag");
    xyz.reserve(static_cast<std::size_t>(n) * 3);
    std::vector<std::int64_t> tags;
    for (std::int64_t b = 0; b < blocks; ++b) {
      in.integer_in("entity dimension", 0, 3);
      in.integer("entity tag");
      const std::int64_t parametric = in.integer_in("parametric flag", 0, 1);
      const std::int64_t count = in.integer("nodes in block");
      check_count(count, file_size, 8, "nodes", in.source(), in.line());
      tags.clear();
      for (std::int64_t i = 0; i < count; ++i) tags.push_back(in.integer("node tag"));
      for (std::int64_t i = 0; i < count; ++i) {
        const double x = in.real("node x"), y = in.real("node y"), z = in.real("node z");
        // Parametric coordinates (u, v, w) follow on the same line; we do not need them.
        if (parametric != 0) in.rest_of_line();
        add_node(tags[static_cast<std::size_t>(i)], x, y, z);
      }
    }
    if (static_cast<std::int64_t>(xyz.size() / 3) != n) {
      in.fail("the $Nodes header announces " + std::to_string(n) + " nodes, the blocks hold " +
              std::to_string(xyz.size() / 3));
    }
  }

  void read_elements_v4() {
    const std::int64_t blocks = in.integer("number of element blocks");
    const std::int64_t n = in.integer("element count");
    check_count(n, file_size, 4, "elements", in.source(), in.line());
    check_count(blocks, file_size, 8, "element blocks", in.source(), in.line());
    in.integer("minimum element tag");
    in.integer("maximum element tag");
    for (std::int64_t b = 0; b < blocks; ++b) {
      in.integer_in("entity dimension", 0, 3);
      in.integer("entity tag");
      const std::int64_t type = in.integer("element type");
      const std::int64_t count = in.integer("elements in block");
      check_count(count, file_size, 4, "elements", in.source(), in.line());
      in.rest_of_line();
      for (std::int64_t i = 0; i < count; ++i) {
        if (type != kGmshTetrahedron) {
          in.rest_of_line();
          continue;
        }
        const std::int64_t element = in.integer("element tag");
        tet_lines.push_back(in.line());
        for (int k = 0; k < 4; ++k) add_tet_node(in.integer("tetrahedron node"), element);
        if (!is_blank(in.rest_of_line())) in.fail("element " + std::to_string(element) + " has more than 4 nodes");
      }
    }
  }
};

}  // namespace

TetMeshData read_gmsh(std::string_view text, const std::string& source) {
  TextScanner in(text, source, '\0');
  GmshReader reader{in, text.size(), {}, {}, {}, {}};
  in.expect("$MeshFormat");
  const std::string_view version = in.token("format version");
  const std::int64_t file_type = in.integer("file type");
  in.integer("data size");
  int major = 0;
  if (version == "2.2" || version == "2.1" || version == "2") {
    major = 2;
  } else if (version == "4.1") {
    major = 4;
  } else {
    throw Error(ErrorKind::kUnsupported,
                "Gmsh format version " + std::string(version) + " is not supported (2.2 and 4.1 are)", source,
                in.line());
  }
  if (file_type != 0) {
    throw Error(ErrorKind::kUnsupported, "binary Gmsh files are not supported; save the mesh as ASCII", source,
                in.line());
  }
  reader.end_section("$MeshFormat");
  bool have_nodes = false;
  bool have_elements = false;
  while (!in.at_end()) {
    const std::string_view section = in.token("a section");
    if (section.empty() || section.front() != '$' || section.starts_with("$End")) {
      in.fail("expected a section such as $Nodes, found '" + std::string(section) + "'");
    }
    if (section == "$Nodes") {
      if (have_nodes) in.fail("a second $Nodes section");
      have_nodes = true;
      major == 2 ? reader.read_nodes_v2() : reader.read_nodes_v4();
      reader.end_section(section);
    } else if (section == "$Elements") {
      if (!have_nodes) in.fail("$Elements before $Nodes");
      have_elements = true;
      major == 2 ? reader.read_elements_v2() : reader.read_elements_v4();
      reader.end_section(section);
    } else {
      // Any other section ($PhysicalNames, $Entities, $NodeData, ...) is skipped whole.
      const std::string end = "$End" + std::string(section.substr(1));
      while (true) {
        const std::string_view t = in.token(end);
        if (t == end) break;
      }
    }
  }
  if (!have_nodes) in.fail("no $Nodes section");
  if (!have_elements) in.fail("no $Elements section");
  if (reader.ids.empty()) in.fail("the mesh holds no tetrahedra (element type 4)");
  TetMeshData data;
  data.points = to_points(reader.xyz);
  data.tets = to_tets(reader.ids);
  data.tet_lines = std::move(reader.tet_lines);
  return data;
}

void write_gmsh(std::ostream& out, const Points& points, const Tets& tets, int version, const std::vector<Index>& labels) {
  // Gmsh tags are positive: label + 1, or 1 for every tet without labels.
  const auto tag = [&](Eigen::Index t) -> Index { return labels.empty() ? 1 : labels[t] + 1; };
  const auto write_xyz = [&](Eigen::Index i) {
    for (int k = 0; k < 3; ++k) {
      out << ' ';
      write_real(out, points(i, k));
    }
    out << '\n';
  };
  if (version == 22) {
    out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << points.rows() << '\n';
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
      out << i + 1;
      write_xyz(i);
    }
    out << "$EndNodes\n$Elements\n" << tets.rows() << '\n';
    for (Eigen::Index t = 0; t < tets.rows(); ++t) {
      out << t + 1 << " 4 2 " << tag(t) << ' ' << tag(t) << ' ' << tets(t, 0) + 1 << ' ' << tets(t, 1) + 1 << ' '
          << tets(t, 2) + 1 << ' ' << tets(t, 3) + 1 << '\n';
    }
    out << "$EndElements\n";
    return;
  }
  if (version != 41) {
    throw Error(ErrorKind::kInvalidArgument, "Gmsh version must be 22 or 41, not " + std::to_string(version));
  }
  // One volume entity per tag, each with that physical tag; all nodes sit in the first entity
  // (Gmsh numbers nodes globally, so elements may use nodes of any entity).
  std::vector<std::vector<Eigen::Index>> by_tag;
  std::vector<Index> tags;
  {
    std::vector<Index> all(static_cast<std::size_t>(tets.rows()));
    for (Eigen::Index t = 0; t < tets.rows(); ++t) all[t] = tag(t);
    tags = all;
    std::sort(tags.begin(), tags.end());
    tags.erase(std::unique(tags.begin(), tags.end()), tags.end());
    if (tags.empty()) tags.push_back(1);
    by_tag.resize(tags.size());
    for (Eigen::Index t = 0; t < tets.rows(); ++t) {
      by_tag[std::lower_bound(tags.begin(), tags.end(), all[t]) - tags.begin()].push_back(t);
    }
  }
  out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  out << "$Entities\n0 0 0 " << tags.size() << '\n';
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
  if (points.rows() > 0) {
    lo = points.colwise().minCoeff().transpose();
    hi = points.colwise().maxCoeff().transpose();
  }
  for (const Index t : tags) {
    out << t << ' ';
    for (int k = 0; k < 3; ++k) {
      write_real(out, lo[k]);
      out << ' ';
    }
    for (int k = 0; k < 3; ++k) {
      write_real(out, hi[k]);
      out << ' ';
    }
    out << "1 " << t << " 0\n";
  }
  out << "$EndEntities\n";
  const Eigen::Index n = points.rows();
  out << "$Nodes\n1 " << n << " 1 " << n << "\n3 " << tags.front() << " 0 " << n << '\n';
  for (Eigen::Index i = 0; i < n; ++i) out << i + 1 << '\n';
  for (Eigen::Index i = 0; i < n; ++i) {
    write_real(out, points(i, 0));
    out << ' ';
    write_real(out, points(i, 1));
    out << ' ';
    write_real(out, points(i, 2));
    out << '\n';
  }
  out << "$EndNodes\n";
  const Eigen::Index m = tets.rows();
  out << "$Elements\n" << tags.size() << ' ' << m << " 1 " << m << '\n';
  for (std::size_t b = 0; b < tags.size(); ++b) {
    out << "3 " << tags[b] << " 4 " << by_tag[b].size() << '\n';
    for (const Eigen::Index t : by_tag[b]) {
      out << t + 1 << ' ' << tets(t, 0) + 1 << ' ' << tets(t, 1) + 1 << ' ' << tets(t, 2) + 1 << ' ' << tets(t, 3) + 1
          << '\n';
    }
  }
  out << "$EndElements\n";
}

}  // namespace tetcut::io
