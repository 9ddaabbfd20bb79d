#pragma once
// A tetrahedral mesh: rest (material) positions, current (deformed) positions, tets, and the
// face and edge adjacency derived from the tets.

#include <tetcut/types.hpp>

#include <array>
#include <span>
#include <string>
#include <vector>

namespace tetcut {

/// Local face f of a tet is the triangle opposite its local vertex f, ordered so that its normal
/// points out of the tet.
inline constexpr std::array<std::array<int, 3>, 4> kTetFaces{{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};
/// Local edges of a tet as pairs of local vertices.
inline constexpr std::array<std::array<int, 2>, 6> kTetEdges{{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

/// Faces and edges of a tet mesh, each stored once. Built in O(T log T).
struct TetAdjacency {
  /// |F| x 3 unique faces, node ids sorted ascending.
  Triangles faces;
  /// |T| x 4 id of local face f of each tet (see kTetFaces).
  Tets tet_faces;
  /// Tets incident on face `f` are face_tets[face_tets_begin[f] .. face_tets_begin[f + 1]).
  std::vector<Index> face_tets_begin;
  std::vector<Index> face_tets;
  /// |E| x 2 unique edges, node ids sorted ascending.
  Edges edges;
  /// |T| x 6 id of local edge e of each tet (see kTetEdges).
  Eigen::Matrix<Index, Eigen::Dynamic, 6, Eigen::RowMajor> tet_edges;

  Index num_faces() const { return static_cast<Index>(faces.rows()); }
  Index num_edges() const { return static_cast<Index>(edges.rows()); }
  std::span<const Index> tets_of_face(Index f) const {
    return {face_tets.data() + face_tets_begin[f], face_tets.data() + face_tets_begin[f + 1]};
  }
  /// The tet across local face `f` of tet `t`, or -1 when that face is on the boundary (or, in
  /// a cut mesh with virtual nodes, shared by more than two tet copies).
  Index neighbor(Index t, int f) const;
  /// Number of faces incident on exactly one tet.
  Index num_boundary_faces() const;
  /// Number of faces incident on three or more tets (zero for a conforming input mesh).
  Index num_overshared_faces() const;
};

class TetMesh {
 public:
  TetMesh() = default;
  /// Takes rest positions and tets; current positions start equal to rest. Throws tetcut::Error
  /// (kInvalidInput) naming `source` and the element when a node id is out of range, a coordinate
  /// is not finite, or a tet does not have positive rest volume (decided exactly). `tet_lines`,
  /// when not empty, gives the source line of each tet for the message.
  TetMesh(Points rest, Tets tets, const std::string& source = {}, std::span<const std::int64_t> tet_lines = {});

  Index num_nodes() const { return static_cast<Index>(rest_.rows()); }
  Index num_tets() const { return static_cast<Index>(tets_.rows()); }
  const Points& rest() const { return rest_; }
  const Points& current() const { return current_; }
  /// Replaces the deformed positions; must be |V| x 3 and finite.
  void set_current(Points current);
  const Tets& tets() const { return tets_; }
  const TetAdjacency& adjacency() const { return adjacency_; }

 private:
  Points rest_;
  Points current_;
  Tets tets_;
  TetAdjacency adjacency_;
};

struct TriangleSurface;

/// Where a triangle of boundary_surface comes from: the tet it bounds and which face of it (local
/// face `local_face`, see kTetFaces).
struct BoundaryFace {
  Index tet = -1;
  int local_face = -1;
};

/// The faces incident on exactly one tet, oriented outward, over the mesh's node ids (rest
/// positions); unused nodes are dropped and the vertex ids renumbered. With `faces`, also where
/// each triangle comes from (one entry per triangle, in order). O(T).
TriangleSurface boundary_surface(const TetMesh& mesh, std::vector<BoundaryFace>* faces = nullptr);

/// Builds faces and edges of `tets` (ids below `num_nodes`).
TetAdjacency build_adjacency(const Tets& tets, Index num_nodes);

/// Signed volume of the tet (a, b, c, d): det[b - a, c - a, d - a] / 6, rounded.
double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

}  // namespace tetcut
