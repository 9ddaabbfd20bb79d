#pragma once
// Twins: surface vertices that are one point of the material held by different copies (the two
// sides of a cut). The surface's vertices are exact points rounded to doubles, and two copies
// may round one point through different weights, a few ulps apart, so twins are matched within
// a tolerance, never bit for bit (which missed twins where a cut meets the boundary).

#include <tetcut/types.hpp>

#include <vector>

namespace tetcut::collision {

/// Per vertex: an id shared by the vertices whose rest positions agree within `rest_tolerance`
/// (per coordinate) and whose positions `now` agree within `tolerance` (e.g. a cut not yet
/// opened there; pass `rest` and infinity for rest twins only). Rest positions are hashed into
/// cells of 4 rest_tolerance, so twins lie in neighbouring cells. O(V) expected.
std::vector<Index> twin_ids(const Points& rest, const Points& now, double rest_tolerance, double tolerance);

}  // namespace tetcut::collision
