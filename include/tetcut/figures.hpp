#pragma once
// The inputs of the paper's figures, so that examples, benchmarks, tests and the demo all cut the
// same thing.

#include <tetcut/generators.hpp>
#include <tetcut/surface.hpp>
#include <tetcut/tet_mesh.hpp>

#include <cstdint>

namespace tetcut::figures {

/// Figure 2's mesh: the single tet (0,0,0), (1,0,0), (0,1,0), (0,0,1).
TetMesh figure2_tet();

/// Figure 2's cut: `count` triangles, each in a random plane through a random point of the tet,
/// centred there, with a random size from 0.2 to 1.5, so that large ones slice through and small
/// ones end inside. Deterministic for a seed (with libstdc++'s distributions).
TriangleSurface figure2_triangles(std::uint64_t seed = 2007, int count = 50);

/// Figure 4's mesh: the unit cube as a 4 x 4 x 4 grid of 5-tet cubes, 320 tets.
TetMesh figure4_cube();

/// Figure 4's cut: 16 planes x = i/17 and 16 planes y = i/17 (i = 1..16), each a square of two
/// triangles reaching past the cube, which cut it into 17 x 17 = 289 sticks.
TriangleSurface figure4_planes();

/// An axis-aligned square {x[axis] = value} over [lo, hi]^2 in the other two axes, as two
/// triangles whose normal points along +axis.
TriangleSurface axis_square(int axis, double value, double lo, double hi);

/// A closed, outward-oriented icosphere: the icosahedron with each triangle split into four
/// `subdivisions` times (20 * 4^subdivisions triangles), vertices pushed onto the sphere.
TriangleSurface icosphere(const Vec3& centre, double radius, int subdivisions);

/// The closed, outward-oriented boundary of a box: 8 vertices, 12 triangles.
TriangleSurface box_surface(const Box& box);

/// Concatenates soups.
TriangleSurface concatenate(const TriangleSurface& a, const TriangleSurface& b);

}  // namespace tetcut::figures
