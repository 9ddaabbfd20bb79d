#pragma once
// The invariants every cutting test checks on a result, stated once.

#include <tetcut/cutter.hpp>

#include <array>
#include <string>
#include <vector>

namespace tetcut::testing {

using Triangle = std::array<Vec3, 3>;

/// A triangle soup with three vertices of its own per triangle.
TriangleSurface soup(const std::vector<Triangle>& triangles);

/// Empty when all hold, else the first violation:
///  - every copy holds material, and the piece volumes add up to the input's volume (relative
///    error below 1e-12) and to the copies' volumes;
///  - each copy's nodes are copies of its tet's nodes, in order;
///  - pieces are exactly the classes of copies that share a face in the output mesh;
///  - the material surface is balanced (every edge used equally often each way: closed and
///    consistently oriented), encloses the material volume (relative 1e-12), and its embedding
///    reproduces the vertices' rest positions;
///  - every surface triangle lies on a copy of its piece.
std::string check_cut_invariants(const TetMesh& input, const CutResult& result);
/// The same when the material's volume is `volume` instead of the whole input's (embedding).
std::string check_cut_invariants(const TetMesh& input, const CutResult& result, double volume);

}  // namespace tetcut::testing
