#pragma once
// The two-dimensional version of the cutter (the paper's Figure 1): a triangle mesh lying in its
// rest plane, cut by polylines.
//
//   tetcut::PlanarCutter cutter(mesh);        // triangles counter-clockwise in the (x, y) plane
//   cutter.cut(polylines);                    // any number of batches, in rest space
//   cutter.cut_deformed(blade, positions);    // or in world space, on the deformed cloth
//   const tetcut::PlanarCutResult r = cutter.result();
//   r.mesh.mesh        // one copy of a triangle per material component, sharing nodes across edges
//   r.material         // the material (cells and boundary), embedded in the copies
//
// Polylines may be open or closed, cross themselves and each other, run through vertices and
// along edges, overlap and repeat, and end inside a triangle. The guarantees are the 3D cutter's,
// from the same exact machinery: points are meetings of lines (stored as planes through the z
// axis in the intersection registry, with the rest plane as the third plane), and every decision
// is a filtered side test with a GMP fallback. World-space cuts are pulled back per copy through
// its motion, as in 3D. Only triangles a batch touches change; node and copy ids, once given, stay.

#include <tetcut/surface.hpp>
#include <tetcut/types.hpp>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace tetcut {

/// |V| x 2 rest coordinates in the plane.
using Points2 = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;

/// A triangle mesh in its rest plane. Every triangle must be counter-clockwise (positive area),
/// and an edge may be shared by at most two triangles.
struct PlanarMesh {
  Points2 rest;
  Triangles triangles;

  Index num_nodes() const { return static_cast<Index>(rest.rows()); }
  Index num_triangles() const { return static_cast<Index>(triangles.rows()); }
};

/// A cut: the segments between consecutive points, and from the last back to the first when
/// closed. Repeated points give zero-length segments, which are skipped and reported.
struct Polyline {
  Points2 points;
  bool closed = false;

  Index num_segments() const {
    const Index n = static_cast<Index>(points.rows());
    return n < 2 ? 0 : (closed && n > 2 ? n : n - 1);
  }
};

/// The cut mesh: each material component of an input triangle has its own copy of the triangle,
/// with the triangle's rest positions; copies whose shared edge holds common material share that
/// edge's nodes. Input node n keeps id n and duplicated nodes follow; triangle t's first copy is t.
struct PlanarCutMesh {
  PlanarMesh mesh;
  std::vector<Index> node_parent;              ///< per node: the input node it copies
  std::vector<Index> triangle_parent;          ///< per copy: the input triangle it copies
  std::vector<Index> triangle_piece;           ///< per copy: its piece (pieces by area, largest first)
  std::vector<double> triangle_material_area;  ///< per copy: the area of the material it holds
  std::vector<double> piece_areas;             ///< per piece, largest first

  Index num_pieces() const { return static_cast<Index>(piece_areas.size()); }
  /// Per copy: its material area over its triangle's rest area (what mass and stiffness scale by).
  std::vector<double> material_fractions() const;
};

/// The material, embedded in the copies: the cells of the arrangement as triangles (fans), and
/// its boundary (both sides of every cut and the uncut outer boundary) as segments with the
/// material on their left. Triangles and segments share vertices; each vertex is embedded in one
/// triangle copy by barycentric weights, so it follows the cloth as it deforms. A vertex is shared
/// exactly by the copies that move it alike: both sides of a cut have their own.
struct PlanarMaterial {
  Points2 rest;  ///< vertex rest positions
  /// Per vertex: the copy it is embedded in and its weights (|V| x 3, summing to one).
  std::vector<Index> vertex_copy;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> vertex_weights;
  /// The material region, counter-clockwise, and per triangle the copy it belongs to.
  Triangles triangles;
  std::vector<Index> triangle_copy;
  /// |S| x 2 vertex ids, material on the left going from the first to the second.
  Edges segments;
  /// Per segment: the cut it lies on, a rest-space segment or a world-space triangle (numbered
  /// together over all batches, in order), or -1 - e for mesh edge e on the outer boundary (edges
  /// numbered as PlanarCutter::edge_nodes gives them).
  std::vector<std::int64_t> segment_source;
  std::vector<Index> segment_copy;  ///< per segment: the copy whose material it bounds

  Index num_vertices() const { return static_cast<Index>(rest.rows()); }
  Index num_triangles() const { return static_cast<Index>(triangles.rows()); }
  Index num_segments() const { return static_cast<Index>(segments.rows()); }
  /// Vertex positions (|V| x 3) for positions of the cut mesh's nodes (|nodes| x 3, e.g. deformed).
  Points positions(const PlanarCutMesh& mesh, const Points& nodes) const;
};

struct PlanarCutResult {
  PlanarCutMesh mesh;
  PlanarMaterial material;
};

