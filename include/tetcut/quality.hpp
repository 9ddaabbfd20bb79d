#pragma once
// Size and shape measures of a tet mesh: what `tetcut info` reports, and what sets the stable
// time step of an explicit simulation (the smallest altitude). Measures and checks of triangle
// surfaces, in one vocabulary: a surface is `balanced` when every edge is used as often in one
// direction as in the other, `two_manifold` when every edge has two triangles.

#include <tetcut/surface.hpp>
#include <tetcut/tet_mesh.hpp>

namespace tetcut {

struct MeshQuality {
  Vec3 bbox_min = Vec3::Zero();
  Vec3 bbox_max = Vec3::Zero();
  double volume = 0;               ///< sum of signed tet volumes
  double min_volume = 0;           ///< smallest tet volume
  double min_dihedral_degrees = 0; ///< over all six dihedral angles of all tets
  double max_dihedral_degrees = 0;
  double min_altitude = 0;         ///< smallest distance from a tet vertex to its opposite face
  Index num_unused_nodes = 0;      ///< nodes referenced by no tet
};

/// Measures `mesh` in rest positions, or in current positions when `current` is true. O(V + T).
MeshQuality measure_quality(const TetMesh& mesh, bool current = false);

/// Measures of a triangle surface, its vertices taken as given (no welding; check_surface
/// welds). Two properties of its edges, distinct: `balanced` (the one cutting and
/// embedding need: the winding number is defined) and `two_manifold`; the CLI's reports use the
/// same names.
struct SurfaceStats {
  Vec3 bbox_min = Vec3::Zero();
  Vec3 bbox_max = Vec3::Zero();
  double area = 0;
  /// Volume enclosed, by the divergence theorem; meaningful when the surface is balanced.
  double enclosed_volume = 0;
  Index num_boundary_edges = 0;      ///< edges with one incident triangle
  Index num_nonmanifold_edges = 0;   ///< edges with three or more incident triangles
  Index num_degenerate_triangles = 0;///< triangles with (exactly) collinear corners
  /// Edges not used equally often in each direction: boundary edges, and edges where the
  /// orientation of the incident triangles is inconsistent.
  Index num_unbalanced_edges = 0;
  /// Every edge has exactly two incident triangles: no boundary and no non-manifold edge
  /// (orientation and vertices are not looked at).
  bool two_manifold = false;
  /// Every edge is used as often in one direction as in the other: the surface is closed and
  /// consistently oriented, though it may be non-manifold (as a cut mesh's material surface may be
  /// where sheets touch). Implies an even number of triangles at every edge.
  bool balanced = false;
};

SurfaceStats measure_surface(const TriangleSurface& surface);

/// What combinatorics says about a triangle surface, after welding vertices with identical
/// coordinates: what embed() checks first. A surface is balanced (as in SurfaceStats) when every
/// edge is used as often in one direction as in the other: closed and consistently oriented, so
/// that its winding number is defined everywhere off the surface, even where the surface touches
/// or passes through itself.
struct SurfaceCheck {
  Index vertices = 0;              ///< distinct vertices after welding
  Index triangles = 0;
  Index degenerate_triangles = 0;  ///< zero area (collinear or repeated corners): skipped by the cut
  /// Edges used more often in one direction than the other: boundary edges (used once) and edges
  /// where neighbouring triangles disagree on orientation.
  Index unbalanced_edges = 0;
  Index misoriented_edges = 0;     ///< of those, edges used at least twice, all the same way
  Index nonmanifold_edges = 0;     ///< edges of more than two triangles (allowed when balanced)
  Index components = 0;            ///< connected through shared edges

  bool balanced() const { return unbalanced_edges == 0; }
};

/// Checks a surface. Throws Error(kInvalidInput) naming the triangle when a corner is not finite
/// or missing. O(F log F).
SurfaceCheck check_surface(const TriangleSurface& surface);

}  // namespace tetcut
