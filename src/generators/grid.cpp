#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>

#include <cmath>
#include <string>

#include "generators/lattice.hpp"

namespace tetcut {
namespace {

// Cube corners are numbered by their offset bits: corner c sits at (c & 1, (c >> 1) & 1, (c >> 2) & 1).
// Five-tet split: a central regular tet on four pairwise non-adjacent corners plus the four
// corners cut off around it. The two parities mirror each other so that every shared cube face
// gets the same diagonal from both sides.
constexpr int kFiveEven[5][4] = {{1, 2, 4, 7}, {0, 1, 2, 4}, {3, 1, 2, 7}, {5, 1, 4, 7}, {6, 2, 4, 7}};
constexpr int kFiveOdd[5][4] = {{0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 3, 6}, {4, 0, 5, 6}, {7, 3, 5, 6}};
// Six-tet split: one tet per monotone path from corner 0 to corner 7.
constexpr int kSix[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

}  // namespace

TetMesh make_grid(const Box& box, const std::array<Index, 3>& cells, int tets_per_cube) {
  if (tets_per_cube != 5 && tets_per_cube != 6) {
    throw Error(ErrorKind::kInvalidArgument, "tets per cube must be 5 or 6, not " + std::to_string(tets_per_cube));
  }
  generators::check_box(box);
  for (int a = 0; a < 3; ++a) {
    if (cells[a] < 1) throw Error(ErrorKind::kInvalidArgument, "cell counts must be at least 1");
  }
  const generators::Lattice lattice(box, cells);
  Points points(lattice.num_corners(), 3);
  for (Index k = 0; k <= cells[2]; ++k) {
    for (Index j = 0; j <= cells[1]; ++j) {
      for (Index i = 0; i <= cells[0]; ++i) points.row(lattice.corner(i, j, k)) = lattice.corner_position(i, j, k);
    }
  }
  std::vector<std::array<Index, 4>> tets;
  tets.reserve(static_cast<std::size_t>(lattice.num_cubes()) * tets_per_cube);
  for (Index k = 0; k < cells[2]; ++k) {
    for (Index j = 0; j < cells[1]; ++j) {
      for (Index i = 0; i < cells[0]; ++i) {
        Index corner[8];
        for (int c = 0; c < 8; ++c) corner[c] = lattice.corner(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        const bool even = (i + j + k) % 2 == 0;
        const int count = tets_per_cube;
        for (int t = 0; t < count; ++t) {
          const int* local = tets_per_cube == 6 ? kSix[t] : (even ? kFiveEven[t] : kFiveOdd[t]);
          tets.push_back({corner[local[0]], corner[local[1]], corner[local[2]], corner[local[3]]});
        }
      }
    }
  }
  return generators::assemble(std::move(points), tets);
}

PlanarMesh make_planar_grid(Index cells, double size) {
  if (cells < 1 || !(size > 0) || !std::isfinite(size)) {
    throw Error(ErrorKind::kInvalidArgument, "a planar grid needs at least one cell and a positive size");
  }
  const Index n = cells;
  PlanarMesh mesh;
  mesh.rest.resize((n + 1) * (n + 1), 2);
  for (Index j = 0; j <= n; ++j) {
    for (Index i = 0; i <= n; ++i) mesh.rest.row(j * (n + 1) + i) << size * i / n, size * j / n;
  }
  mesh.triangles.resize(2 * n * n, 3);
  for (Index j = 0; j < n; ++j) {
    for (Index i = 0; i < n; ++i) {
      const Index a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.triangles.row(2 * (j * n + i)) << a, b, c;
      mesh.triangles.row(2 * (j * n + i) + 1) << a, c, d;
    }
  }
  return mesh;
}

}  // namespace tetcut
