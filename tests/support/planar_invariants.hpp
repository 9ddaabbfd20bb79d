#pragma once
// The invariants every planar (cloth) cutting test checks on a result, stated once.

#include <tetcut/planar_cutter.hpp>

#include <array>
#include <initializer_list>
#include <vector>

namespace tetcut::testing {

/// A polyline through the given (x, y) points.
Polyline polyline(std::initializer_list<std::array<double, 2>> points, bool closed = false);

/// The mesh's rest area.
double planar_area(const PlanarMesh& mesh);

/// The piece areas, smallest first.
std::vector<double> sorted_areas(const PlanarCutResult& r);

/// Checks (as gtest expectations) what every cut must keep: copies hold material and add up per
/// piece, pieces add up to the mesh (relative 1e-12), the boundary is closed (as many segments
/// leave every vertex as enter it) and oriented with the material on its left (its shoelace sum,
/// per piece, is that piece's area), the material triangles cover each piece counter-clockwise,
/// and embedded vertices sit where their copies' rest corners put them.
void expect_planar_invariants(const PlanarMesh& input, const PlanarCutResult& r);

}  // namespace tetcut::testing
