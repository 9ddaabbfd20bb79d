#pragma once
// Invariants every mesh-producing test checks, computed exactly where the claim is exact.

#include <tetcut/generators.hpp>
#include <tetcut/tet_mesh.hpp>

#include <gmpxx.h>

#include <string>

namespace tetcut::testing {

/// Sum of the tets' signed volumes in exact rational arithmetic.
mpq_class exact_volume(const TetMesh& mesh);

/// Exact volume of a box.
mpq_class exact_volume(const Box& box);

/// Empty when every tet has positive volume (exactly) and every face is shared by one or two
/// tets; otherwise a description of the first violation.
std::string check_positive_and_conforming(const TetMesh& mesh);

/// Empty when every boundary face (one incident tet) lies exactly on one face plane of `box`.
std::string check_boundary_on_box(const TetMesh& mesh, const Box& box);

}  // namespace tetcut::testing
