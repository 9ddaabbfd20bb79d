// Lazy refinement (paper 3.1): a tet becomes cells only when a triangle may cut it. Its first
// cell is the tet itself, its facets the polygons of its faces as the refined neighbours left them
// (with the points they put on shared edges), so that neighbours agree on every shared face.

#include "cells/cell_complex.hpp"

#include "mesh/local_index.hpp"
#include "util/broken.hpp"

#include <tetcut/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tetcut::cells {

using geometry::Plane;
using registry::OrientedPlane;

PlaneId CellComplex::face_plane(Index face) {
  if (face_plane_[face] < 0) {
    // Faces are stored with ascending node ids; the plane through them in that order fixes the
    // orientation of every facet on the face.
    const auto& faces = mesh_->adjacency().faces;
    const Points& p = mesh_->rest();
    face_plane_[face] = registry_->add_plane(Plane::through(p.row(faces(face, 0)).transpose(),
                                                            p.row(faces(face, 1)).transpose(),
                                                            p.row(faces(face, 2)).transpose()));
  }
  return face_plane_[face];
}

VertexId CellComplex::node_vertex(Index node, Index tet) {
  if (node_vertex_[node] < 0) {
    // A mesh node is the meeting of the three faces of `tet` through it.
    const int i = local_index(mesh_->tets(), tet, node);
    PlaneId planes[3];
    for (int k = 0, m = 0; k < 4; ++k) {
      if (k != i) planes[m++] = face_plane(mesh_->adjacency().tet_faces(tet, k));
    }
    node_vertex_[node] = registry_->add_node(node, planes[0], planes[1], planes[2]);
  }
  return node_vertex_[node];
}

EdgeId CellComplex::add_edge(VertexId a, VertexId b, std::array<PlaneId, 2> line, Index mesh_edge) {
  Edge edge;
  edge.a = a;
  edge.b = b;
  edge.line = line;
  edge.mesh_edge = mesh_edge;
  if (mesh_edge >= 0) edge.next_on_mesh_edge = mesh_edge_first_[mesh_edge];
  const EdgeId id = static_cast<EdgeId>(edges_.push_back(std::move(edge)) - edges_.begin());
  if (mesh_edge >= 0) mesh_edge_first_[mesh_edge] = id;
  return id;
}

template <typename Visit>
void CellComplex::walk_mesh_edge(Index mesh_edge, VertexId start, VertexId target, Visit&& visit) const {
  // The edge records on a mesh edge form a path between its nodes: at each vertex, take the record
  // that does not lead back. O(records on the edge) per step.
  VertexId previous = -1, current = start;
  while (current != target) {
    EdgeId next = -1;
    for (EdgeId e = mesh_edge_first_[mesh_edge]; e >= 0; e = edges_[e].next_on_mesh_edge) {
      const Edge& edge = edges_[e];
      const VertexId other = edge.a == current ? edge.b : (edge.b == current ? edge.a : -1);
      if (other >= 0 && other != previous) {
        next = e;
        break;
      }
    }
    if (next < 0) broken("cell complex", "the edge records on a mesh edge do not form a path");
    visit(current, next);
    previous = current;
    current = edges_[next].a == current ? edges_[next].b : edges_[next].a;
  }
}

void CellComplex::append_mesh_edge_chain(Index mesh_edge, Index from, Index to, Index tet, FacetId facet,
                                         std::vector<Corner>* corners) {
  const VertexId start = node_vertex(from, tet);
  const VertexId target = node_vertex(to, tet);
  if (mesh_edge_first_[mesh_edge] < 0) {
    // The two faces of `tet` through the edge are those opposite its two other nodes.
    PlaneId line[2];
    for (int k = 0, m = 0; k < 4; ++k) {
      const Index node = mesh_->tets()(tet, k);
      if (node != from && node != to) line[m++] = face_plane(mesh_->adjacency().tet_faces(tet, k));
    }
    add_edge(start, target, {line[0], line[1]}, mesh_edge);
  }
  walk_mesh_edge(mesh_edge, start, target, [&](VertexId from_vertex, EdgeId edge) {
    corners->push_back({from_vertex, edge});
    edges_[edge].facets.push_back(facet);
  });
}

