#include <tetcut/error.hpp>
#include <tetcut/surface.hpp>
#include <tetcut/tet_mesh.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "geometry/predicates.hpp"

namespace tetcut {
namespace {

// Elements are named 1-based, as every text format in the field numbers them.
std::string tet_label(Index t) { return "tetrahedron " + std::to_string(t + 1); }

std::int64_t tet_line(Index t, std::span<const std::int64_t> lines) {
  return lines.empty() ? 0 : lines[t];
}

void check_finite(const Points& points, const std::string& source, const char* what) {
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(points(i, k))) {
        throw Error(ErrorKind::kInvalidInput,
                    std::string(what) + " " + std::to_string(i + 1) + " has a coordinate that is not a finite number",
                    source);
      }
    }
  }
}

// Sorts each key's entries and assigns ids to unique keys. `keys` holds (key, owner slot) pairs
// whose keys are ascending node ids; returns, for each owner slot, the id of its key, and fills
// `unique` with the distinct keys in ascending order. A counting sort by the first node, then a
// sort of each node's few entries (in parallel): O(n) for meshes whose nodes have bounded degree,
// where one comparison sort of all entries was the largest cost of building a big mesh.
template <typename Key>
std::vector<Index> number_keys(std::vector<std::pair<Key, Index>>& keys, std::vector<Key>& unique, Index num_nodes) {
  std::vector<std::size_t> begin(static_cast<std::size_t>(num_nodes) + 1, 0);
  for (const auto& entry : keys) ++begin[static_cast<std::size_t>(entry.first[0]) + 1];
  for (std::size_t n = 1; n < begin.size(); ++n) begin[n] += begin[n - 1];
  std::vector<std::pair<Key, Index>> sorted(keys.size());
  {
    std::vector<std::size_t> fill(begin.begin(), begin.end() - 1);
    for (const auto& entry : keys) sorted[fill[static_cast<std::size_t>(entry.first[0])]++] = entry;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, static_cast<std::size_t>(num_nodes), 4096), [&](const auto& range) {
    for (std::size_t n = range.begin(); n != range.end(); ++n) {
      std::sort(sorted.begin() + static_cast<std::ptrdiff_t>(begin[n]), sorted.begin() + static_cast<std::ptrdiff_t>(begin[n + 1]));
    }
  });
  keys = std::move(sorted);
  std::vector<Index> id_of_slot(keys.size());
  unique.clear();
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (i == 0 || keys[i].first != keys[i - 1].first) unique.push_back(keys[i].first);
    id_of_slot[keys[i].second] = static_cast<Index>(unique.size() - 1);
  }
  return id_of_slot;
}

}  // namespace

double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

TetAdjacency build_adjacency(const Tets& tets, Index num_nodes) {
  if (tets.size() > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= num_nodes)) {
    throw Error(ErrorKind::kInvalidArgument, "build_adjacency: a node id outside [0, num_nodes)");
  }
  const Index num_tets = static_cast<Index>(tets.rows());
  TetAdjacency adj;

  // Faces: O(T log T) by sorting the 4T sorted node triples.
  using FaceKey = std::array<Index, 3>;
  std::vector<std::pair<FaceKey, Index>> face_keys;
  face_keys.reserve(static_cast<std::size_t>(num_tets) * 4);
  for (Index t = 0; t < num_tets; ++t) {
    for (int f = 0; f < 4; ++f) {
      FaceKey key{tets(t, kTetFaces[f][0]), tets(t, kTetFaces[f][1]), tets(t, kTetFaces[f][2])};
      std::sort(key.begin(), key.end());
      face_keys.emplace_back(key, t * 4 + f);
    }
  }
  std::vector<FaceKey> unique_faces;
  const std::vector<Index> face_of_slot = number_keys(face_keys, unique_faces, num_nodes);
  adj.faces.resize(static_cast<Eigen::Index>(unique_faces.size()), 3);
  for (std::size_t i = 0; i < unique_faces.size(); ++i) {
    for (int k = 0; k < 3; ++k) adj.faces(static_cast<Eigen::Index>(i), k) = unique_faces[i][k];
  }
  adj.tet_faces.resize(num_tets, 4);
  adj.face_tets_begin.assign(unique_faces.size() + 1, 0);
  for (Index t = 0; t < num_tets; ++t) {
    for (int f = 0; f < 4; ++f) {
      const Index face = face_of_slot[t * 4 + f];
      adj.tet_faces(t, f) = face;
      ++adj.face_tets_begin[face + 1];
    }
  }
  for (std::size_t i = 1; i < adj.face_tets_begin.size(); ++i) adj.face_tets_begin[i] += adj.face_tets_begin[i - 1];
  adj.face_tets.resize(static_cast<std::size_t>(num_tets) * 4);
  std::vector<Index> fill(adj.face_tets_begin.begin(), adj.face_tets_begin.end() - 1);
  for (Index t = 0; t < num_tets; ++t) {
    for (int f = 0; f < 4; ++f) adj.face_tets[fill[adj.tet_faces(t, f)]++] = t;
  }

  // Edges, the same way.
  using EdgeKey = std::array<Index, 2>;
  std::vector<std::pair<EdgeKey, Index>> edge_keys;
  edge_keys.reserve(static_cast<std::size_t>(num_tets) * 6);
  for (Index t = 0; t < num_tets; ++t) {
    for (int e = 0; e < 6; ++e) {
      EdgeKey key{tets(t, kTetEdges[e][0]), tets(t, kTetEdges[e][1])};
      if (key[0] > key[1]) std::swap(key[0], key[1]);
      edge_keys.emplace_back(key, t * 6 + e);
    }
  }
  std::vector<EdgeKey> unique_edges;
  const std::vector<Index> edge_of_slot = number_keys(edge_keys, unique_edges, num_nodes);
  adj.edges.resize(static_cast<Eigen::Index>(unique_edges.size()), 2);
  for (std::size_t i = 0; i < unique_edges.size(); ++i) {
    adj.edges(static_cast<Eigen::Index>(i), 0) = unique_edges[i][0];
    adj.edges(static_cast<Eigen::Index>(i), 1) = unique_edges[i][1];
  }
  adj.tet_edges.resize(num_tets, 6);
  for (Index t = 0; t < num_tets; ++t) {
    for (int e = 0; e < 6; ++e) adj.tet_edges(t, e) = edge_of_slot[t * 6 + e];
  }
  return adj;
}