/// What one batch did, and what a simulator needs to carry its state over (see CutBatchReport).
struct PlanarCutReport {
  Index segments = 0;                ///< segments in the batch (cut_deformed: triangles)
  /// Zero-length segments (cut_deformed: zero-area triangles), numbered in the batch, skipped.
  std::vector<Index> degenerate;
  /// cut_deformed: copies lying in the plane of a cut triangle that reaches them, ascending. The
  /// triangle would meet them in an area, not a line, so it does not cut them.
  std::vector<Index> skipped_coplanar;
  std::vector<Index> touched;        ///< input triangles whose material changed, ascending
  Index first_new_node = 0;          ///< nodes from here on are new ...
  std::vector<Index> new_node_source;     ///< ... split from these nodes
  Index first_new_triangle = 0;      ///< copies from here on are new ...
  std::vector<Index> new_triangle_source; ///< ... split from these copies
  std::vector<Index> changed_triangles;   ///< older copies whose nodes changed, ascending
};

/// A coordinate plane in space that a planar mesh lies in: rest (u, v) are the coordinates on axes
/// `u` and `v`, the coordinate on axis `normal` is `offset`.
struct RestPlane {
  int u = 0, v = 1, normal = 2;
  double offset = 0;
};

/// The planar mesh of a triangle surface lying in a coordinate plane (one coordinate the same,
/// bit for bit, at every vertex), with (u, v) ordered so that its triangles are counter-clockwise.
/// Error(kInvalidInput) when no coordinate is constant or the triangles are not all of one
/// orientation there (naming one that differs).
PlanarMesh planar_mesh(const TriangleSurface& surface, RestPlane* plane);
/// Points in space (|P| x 3) to (u, v), dropping the normal coordinate; and back.
Points2 to_plane(const Points& points, const RestPlane& plane);
Points to_space(const Points2& points, const RestPlane& plane);

class PlanarCutter {
 public:
  /// Takes the mesh to cut; each triangle starts as its own copy over the input nodes. Throws
  /// Error(kInvalidInput) naming the triangle or node for a non-finite coordinate, an id out of
  /// range, a triangle that is not counter-clockwise (zero or negative area, decided exactly) or an
  /// edge shared by more than two triangles. O(T log T).
  explicit PlanarCutter(PlanarMesh mesh);
  ~PlanarCutter();
  PlanarCutter(PlanarCutter&&) noexcept;
  PlanarCutter& operator=(PlanarCutter&&) noexcept;

  /// Cuts by a batch of polylines in rest coordinates. Throws Error(kInvalidInput) naming the
  /// polyline and point when a coordinate is not finite, changing nothing. Cost: proportional to
  /// the triangles the batch touches and the cells already in them, plus O(log T) per segment,
  /// plus O(T) to recount the pieces.
  PlanarCutReport cut(std::span<const Polyline> batch);

  /// Cuts in world space, on the cut mesh with its nodes at `nodes` (num_nodes() x 3, e.g. the
  /// cloth as it hangs), by a batch of triangles (e.g. the strip a blade sweeps, swept_blade, or a
  /// polyline pushed through the cloth). Each triangle copy that a triangle reaches in its current
  /// shape is cut along the pre-image of what the triangle meets of it: the triangle's plane and
  /// its edges' walls pulled back through the copy's own affine motion (as Cutter::cut_deformed
  /// does per tet), inserted into that copy's cells only. The pull-backs are exact, and on an edge
  /// they depend only on its two nodes, so copies sharing an edge and its nodes cut it at the very
  /// same registered point. A copy lying in a triangle's plane where the triangle reaches it is
  /// not cut by it and is reported (skipped_coplanar); zero-area triangles are skipped and
  /// reported. Throws Error(kInvalidInput), changing nothing, for a non-finite or missing corner,
  /// a wrong number of node positions or a non-finite one. Cost: O(copies) to find those near the
  /// batch (a pass over their current boxes), then as cut() per copy a triangle reaches.
  PlanarCutReport cut_deformed(const TriangleSurface& batch, const Points& nodes);

  /// Maps points on the mesh in its deformed positions (|P| x 3, e.g. a blade drawn on the cloth)
  /// to rest coordinates: each through the affine motion of the triangle copy nearest to it (in
  /// world space, over copies that are not degenerate in `nodes`). Geometry, not topology: the
  /// result is rounded (cut_deformed is the exact world-space cut); cutting along it is a
  /// rest-space cut, for a path that must follow the material across batches while the cloth
  /// moves. O(copies) per point.
  Points2 to_rest(const Points& world, const Points& nodes) const;

  PlanarCutResult result() const;

  Index num_nodes() const;
  Index num_triangles() const;  ///< copies
  /// Per copy, its three nodes in its input triangle's order.
  const std::vector<std::array<Index, 3>>& triangle_nodes() const;
  const std::vector<Index>& node_parent() const;
  const std::vector<Index>& triangle_parent() const;
  /// Input mesh edges (node pairs, smaller id first), as numbered in PlanarMaterial.
  const std::vector<std::array<Index, 2>>& edge_nodes() const;
  const PlanarMesh& input() const;
  /// Cells (convex polygons of the arrangement) over all triangles: for measurements and tests.
  Index num_cells() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tetcut
