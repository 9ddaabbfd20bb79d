#include "support/invariants.hpp"

#include "geometry/predicates.hpp"

namespace tetcut::testing {

mpq_class exact_volume(const TetMesh& mesh) {
  mpq_class sum = 0;
  const Points& p = mesh.rest();
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    mpq_class m[3][3];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m[r][c] = mpq_class(p(mesh.tets()(t, r + 1), c)) - mpq_class(p(mesh.tets()(t, 0), c));
    }
    sum += m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  }
  return sum / 6;
}

mpq_class exact_volume(const Box& box) {
  mpq_class v = 1;
  for (int a = 0; a < 3; ++a) v *= mpq_class(box.max[a]) - mpq_class(box.min[a]);
  return v;
}

std::string check_positive_and_conforming(const TetMesh& mesh) {
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    const auto& p = mesh.rest();
    const auto& tet = mesh.tets();
    if (geometry::orient3d(p.row(tet(t, 0)).data(), p.row(tet(t, 1)).data(), p.row(tet(t, 2)).data(),
                           p.row(tet(t, 3)).data()) <= 0) {
      return "tet " + std::to_string(t) + " is not positively oriented";
    }
  }
  const TetAdjacency& adj = mesh.adjacency();
  for (Index f = 0; f < adj.num_faces(); ++f) {
    const std::size_t n = adj.tets_of_face(f).size();
    if (n < 1 || n > 2) return "face " + std::to_string(f) + " is shared by " + std::to_string(n) + " tets";
  }
  return {};
}

std::string check_boundary_on_box(const TetMesh& mesh, const Box& box) {
  const TetAdjacency& adj = mesh.adjacency();
  for (Index f = 0; f < adj.num_faces(); ++f) {
    if (adj.tets_of_face(f).size() != 1) continue;
    bool on_some_plane = false;
    for (int axis = 0; axis < 3 && !on_some_plane; ++axis) {
      for (const double plane : {box.min[axis], box.max[axis]}) {
        bool all = true;
        for (int k = 0; k < 3; ++k) all = all && mesh.rest()(adj.faces(f, k), axis) == plane;
        on_some_plane = on_some_plane || all;
      }
    }
    if (!on_some_plane) return "boundary face " + std::to_string(f) + " is not on the box boundary";
  }
  return {};
}

}  // namespace tetcut::testing
