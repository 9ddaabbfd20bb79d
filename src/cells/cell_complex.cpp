#include "cells/cell_complex.hpp"

#include <tetcut/tet_mesh.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace tetcut::cells {

using geometry::Plane;

CellComplex::CellComplex(const std::array<Vec3, 4>& corners) {
  PlaneId face_plane[4];
  for (int f = 0; f < 4; ++f) {
    const auto& local = kTetFaces[f];
    // Outward normals; distinct planes for a tet with volume, so no two merge.
    face_plane[f] = add_plane(Plane::through(corners[local[0]], corners[local[1]], corners[local[2]])).id;
  }
  // Corner i is on every face but face i.
  for (int i = 0; i < 4; ++i) {
    PlaneId on[3];
    for (int f = 0, m = 0; f < 4; ++f) {
      if (f != i) on[m++] = face_plane[f];
    }
    add_vertex(on[0], on[1], on[2]);
  }
  cells_.push_back(Cell{});
  for (int f = 0; f < 4; ++f) {
    Facet facet;
    facet.plane = face_plane[f];
    facet.back = 0;  // outward normal: the tet is behind its faces
    facet.tet_face = static_cast<std::int8_t>(f);
    for (int k = 0; k < 3; ++k) {
      const int a = kTetFaces[f][k], b = kTetFaces[f][(k + 1) % 3];
      facet.vertices.push_back(a);
      // The other face through corners a and b is the one opposite the fourth corner.
      facet.edge_planes.push_back(face_plane[6 - f - a - b]);
    }
    facets_.push_back(facet);
    cells_[0].facets.push_back(f);
    index_edges(f);
  }
}

CellComplex::OrientedPlane CellComplex::add_plane(const Plane& plane) {
  for (PlaneId id = 0; id < static_cast<PlaneId>(planes_.size()); ++id) {
    const int alignment = geometry::plane_alignment(planes_[id], plane);
    if (alignment != 0) return {id, alignment};
  }
  planes_.push_back(plane);
  return {static_cast<PlaneId>(planes_.size() - 1), 1};
}

VertexId CellComplex::add_vertex(PlaneId a, PlaneId b, PlaneId c) {
  const int orientation = geometry::normal_determinant_sign(planes_[a], planes_[b], planes_[c]);
  if (orientation == 0) throw std::logic_error("cell complex: a vertex's three planes do not meet in one point");
  vertices_.push_back(Vertex{{a, b, c}, static_cast<std::int8_t>(orientation)});
  return static_cast<VertexId>(vertices_.size() - 1);
}

int CellComplex::side(VertexId v, PlaneId plane) const {
  std::vector<std::int8_t>* memo = nullptr;
  for (auto& [id, values] : side_memo_) {
    if (id == plane) memo = &values;
  }
  if (memo != nullptr) {
    if (memo->size() <= static_cast<std::size_t>(v)) memo->resize(vertices_.size(), 2);
    if ((*memo)[v] != 2) return (*memo)[v];
  }
  const Vertex& vertex = vertices_[v];
  int s = 0;
  if (vertex.planes[0] != plane && vertex.planes[1] != plane && vertex.planes[2] != plane) {
    s = geometry::side_of_tpi(planes_[vertex.planes[0]], planes_[vertex.planes[1]], planes_[vertex.planes[2]],
                              vertex.orientation, planes_[plane]);
  }
  if (memo != nullptr) (*memo)[v] = static_cast<std::int8_t>(s);
  return s;
}

int CellComplex::classify(CellId cell, PlaneId plane) const {
  bool positive = false, negative = false;
  for (const FacetId f : cells_[cell].facets) {
    for (const VertexId v : facets_[f].vertices) {
      const int s = side(v, plane);
      positive = positive || s > 0;
      negative = negative || s < 0;
      if (positive && negative) return 0;
    }
  }
  if (positive) return 1;
  if (negative) return -1;
  return 2;
}

void CellComplex::index_edges(FacetId f) {
  const auto& vs = facets_[f].vertices;
  for (std::size_t i = 0; i < vs.size(); ++i) facets_of_edge_[edge_key(vs[i], vs[(i + 1) % vs.size()])].push_back(f);
}

void CellComplex::unindex_edges(FacetId f) {
  const auto& vs = facets_[f].vertices;
  for (std::size_t i = 0; i < vs.size(); ++i) {
    auto it = facets_of_edge_.find(edge_key(vs[i], vs[(i + 1) % vs.size()]));
    if (it == facets_of_edge_.end()) continue;
    auto& list = it->second;
    list.erase(std::remove(list.begin(), list.end(), f), list.end());
    if (list.empty()) facets_of_edge_.erase(it);
  }
}

