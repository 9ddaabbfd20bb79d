#pragma once
// The material of one tet as a complex of convex cells, refined by cut triangles.
//
// Start: one cell, the tet, bounded by its four face planes. Inserting a cut triangle splits only
// the cells whose closure meets the triangle: first by the triangle's three walls (planes through
// each edge along the axis that the triangle's normal is largest on), keeping the outer pieces as
// they are, then the piece inside the walls by the triangle's plane. The facet created on the plane
// then lies inside the triangle, so it is "covered": material does not pass through it. A cell that
// already has a facet on the triangle's plane inside the walls gets that facet covered instead
// (cuts along earlier cuts or along tet faces).
//
// Material components of the tet are the classes of cells joined through uncovered facets. This
// handles partial cuts (the cells on both sides of a cut stay joined around its edge), closed cut
// surfaces floating inside the tet, T-cuts, and coplanar overlapping cuts with no special cases.
//
// The complex is conforming: facets are shared records (front cell, back cell), and a vertex
// inserted on an edge is inserted into every facet that has that edge. All vertices are meetings
// of three planes of the tet's plane table; every decision uses the exact predicates of
// geometry/plane.hpp. Identical planes are stored once, so walls that coincide with tet faces or
// other cuts refer to the same plane.

#include <tetcut/types.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "geometry/plane.hpp"

namespace tetcut::cells {

using PlaneId = std::int32_t;
using VertexId = std::int32_t;
using FacetId = std::int32_t;
using CellId = std::int32_t;

inline constexpr CellId kOutside = -1;

struct Vertex {
  std::array<PlaneId, 3> planes;
  std::int8_t orientation;  // sign of det3 of the three normals
};

struct Facet {
  PlaneId plane = -1;
  /// Vertex cycle, counter-clockwise seen from the side the plane's normal points to.
  std::vector<VertexId> vertices;
  /// edge_planes[i] is the second plane through edge (vertices[i], vertices[i + 1]).
  std::vector<PlaneId> edge_planes;
  CellId front = kOutside;  ///< cell on the side the plane's normal points to
  CellId back = kOutside;
  bool covered = false;     ///< inside a cut triangle: a material boundary
  std::int32_t cut = -1;    ///< the cut triangle that covered it first, or -1
  /// Tet face (0-3, opposite that local node) this facet lies on, or -1 for facets inside the tet.
  std::int8_t tet_face = -1;
};

struct Cell {
  std::vector<FacetId> facets;
};

class CellComplex {
 public:
  /// The four corners of a positively oriented tet.
  explicit CellComplex(const std::array<Vec3, 4>& corners);

  /// Inserts the cut triangle (a, b, c), which must not be degenerate (collinear corners), with an
  /// id recorded on the facets it covers. O(cells touched x facets per cell).
  void insert_triangle(const Vec3& a, const Vec3& b, const Vec3& c, std::int32_t cut_id);

  /// Component id of every cell (0 .. num_components - 1), ordered by the lowest cell id.
  std::vector<std::int32_t> components(std::int32_t* num_components) const;

  /// Volume of a cell from rounded vertex coordinates (output only).
  double cell_volume(CellId cell) const;
  /// Rounded coordinates of a vertex (output only).
  Vec3 position(VertexId v) const;

  const std::vector<Cell>& cells() const { return cells_; }
  const std::vector<Facet>& facets() const { return facets_; }
  const std::vector<Vertex>& vertices() const { return vertices_; }
  const std::vector<geometry::Plane>& planes() const { return planes_; }

  /// Checks the complex's invariants exactly: every facet's vertices lie on its plane and each
  /// edge's endpoints on its edge plane; every cell is closed, each of its edges used once in each
  /// direction by its outward-oriented facets; front/back and cell facet lists agree. Returns an
  /// empty string when all hold, else the first violation. O(total facet size x log).
  std::string validate() const;

  /// Side (+1, 0, -1) of a vertex relative to a plane of the table. Exact.
  int side(VertexId v, PlaneId plane) const;

 private:
  struct OrientedPlane {
    PlaneId id;
    int sign;  // +1 if the requested orientation matches the stored plane, -1 if opposite
  };
  OrientedPlane add_plane(const geometry::Plane& plane);
  VertexId add_vertex(PlaneId a, PlaneId b, PlaneId c);

  /// Splits `cell` by `plane` when the plane passes through its interior. The part on the positive
  /// side keeps the id `cell`; returns the id of the negative part, or -1 when nothing was split.
  /// The facet created on the plane is returned through `section`.
  CellId split(CellId cell, PlaneId plane, FacetId* section);

  /// -1, 0 or +1 when all vertices of the cell are <= 0, mixed, or >= 0 relative to the plane;
  /// 2 when all are exactly on it (impossible for a cell with volume).
  int classify(CellId cell, PlaneId plane) const;

  void index_edges(FacetId f);
  void unindex_edges(FacetId f);
  /// Inserts w between u and v in every facet that has the edge (u, v).
  void insert_on_edge(VertexId u, VertexId v, VertexId w);

  static std::uint64_t edge_key(VertexId u, VertexId v) {
    if (u > v) std::swap(u, v);
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(u)) << 32) | static_cast<std::uint32_t>(v);
  }

  std::vector<geometry::Plane> planes_;
  std::vector<Vertex> vertices_;
  std::vector<Facet> facets_;
  std::vector<Cell> cells_;
  std::unordered_map<std::uint64_t, std::vector<FacetId>> facets_of_edge_;
  // Memo of vertex sides for the planes of the insertion in progress (2 = not yet computed).
  mutable std::vector<std::pair<PlaneId, std::vector<std::int8_t>>> side_memo_;
};

}  // namespace tetcut::cells
