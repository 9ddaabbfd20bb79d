#pragma once
// Whether the material surface passes through itself: exact triangle-triangle tests between parts
// of the surface of different tet copies (what `tetcut sim --check-intersections` reports per
// frame). A measure; the response is the simulator's surface contact (Simulator::set_contact_surface).

#include <tetcut/cutter.hpp>

#include <array>
#include <span>

namespace tetcut {

/// Whether the closed triangles (a0, a1, a2) and (b0, b1, b2) share a point, decided exactly
/// (orient3d and orient2d with exact fallbacks): touching at a point or along an edge counts,
/// coplanar overlap counts. Both must be non-degenerate (corners not collinear).
bool triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b);

struct SurfaceIntersections {
  Index intersecting_pairs = 0;  ///< pairs of triangles of different copies that intersect
  Index candidate_pairs = 0;     ///< pairs of different copies whose boxes meet (tested, or excluded)
  /// Triangles with collinear corners where they are now or in the material (bounding no
  /// material: a sliver, or two corners at one material point embedded twice): not tested.
  Index degenerate_triangles = 0;
  /// Up to 16 intersecting pairs (triangle ids, the smaller first), in increasing order.
  std::vector<std::array<Index, 2>> examples;
};

/// Counts the pairs of material-surface triangles bounding different tet copies that intersect
/// with the surface's vertices at `positions` (|V| x 3, e.g. Session::surface_positions());
/// `copy_nodes` are the cut mesh's copies (Cutter::tet_nodes). Excluded, as touching by
/// construction rather than colliding:
/// - pairs that share a point across a cut not yet opened there: two vertices with the same rest
///   position (up to its rounding, 64 ulps of the largest rest coordinate: copies may round one
///   exact point differently) that are still within `opened` of each other now (at least the rounding
///   of placing a vertex by its copy's weights, 64 ulps of the largest coordinate; a simulation
///   passes its solver's noise, since the two sides of a cut, free to drift, wander around each
///   other by about its tolerance before anything opens them); and pairs on the two
///   sides of one cut triangle whose six corners are all such unopened points (the two sides'
///   triangulations of a polygon overlap without always sharing a corner); and pairs that touch
///   in the material (decided exactly, or apart there by no more than `opened` or the rounding
///   of rest points, 64 ulps as above: surface contact leaves pairs within its allowance in the
///   material out of its barrier, as touching; or lying in one plane there, facing each other,
///   anywhere along it: the two sides of a flat part of a cut, whose fans may put a corner of one
///   a little beside the other's triangle, and which contact leaves out as lying across one cut
///   when they are within its thickness) and now cross by at most `opened` (one reaches no further than
///   that behind the other, the material being behind each: the sides of a cut pressed
///   together, which slide along each other as each bulges; or, where they are not coplanar,
///   the segment where they cross lies within `opened` of both triangles' rims: a face that meets
///   a cut at a rim, the side of a neighbour pressed into it there). So the two sides of a fresh cut,
///   which coincide, are not counted, and are as soon as they have moved apart and cross, or
///   pressed together, go into each other by more than `opened`. A simulation with surface
///   contact passes the fresh-cut allowance of its guards (a hundredth of an edge; see
///   Simulator::SurfaceContactState).
/// - pairs apart in the material by no more than `slid` that cross by no more than `opened`, as
///   above: the sides of a cut pressed together and slid along each other, a rim of one side now
///   pressed into the other's face beside it, or across a crease of the cut. Contact leaves pairs
///   that close across a cut to its guards, which let them go into each other by the allowance,
///   as they let touching ones. A simulation with surface contact passes how far apart those may
///   lie (Simulator::SurfaceContactState::guarded_reach, two thicknesses; on the slinky, the
///   upper lip of its shell's slit pressed 3e-5 into the lower lip's rim, 0.0017 from it along the
///   cut in the material, counted as crossing before). 0: only pairs touching there.
/// Pairs of copies that share a node count as any others: where a cut runs between two such
/// copies (near an incision's end, a folded flap's hinge, the neighbouring coils of a slinky cut
/// out of tets larger than its pitch) their sides pass through each other as any others' do (the
/// folded flap's, pressed together where its cut ends, crossed in 18 pairs that were left out as
/// meeting by construction). Where their surfaces do meet by construction, they touch in the
/// material and fall under the rules above (folds of 1e-16 where tets' faces miss each other by
/// rounding, a cut along 0.5 through a lattice at thirds, which deformed positions, rounded,
/// show as crossing by as little).
/// Broad phase: a box hierarchy over the triangles; O(F log F + candidates), parallel. Throws
/// Error(kInvalidArgument) when `positions` has the wrong size or a triangle names a copy that
/// `copy_nodes` lacks.
SurfaceIntersections count_surface_intersections(const MaterialSurface& surface, std::span<const std::array<Index, 4>> copy_nodes,
                                                 const Points& positions, double opened = 0, double slid = 0);

}  // namespace tetcut