void CellComplex::insert_on_edge(VertexId u, VertexId v, VertexId w) {
  const auto it = facets_of_edge_.find(edge_key(u, v));
  if (it == facets_of_edge_.end()) return;
  const std::vector<FacetId> owners = it->second;
  facets_of_edge_.erase(it);
  for (const FacetId f : owners) {
    Facet& facet = facets_[f];
    const std::size_t n = facet.vertices.size();
    for (std::size_t i = 0; i < n; ++i) {
      const VertexId a = facet.vertices[i], b = facet.vertices[(i + 1) % n];
      if ((a == u && b == v) || (a == v && b == u)) {
        facet.vertices.insert(facet.vertices.begin() + static_cast<std::ptrdiff_t>(i + 1), w);
        facet.edge_planes.insert(facet.edge_planes.begin() + static_cast<std::ptrdiff_t>(i + 1), facet.edge_planes[i]);
        break;
      }
    }
    facets_of_edge_[edge_key(u, w)].push_back(f);
    facets_of_edge_[edge_key(w, v)].push_back(f);
  }
}

CellId CellComplex::split(CellId cell, PlaneId plane, FacetId* section) {
  if (classify(cell, plane) != 0) return -1;
  const CellId negative_cell = static_cast<CellId>(cells_.size());
  cells_.push_back(Cell{});

  // 1. Put a vertex on every edge of the cell that crosses the plane, in every facet sharing it.
  const std::vector<FacetId> old_facets = cells_[cell].facets;
  for (const FacetId f : old_facets) {
    for (std::size_t i = 0; i < facets_[f].vertices.size(); ++i) {
      const std::size_t n = facets_[f].vertices.size();
      const VertexId u = facets_[f].vertices[i], v = facets_[f].vertices[(i + 1) % n];
      if (side(u, plane) * side(v, plane) < 0) {
        const VertexId w = add_vertex(facets_[f].plane, facets_[f].edge_planes[i], plane);
        insert_on_edge(u, v, w);
      }
    }
  }

  // 2. Distribute the facets, splitting those that cross. Collect the section's edges, directed as
  //    the section's counter-clockwise cycle (seen from the positive side) runs.
  struct SectionEdge {
    VertexId from, to;
    PlaneId plane;
  };
  std::vector<SectionEdge> section_edges;
  std::vector<FacetId> positive_facets, negative_facets;
  for (const FacetId f : old_facets) {
    const bool cell_is_back = facets_[f].back == cell;
    const std::vector<VertexId> vs = facets_[f].vertices;
    const std::vector<PlaneId> es = facets_[f].edge_planes;
    const std::size_t n = vs.size();
    bool positive = false, negative = false;
    for (const VertexId v : vs) {
      positive = positive || side(v, plane) > 0;
      negative = negative || side(v, plane) < 0;
    }
    // Outward direction of edge i for the cell: the stored direction when the cell is behind.
    auto add_on_plane_edges = [&](bool reverse) {
      for (std::size_t i = 0; i < n; ++i) {
        const VertexId a = vs[i], b = vs[(i + 1) % n];
        if (side(a, plane) != 0 || side(b, plane) != 0) continue;
        const bool outward_is_stored = cell_is_back;
        VertexId from = outward_is_stored ? a : b, to = outward_is_stored ? b : a;
        if (reverse) std::swap(from, to);
        section_edges.push_back({from, to, facets_[f].plane});
      }
    };
    if (!negative) {
      positive_facets.push_back(f);
      add_on_plane_edges(false);
      continue;
    }
    if (!positive) {
      (cell_is_back ? facets_[f].back : facets_[f].front) = negative_cell;
      negative_facets.push_back(f);
      add_on_plane_edges(true);
      continue;
    }
    // Crossing facet: keep the >= 0 arc in f, move the <= 0 arc to a new facet; each arc is closed
    // by a chord on the plane.
    auto arc = [&](int sign, std::vector<VertexId>& out_vs, std::vector<PlaneId>& out_es, VertexId* chord_from,
                   VertexId* chord_to) {
      for (std::size_t i = 0; i < n; ++i) {
        if (side(vs[i], plane) * sign < 0) continue;
        out_vs.push_back(vs[i]);
        const VertexId next = vs[(i + 1) % n];
        if (side(next, plane) * sign >= 0) {
          out_es.push_back(es[i]);
        } else {
          out_es.push_back(plane);
          *chord_from = vs[i];
        }
      }
      // The chord ends at the first kept vertex after the skipped run.
      for (std::size_t i = 0; i < out_vs.size(); ++i) {
        if (out_es[i] == plane && side(out_vs[i], plane) == 0 && out_vs[i] == *chord_from) {
          *chord_to = out_vs[(i + 1) % out_vs.size()];
        }
      }
    };
    std::vector<VertexId> pos_vs, neg_vs;
    std::vector<PlaneId> pos_es, neg_es;
    VertexId pos_from = -1, pos_to = -1, neg_from = -1, neg_to = -1;
    arc(+1, pos_vs, pos_es, &pos_from, &pos_to);
    arc(-1, neg_vs, neg_es, &neg_from, &neg_to);
    unindex_edges(f);
    Facet negative_part = facets_[f];
    negative_part.vertices = std::move(neg_vs);
    negative_part.edge_planes = std::move(neg_es);
    (cell_is_back ? negative_part.back : negative_part.front) = negative_cell;
    facets_[f].vertices = std::move(pos_vs);
    facets_[f].edge_planes = std::move(pos_es);
    const FacetId g = static_cast<FacetId>(facets_.size());
    const CellId other = cell_is_back ? negative_part.front : negative_part.back;
    facets_.push_back(std::move(negative_part));
    index_edges(f);
    index_edges(g);
    if (other != kOutside) cells_[other].facets.push_back(g);
    positive_facets.push_back(f);
    negative_facets.push_back(g);
    // The chord in the positive part, in the cell's outward direction.
    section_edges.push_back(cell_is_back ? SectionEdge{pos_from, pos_to, facets_[f].plane}
                                         : SectionEdge{pos_to, pos_from, facets_[f].plane});
  }

  // 3. Chain the section's edges into its cycle. Each edge was seen from both sides; keep one copy.
  std::unordered_map<VertexId, std::pair<VertexId, PlaneId>> next;
  for (const SectionEdge& e : section_edges) next[e.from] = {e.to, e.plane};
  Facet cap;
  cap.plane = plane;
  cap.front = cell;
  cap.back = negative_cell;
  const VertexId start = section_edges.front().from;
  VertexId v = start;
  do {
    const auto it = next.find(v);
    if (it == next.end() || cap.vertices.size() > next.size()) {
      throw std::logic_error("cell complex: the section of a split cell is not one closed polygon");
    }
    cap.vertices.push_back(v);
    cap.edge_planes.push_back(it->second.second);
    v = it->second.first;
  } while (v != start);
  if (cap.vertices.size() != next.size()) {
    throw std::logic_error("cell complex: the section of a split cell is not one closed polygon");
  }
  const FacetId cap_id = static_cast<FacetId>(facets_.size());
  facets_.push_back(std::move(cap));
  index_edges(cap_id);
  positive_facets.push_back(cap_id);
  negative_facets.push_back(cap_id);
  cells_[cell].facets = std::move(positive_facets);
  cells_[negative_cell].facets = std::move(negative_facets);
  if (section != nullptr) *section = cap_id;
  return negative_cell;
}

