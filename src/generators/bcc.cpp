#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "generators/lattice.hpp"

namespace tetcut {

namespace {

// Fraction of a cube by which the box extent may exceed a whole number of cubes before another
// cube is added: absorbs the rounding of extent / spacing (e.g. 0.3 / 0.1 = 2.9999999999999996
// must give 3 cubes, not 4). Only the cube count depends on it, never topology.
constexpr double kCubeCountSlack = 1e-9;

}  // namespace

TetMesh make_bcc(const Box& box, double spacing) {
  generators::check_box(box);
  if (!std::isfinite(spacing) || spacing <= 0) {
    throw Error(ErrorKind::kInvalidArgument, "BCC spacing must be a positive number");
  }
  std::array<Index, 3> cells{};
  Box lattice_box;
  for (int a = 0; a < 3; ++a) {
    const double extent = box.max[a] - box.min[a];
    const double count = std::max(1.0, std::ceil(extent / spacing - kCubeCountSlack));
    if (count > 5000) {
      throw Error(ErrorKind::kInvalidArgument, "spacing " + std::to_string(spacing) + " gives more than 5000 cubes along an axis");
    }
    cells[a] = static_cast<Index>(count);
    const double centre = 0.5 * (box.min[a] + box.max[a]);
    lattice_box.min[a] = centre - 0.5 * count * spacing;
    lattice_box.max[a] = centre + 0.5 * count * spacing;
  }
  const generators::Lattice lattice(lattice_box, cells);
  const Index num_corners = lattice.num_corners();
  Points points(num_corners + lattice.num_cubes(), 3);
  for (Index k = 0; k <= cells[2]; ++k) {
    for (Index j = 0; j <= cells[1]; ++j) {
      for (Index i = 0; i <= cells[0]; ++i) points.row(lattice.corner(i, j, k)) = lattice.corner_position(i, j, k);
    }
  }
  for (Index k = 0; k < cells[2]; ++k) {
    for (Index j = 0; j < cells[1]; ++j) {
      for (Index i = 0; i < cells[0]; ++i) {
        points.row(num_corners + lattice.cube(i, j, k)) = lattice.centre_position(i, j, k);
      }
    }
  }

  std::vector<std::array<Index, 4>> tets;
  // Each cube face is visited once from the cube on its low side (or the boundary cube).
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    std::array<Index, 3> face_counts = cells;
    face_counts[axis] = cells[axis] + 1;  // face planes along `axis`
    for (Index fk = 0; fk < face_counts[2]; ++fk) {
      for (Index fj = 0; fj < face_counts[1]; ++fj) {
        for (Index fi = 0; fi < face_counts[0]; ++fi) {
          const std::array<Index, 3> f{fi, fj, fk};
          // The square's corners in cyclic order around the face.
          Index square[4];
          for (int c = 0; c < 4; ++c) {
            std::array<Index, 3> p = f;
            p[u] += (c == 1 || c == 2) ? 1 : 0;
            p[v] += (c >= 2) ? 1 : 0;
            square[c] = lattice.corner(p[0], p[1], p[2]);
          }
          Index centres[2];
          int num_centres = 0;
          for (int side = 0; side < 2; ++side) {
            std::array<Index, 3> c = f;
            c[axis] -= 1 - side;  // side 0: the cube below the face, side 1: above
            if (c[axis] < 0 || c[axis] >= cells[axis]) continue;
            centres[num_centres++] = num_corners + lattice.cube(c[0], c[1], c[2]);
          }
          if (num_centres == 2) {
            for (int e = 0; e < 4; ++e) tets.push_back({centres[0], centres[1], square[e], square[(e + 1) % 4]});
          } else {
            tets.push_back({centres[0], square[0], square[1], square[2]});
            tets.push_back({centres[0], square[0], square[2], square[3]});
          }
        }
      }
    }
  }
  return generators::assemble(std::move(points), tets);
}

}  // namespace tetcut