Index TetAdjacency::neighbor(Index t, int f) const {
  const auto tets_here = tets_of_face(tet_faces(t, f));
  if (tets_here.size() != 2) return -1;
  return tets_here[0] == t ? tets_here[1] : tets_here[0];
}

Index TetAdjacency::num_boundary_faces() const {
  Index n = 0;
  for (Index f = 0; f < num_faces(); ++f) n += (face_tets_begin[f + 1] - face_tets_begin[f]) == 1;
  return n;
}

Index TetAdjacency::num_overshared_faces() const {
  Index n = 0;
  for (Index f = 0; f < num_faces(); ++f) n += (face_tets_begin[f + 1] - face_tets_begin[f]) > 2;
  return n;
}

TetMesh::TetMesh(Points rest, Tets tets, const std::string& source, std::span<const std::int64_t> tet_lines)
    : rest_(std::move(rest)), tets_(std::move(tets)) {
  check_finite(rest_, source, "node");
  const Index num_nodes = static_cast<Index>(rest_.rows());
  for (Index t = 0; t < num_tets(); ++t) {
    for (int k = 0; k < 4; ++k) {
      const Index node = tets_(t, k);
      if (node < 0 || node >= num_nodes) {
        throw Error(ErrorKind::kInvalidInput,
                    tet_label(t) + " refers to node " + std::to_string(node + 1) + ", but there are only " +
                        std::to_string(num_nodes) + " nodes",
                    source, tet_line(t, tet_lines));
      }
    }
    for (int j = 0; j < 4; ++j) {
      for (int k = j + 1; k < 4; ++k) {
        if (tets_(t, j) == tets_(t, k)) {
          throw Error(ErrorKind::kInvalidInput,
                      tet_label(t) + " uses node " + std::to_string(tets_(t, j) + 1) + " twice",
                      source, tet_line(t, tet_lines));
        }
      }
    }
    const int orientation = geometry::orient3d(rest_.row(tets_(t, 0)).data(), rest_.row(tets_(t, 1)).data(),
                                               rest_.row(tets_(t, 2)).data(), rest_.row(tets_(t, 3)).data());
    if (orientation <= 0) {
      throw Error(ErrorKind::kInvalidInput,
                  tet_label(t) + (orientation == 0 ? " has zero volume (its four nodes are coplanar)"
                                                              : " is inverted (negative volume)"),
                  source, tet_line(t, tet_lines));
    }
  }
  current_ = rest_;
  adjacency_ = build_adjacency(tets_, num_nodes);
}

TriangleSurface boundary_surface(const TetMesh& mesh, std::vector<BoundaryFace>* faces) {
  const TetAdjacency& adj = mesh.adjacency();
  if (faces != nullptr) faces->clear();
  std::vector<Index> new_id(static_cast<std::size_t>(mesh.num_nodes()), -1);
  std::vector<Index> corners;
  Index num_vertices = 0;
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    for (int f = 0; f < 4; ++f) {
      if (adj.tets_of_face(adj.tet_faces(t, f)).size() != 1) continue;
      if (faces != nullptr) faces->push_back({t, f});
      for (const int local : kTetFaces[f]) {
        Index& id = new_id[mesh.tets()(t, local)];
        if (id < 0) id = num_vertices++;
        corners.push_back(id);
      }
    }
  }
  TriangleSurface surface;
  surface.vertices.resize(num_vertices, 3);
  for (Index v = 0; v < mesh.num_nodes(); ++v) {
    if (new_id[v] >= 0) surface.vertices.row(new_id[v]) = mesh.rest().row(v);
  }
  surface.triangles.resize(static_cast<Eigen::Index>(corners.size() / 3), 3);
  std::copy(corners.begin(), corners.end(), surface.triangles.data());
  return surface;
}

void TetMesh::set_current(Points current) {
  if (current.rows() != rest_.rows()) {
    throw Error(ErrorKind::kInvalidArgument, "deformed positions have " + std::to_string(current.rows()) +
                                                 " nodes, the mesh has " + std::to_string(rest_.rows()));
  }
  check_finite(current, {}, "deformed node");
  current_ = std::move(current);
}

}  // namespace tetcut