void CellComplex::insert_triangle(const Vec3& a, const Vec3& b, const Vec3& c, std::int32_t cut_id) {
  const Plane triangle_plane = Plane::through(a, b, c);
  // Walls along the axis the normal is largest on (decided on the rounded normal; any axis with a
  // non-zero normal component works, and that one is checked exactly).
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(triangle_plane.approx()[k].value) > std::abs(triangle_plane.approx()[axis].value)) axis = k;
  }
  if (geometry::normal_component_sign(triangle_plane, axis) == 0) {
    for (int k = 0; k < 3; ++k) {
      if (geometry::normal_component_sign(triangle_plane, k) != 0) axis = k;
    }
  }
  const PlaneId cut_plane = add_plane(triangle_plane).id;
  const Vec3* corners[3] = {&a, &b, &c};
  OrientedPlane walls[3];
  for (int e = 0; e < 3; ++e) {
    const Vec3& from = *corners[e];
    const Vec3& to = *corners[(e + 1) % 3];
    const Vec3& opposite = *corners[(e + 2) % 3];
    Plane wall = Plane::wall(from, to, axis);
    if (geometry::side_of_point(wall, opposite) < 0) wall = wall.flipped();
    walls[e] = add_plane(wall);  // sign: +1 when the stored plane's positive side is inward
  }
  side_memo_.clear();
  side_memo_.push_back({cut_plane, {}});
  for (const OrientedPlane& w : walls) side_memo_.push_back({w.id, {}});

  const CellId existing = static_cast<CellId>(cells_.size());
  for (CellId cell = 0; cell < existing; ++cell) {
    const int on_plane = classify(cell, cut_plane);
    bool has_facet_on_plane = false;
    for (const FacetId f : cells_[cell].facets) has_facet_on_plane = has_facet_on_plane || facets_[f].plane == cut_plane;
    if (on_plane != 0 && !has_facet_on_plane) continue;
    bool outside = false;
    for (const OrientedPlane& w : walls) outside = outside || classify(cell, w.id) * w.sign == -1;
    if (outside) continue;
    CellId inside = cell;
    for (const OrientedPlane& w : walls) {
      const CellId negative = split(inside, w.id, nullptr);
      if (negative >= 0 && w.sign < 0) inside = negative;
    }
    FacetId section = -1;
    if (split(inside, cut_plane, &section) >= 0) {
      facets_[section].covered = true;
      facets_[section].cut = cut_id;
    } else {
      for (const FacetId f : cells_[inside].facets) {
        if (facets_[f].plane != cut_plane) continue;
        if (!facets_[f].covered) facets_[f].cut = cut_id;
        facets_[f].covered = true;
      }
    }
  }
  side_memo_.clear();
}

