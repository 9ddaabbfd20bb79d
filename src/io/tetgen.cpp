// TetGen .node / .ele. Node numbering starts at 0 or 1 (TetGen's -z switch), taken from the first
// node; extra attribute and boundary-marker columns are skipped.

#include <string>
#include <unordered_map>

#include "io/formats.hpp"
#include "io/text_scanner.hpp"

namespace tetcut::io {

TetgenNodes read_tetgen_nodes(std::string_view node_text, const std::string& node_source) {
  TextScanner nodes(node_text, node_source);
  const std::int64_t num_nodes = nodes.integer("node count");
  check_count(num_nodes, node_text.size(), 8, "nodes", node_source, nodes.line());
  if (num_nodes == 0) nodes.fail("the .node file lists no nodes");
  const std::int64_t dim = nodes.integer("dimension");
  if (dim != 3) nodes.fail("only 3D meshes can be read (dimension is " + std::to_string(dim) + ")");
  nodes.integer_in("attribute count", 0, 1000);
  nodes.integer_in("boundary marker flag", 0, 1);
  nodes.rest_of_line();
  std::vector<double> xyz;
  xyz.reserve(static_cast<std::size_t>(num_nodes) * 3);
  std::unordered_map<std::int64_t, Index> node_of_id;
  for (std::int64_t i = 0; i < num_nodes; ++i) {
    const std::int64_t id = nodes.integer("node number");
    if (!node_of_id.emplace(id, static_cast<Index>(i)).second) {
      nodes.fail("node " + std::to_string(id) + " is defined twice");
    }
    for (const char* axis : {"x", "y", "z"}) xyz.push_back(nodes.real(std::string("node ") + axis));
    nodes.rest_of_line();  // attributes and boundary marker
  }
  return TetgenNodes{std::move(xyz), std::move(node_of_id), node_source};
}

TetMeshData read_tetgen_elements(TetgenNodes nodes, std::string_view ele_text, const std::string& ele_source) {
  const auto& node_of_id = nodes.node_of_id;
  const std::string& node_source = nodes.source;
  TextScanner eles(ele_text, ele_source);
  const std::int64_t num_tets = eles.integer("tetrahedron count");
  check_count(num_tets, ele_text.size(), 10, "tetrahedra", ele_source, eles.line());
  const std::int64_t nodes_per_tet = eles.integer("nodes per tetrahedron");
  if (nodes_per_tet != 4 && nodes_per_tet != 10) {
    eles.fail("nodes per tetrahedron must be 4 or 10, not " + std::to_string(nodes_per_tet));
  }
  eles.integer_in("attribute count", 0, 1000);
  eles.rest_of_line();
  TetMeshData data;
  std::vector<Index> ids;
  ids.reserve(static_cast<std::size_t>(num_tets) * 4);
  data.tet_lines.reserve(static_cast<std::size_t>(num_tets));
  for (std::int64_t t = 0; t < num_tets; ++t) {
    const std::int64_t element = eles.integer("tetrahedron number");
    data.tet_lines.push_back(eles.line());
    for (int k = 0; k < 4; ++k) {
      const std::int64_t id = eles.integer("tetrahedron node");
      const auto it = node_of_id.find(id);
      if (it == node_of_id.end()) {
        eles.fail("tetrahedron " + std::to_string(element) + " refers to node " + std::to_string(id) +
                  ", which " + node_source + " does not define");
      }
      ids.push_back(it->second);
    }
    eles.rest_of_line();  // second-order nodes and attributes
  }
  data.points = to_points(nodes.xyz);
  data.tets = to_tets(ids);
  return data;
}

void write_tetgen_node(std::ostream& out, const Points& points) {
  out << points.rows() << " 3 0 0\n";
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    out << i;
    for (int k = 0; k < 3; ++k) {
      out << ' ';
      write_real(out, points(i, k));
    }
    out << '\n';
  }
}

void write_tetgen_ele(std::ostream& out, const Tets& tets) {
  out << tets.rows() << " 4 0\n";
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    out << t << ' ' << tets(t, 0) << ' ' << tets(t, 1) << ' ' << tets(t, 2) << ' ' << tets(t, 3) << '\n';
  }
}

}  // namespace tetcut::io
