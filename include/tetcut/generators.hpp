#pragma once
// Structured meshes: boxes of cubes split into tets, BCC lattices, and planar squares of triangles.

#include <tetcut/planar_cutter.hpp>
#include <tetcut/tet_mesh.hpp>

#include <array>

namespace tetcut {

struct Box {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Ones();
};

/// A box of cells[0] x cells[1] x cells[2] cubes, each split into 5 tets (alternating between
/// the two mirror-image splits so that faces conform) or 6 tets (Freudenthal/Kuhn split along
/// each cube's main diagonal). Nodes on the box faces lie exactly on them, so the tet volumes
/// add up to the box volume exactly. Throws Error(kInvalidArgument) on an empty box or a cell
/// count below 1.
TetMesh make_grid(const Box& box, const std::array<Index, 3>& cells, int tets_per_cube);

/// A body-centred cubic lattice (Molino, Bridson, Teran, Fedkiw 2003) of cube size `spacing`:
/// nodes at cube corners and cube centres, and four tets around each edge joining the centres
/// of two neighbouring cubes. On the boundary, each half-octahedron becomes a pyramid from the
/// cube centre to the boundary square, split into two tets, so the mesh fills its box exactly.
/// The lattice has ceil(extent / spacing) cubes along each axis (at least one), centred on `box`,
/// so it covers `box`.
TetMesh make_bcc(const Box& box, double spacing);

/// A square of side `size` at the origin as cells x cells squares, each split along its diagonal
/// from (i, j) to (i + 1, j + 1) into two counter-clockwise triangles: node (i, j) is
/// j (cells + 1) + i, square (i, j) holds triangles 2 (j cells + i) and the one after. Throws
/// Error(kInvalidArgument) on a cell count below 1 or a size that is not positive.
PlanarMesh make_planar_grid(Index cells, double size = 1);

}  // namespace tetcut