std::vector<std::int32_t> CellComplex::components(std::int32_t* num_components) const {
  std::vector<CellId> parent(cells_.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](CellId x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const Facet& f : facets_) {
    if (f.covered || f.front == kOutside || f.back == kOutside) continue;
    const CellId a = find(f.front), b = find(f.back);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  std::vector<std::int32_t> component(cells_.size(), -1);
  std::int32_t count = 0;
  for (CellId c = 0; c < static_cast<CellId>(cells_.size()); ++c) {
    const CellId root = find(c);
    if (component[root] < 0) component[root] = count++;
    component[c] = component[root];
  }
  if (num_components != nullptr) *num_components = count;
  return component;
}

Vec3 CellComplex::position(VertexId v) const {
  const Vertex& vertex = vertices_[v];
  return geometry::tpi_coordinates(planes_[vertex.planes[0]], planes_[vertex.planes[1]], planes_[vertex.planes[2]]);
}

double CellComplex::cell_volume(CellId cell) const {
  // Divergence theorem over fans of the outward-oriented facets, relative to one vertex of the cell.
  const Vec3 origin = position(facets_[cells_[cell].facets.front()].vertices.front());
  double six_volume = 0;
  for (const FacetId f : cells_[cell].facets) {
    const Facet& facet = facets_[f];
    const bool outward_is_stored = facet.back == cell;
    const std::size_t n = facet.vertices.size();
    const Vec3 first = position(facet.vertices[0]) - origin;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      Vec3 p = position(facet.vertices[i]) - origin, q = position(facet.vertices[i + 1]) - origin;
      if (!outward_is_stored) std::swap(p, q);
      six_volume += first.dot(p.cross(q));
    }
  }
  return six_volume / 6.0;
}

std::string CellComplex::validate() const {
  for (FacetId f = 0; f < static_cast<FacetId>(facets_.size()); ++f) {
    const Facet& facet = facets_[f];
    const std::size_t n = facet.vertices.size();
    if (n < 3 || facet.edge_planes.size() != n) return "facet " + std::to_string(f) + " has fewer than 3 vertices";
    for (std::size_t i = 0; i < n; ++i) {
      const VertexId a = facet.vertices[i], b = facet.vertices[(i + 1) % n];
      if (side(a, facet.plane) != 0) return "facet " + std::to_string(f) + ": a vertex is off its plane";
      if (side(a, facet.edge_planes[i]) != 0 || side(b, facet.edge_planes[i]) != 0) {
        return "facet " + std::to_string(f) + ": an edge is off its edge plane";
      }
    }
    for (const CellId c : {facet.front, facet.back}) {
      if (c == kOutside) continue;
      const auto& list = cells_[c].facets;
      if (std::find(list.begin(), list.end(), f) == list.end()) {
        return "facet " + std::to_string(f) + " is missing from its cell's list";
      }
    }
  }
  for (CellId c = 0; c < static_cast<CellId>(cells_.size()); ++c) {
    std::vector<std::pair<VertexId, VertexId>> edges;
    for (const FacetId f : cells_[c].facets) {
      const Facet& facet = facets_[f];
      if (facet.front != c && facet.back != c) return "cell " + std::to_string(c) + " lists a facet not bounding it";
      const bool outward_is_stored = facet.back == c;
      const std::size_t n = facet.vertices.size();
      for (std::size_t i = 0; i < n; ++i) {
        VertexId a = facet.vertices[i], b = facet.vertices[(i + 1) % n];
        if (!outward_is_stored) std::swap(a, b);
        edges.emplace_back(a, b);
      }
    }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i < edges.size(); ++i) {
      if (i > 0 && edges[i] == edges[i - 1]) return "cell " + std::to_string(c) + " uses an edge twice in one direction";
      const std::pair<VertexId, VertexId> reverse(edges[i].second, edges[i].first);
      if (!std::binary_search(edges.begin(), edges.end(), reverse)) {
        return "cell " + std::to_string(c) + " is not closed";
      }
    }
    if (!(cell_volume(c) > 0)) return "cell " + std::to_string(c) + " has no volume";
  }
  return {};
}

}  // namespace tetcut::cells