void CellComplex::mesh_edge_points(Index mesh_edge, Index from, Index to, std::vector<VertexId>* out) const {
  if (mesh_edge_first_[mesh_edge] < 0) return;
  const VertexId start = node_vertex_[from];
  walk_mesh_edge(mesh_edge, start, node_vertex_[to], [&](VertexId vertex, EdgeId) {
    if (vertex != start) out->push_back(vertex);
  });
}

void CellComplex::add_face_facet(Index face, Index tet, CellId cell) {
  const TetAdjacency& adj = mesh_->adjacency();
  const Tets& tets = mesh_->tets();
  const PlaneId plane = face_plane(face);
  int local_face = 0;
  while (adj.tet_faces(tet, local_face) != face) ++local_face;
  // Face k of a tet is opposite its local node k: that node tells which side the tet is on.
  const int tet_side = geometry::side_of_point(registry_->plane(plane), mesh_->rest().row(tets(tet, local_face)).transpose());
  Side other = kOutside;
  for (const Index t : adj.tets_of_face(face)) {
    if (t != tet) other = unrefined_side(t);
  }
  Facet facet;
  facet.plane = plane;
  facet.mesh_face = face;
  facet.front = tet_side > 0 ? cell : other;
  facet.back = tet_side > 0 ? other : cell;
  const FacetId id = static_cast<FacetId>(facets_.push_back(std::move(facet)) - facets_.begin());

  // The cycle n0 -> n1 -> n2 (ascending ids) is counter-clockwise seen from the plane's front.
  const Index n[3] = {adj.faces(face, 0), adj.faces(face, 1), adj.faces(face, 2)};
  std::vector<Corner> corners;
  for (int k = 0; k < 3; ++k) {
    const Index from = n[k], to = n[(k + 1) % 3];
    Index mesh_edge = -1;
    for (int e = 0; e < 6; ++e) {
      const Index a = tets(tet, kTetEdges[e][0]), b = tets(tet, kTetEdges[e][1]);
      if ((a == from && b == to) || (a == to && b == from)) mesh_edge = adj.tet_edges(tet, e);
    }
    append_mesh_edge_chain(mesh_edge, from, to, tet, id, &corners);
  }
  facets_[id].corners = std::move(corners);
  facets_[id].next_on_mesh_face = face_first_facet_[face];
  face_first_facet_[face] = id;
  cells_[cell].facets.push_back(id);
}

CellId CellComplex::refine(Index tet) {
  if (first_cell_[tet] >= 0) return first_cell_[tet];
  Cell c;
  c.tet = tet;
  c.material = tet_material_[tet] != 0;
  c.label = tet_label_[tet];
  const CellId cell = static_cast<CellId>(cells_.push_back(std::move(c)) - cells_.begin());
  first_cell_[tet] = cell;
  const Side marker = unrefined_side(tet);
  for (int k = 0; k < 4; ++k) {
    const Index face = mesh_->adjacency().tet_faces(tet, k);
    if (face_first_facet_[face] < 0) {
      add_face_facet(face, tet, cell);
      continue;
    }
    // A refined neighbour already made this face's facets; they refer to this tet by its marker.
    for (FacetId f = face_first_facet_[face]; f >= 0; f = facets_[f].next_on_mesh_face) {
      Facet& facet = facets_[f];
      if (facet.front == marker) {
        facet.front = cell;
      } else if (facet.back == marker) {
        facet.back = cell;
      } else {
        broken("cell complex", "a facet on a face of an unrefined tet does not refer to it");
      }
      cells_[cell].facets.push_back(f);
    }
  }
  return cell;
}

}  // namespace tetcut::cells
