#include "cells/cell_complex.hpp"

#include "mesh/local_index.hpp"
#include "util/broken.hpp"

#include <tetcut/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace tetcut::cells {

using geometry::Plane;
using registry::OrientedPlane;

CellComplex::CellComplex(const TetMesh& mesh, registry::IntersectionRegistry& registry)
    : mesh_(&mesh),
      registry_(&registry),
      first_cell_(static_cast<std::size_t>(mesh.num_tets()), -1),
      tet_material_(static_cast<std::size_t>(mesh.num_tets()), 1),
      face_first_facet_(static_cast<std::size_t>(mesh.adjacency().num_faces()), -1),
      face_plane_(static_cast<std::size_t>(mesh.adjacency().num_faces()), -1),
      mesh_edge_first_(static_cast<std::size_t>(mesh.adjacency().num_edges()), -1),
      node_vertex_(static_cast<std::size_t>(mesh.num_nodes()), -1),
      tet_label_(static_cast<std::size_t>(mesh.num_tets()), -1),
      tet_touch_stamp_(static_cast<std::size_t>(mesh.num_tets()), -1) {}

Index CellComplex::tet_of(Side s) const {
  if (is_cell(s)) return cells_[s].tet;
  if (is_unrefined(s)) return unrefined_tet(s);
  return -1;
}

bool CellComplex::side_is_material(Side s) const {
  if (is_cell(s)) return cells_[s].material;
  if (is_unrefined(s)) return tet_material(unrefined_tet(s));
  return false;
}

void CellComplex::set_tet_material(Index tet, bool material) {
  tet_material_[tet] = material ? 1 : 0;
  for (CellId c = first_cell_[tet]; c >= 0; c = cells_[c].next_in_tet) cells_[c].material = material;
}

}  // namespace tetcut::cells
