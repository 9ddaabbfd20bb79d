#pragma once
// The cells of one triangle of a planar mesh, refined by cut segments: a half-edge structure of
// convex polygons (the 2D counterpart of cells::CellComplex).
//
// The plane is z = 0 of the intersection registry: a line is a plane through the z axis (a wall
// along axis 2 through two input points, or a wall along axis 0 or 1 through one input point and
// that point lifted to z = 1, which is exact), and a point is the meeting of two lines and the rest
// plane. So the 2D cutter decides everything with the registry's exact side tests and shares its
// planes, its points and its exactness story with the 3D cutter.
//
// Inserting a segment splits, by the segment's line, each cell whose chord on that line overlaps
// the segment with positive length; the chord is subdivided at the segment's ends, and the pieces
// inside the segment are "covered": material does not pass through them. An edge that already
// lies on the line (an earlier cut, or the triangle's side) is subdivided and covered the same way.
// The segment's ends are bounded by walls through its endpoints along a coordinate axis (the
// segment is the part of its line on the positive side of both). Cells stay convex.
//
// Points on the triangle's sides are shared with the neighbouring triangle through
// PlanarGeometry::edge_points: one point, one vertex, whichever triangle made it first.

#include <tetcut/types.hpp>

#include <array>
#include <cstdint>
#include <vector>

#include "registry/intersection_registry.hpp"

namespace tetcut::planar {

using registry::OrientedPlane;
using registry::PlaneId;
using registry::VertexId;

/// Lines and points shared by every triangle of one mesh.
struct PlanarGeometry {
  explicit PlanarGeometry(const Points& rest3) : registry(rest3) {}

  registry::IntersectionRegistry registry;
  PlaneId rest_plane = -1;             ///< z = 0, normal +z
  std::vector<PlaneId> edge_line;      ///< per mesh edge
  std::vector<VertexId> node_vertex;   ///< per input node
  /// Per mesh edge: the registered vertices strictly inside it.
  std::vector<std::vector<VertexId>> edge_points;
  /// Per registered vertex: the mesh edge it lies strictly inside, or -1.
  std::vector<Index> vertex_edge;

  int side(VertexId v, OrientedPlane p) const { return p.sign * registry.side(v, p.id); }
  /// The vertex where `line` meets mesh edge `edge` strictly inside it: the one already there,
  /// or a new one.
  VertexId edge_point(Index edge, PlaneId line);
  /// A vertex where two lines meet strictly inside a triangle (a new point, never one on an edge).
  VertexId interior_point(PlaneId a, PlaneId b);
};

/// A cut segment ready to insert: the part of its line on the positive side of (or on) each of
/// its walls. A rest-space segment has two walls, through its ends; a world-space cut triangle
/// pulled back into one copy has up to three, its edges' walls pulled back through that copy's
/// motion (what the triangle meets of the copy is the pre-image of its line bounded by them).
struct PreparedSegment {
  static constexpr int kMaxWalls = 3;
  PlaneId line = -1;
  std::array<OrientedPlane, kMaxWalls> walls;
  int num_walls = 2;
  std::int64_t id = -1;  ///< numbering over all batches
  /// Only faces of this label (a copy) are cut; -1: every face.
  Index label = -1;
};

struct HalfEdge {
  VertexId origin = -1;
  std::int32_t twin = -1, next = -1;
  std::int32_t face = -1;  ///< -1: outside the triangle
  PlaneId line = -1;
  std::int8_t side = -1;   ///< on the triangle's side k (corner k to k + 1), or -1 inside it
  /// The first cut segment covering this edge, or -1 (uncovered: material passes).
  std::int64_t covering = -1;
};

struct Face {
  std::int32_t half_edge = -1;
  Index label = -1;  ///< the caller's: the triangle copy whose material the face is
};

/// One elementary stretch of a triangle's side: from points[i] to points[i + 1].
struct SideIntervals {
  std::vector<VertexId> points;   ///< from corner k to corner k + 1
  std::vector<Index> labels;      ///< per interval: the label of the face on it
  std::vector<std::uint8_t> covered;  ///< per interval
};

class TriangleArrangement {
 public:
  /// One cell: the triangle with corners (counter-clockwise), the lines of its sides (side k from
  /// corner k to k + 1) and the mesh edges they lie on.
  TriangleArrangement(std::array<VertexId, 3> corners, std::array<PlaneId, 3> side_lines,
                      std::array<Index, 3> side_edges, Index label);

  /// Inserts a segment into the faces it may cut (segment.label); returns whether any material
  /// was newly separated or bounded (a cell split, or an edge newly covered). O(cells + their edges).
  bool insert(PlanarGeometry& geometry, const PreparedSegment& segment);

  const std::vector<Face>& faces() const { return faces_; }
  const std::vector<HalfEdge>& half_edges() const { return half_edges_; }
  std::vector<Face>& mutable_faces() { return faces_; }

  /// Connected components of the material: faces joined across uncovered edges. Writes each face's
  /// component, numbered in order of each component's first face; returns the count.
  int components(std::vector<int>* face_component) const;
  /// The pieces of side k, in order from corner k to corner k + 1.
  SideIntervals side_intervals(int k) const;
  /// Area of a face from the rounded positions of its corners (for measurements only).
  double face_area(const registry::IntersectionRegistry& registry, int face) const;
  /// The face's corners, counter-clockwise.
  std::vector<VertexId> face_corners(int face) const;

 private:
  bool insert_into_face(PlanarGeometry& geometry, int face, const PreparedSegment& segment);
  bool cover_collinear(PlanarGeometry& geometry, std::int32_t h, const PreparedSegment& segment);
  /// Puts `point` inside half-edge h (and its twin); returns the half-edge from the point on.
  std::int32_t split_edge(std::int32_t h, VertexId point);
  /// The point where `line` meets half-edge h strictly inside it.
  VertexId point_on_edge(PlanarGeometry& geometry, std::int32_t h, PlaneId line);
  void cover(std::int32_t h, std::int64_t id);

  std::array<VertexId, 3> corners_;
  std::array<Index, 3> side_edges_;
  std::vector<HalfEdge> half_edges_;
  std::vector<Face> faces_;
};

}  // namespace tetcut::planar
