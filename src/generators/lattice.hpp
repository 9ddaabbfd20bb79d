#pragma once
// Shared pieces of the structured generators: node numbering of a box of cubes, and assembly of a
// TetMesh from tets whose orientation is fixed up with the exact predicate.

#include <tetcut/generators.hpp>

#include <array>
#include <vector>

namespace tetcut::generators {

/// Throws unless min < max on every axis and all bounds are finite.
void check_box(const Box& box);

class Lattice {
 public:
  Lattice(const Box& box, const std::array<Index, 3>& cells) : box_(box), cells_(cells) {}

  Index num_corners() const { return (cells_[0] + 1) * (cells_[1] + 1) * (cells_[2] + 1); }
  Index num_cubes() const { return cells_[0] * cells_[1] * cells_[2]; }
  Index corner(Index i, Index j, Index k) const { return i + (cells_[0] + 1) * (j + (cells_[1] + 1) * k); }
  Index cube(Index i, Index j, Index k) const { return i + cells_[0] * (j + cells_[1] * k); }
  /// Coordinate of lattice plane i along `axis`; the last plane is exactly the box's max, so
  /// boundary nodes lie exactly on the box faces.
  double plane(int axis, Index i) const {
    if (i == cells_[axis]) return box_.max[axis];
    return box_.min[axis] + (box_.max[axis] - box_.min[axis]) * static_cast<double>(i) / cells_[axis];
  }
  Vec3 corner_position(Index i, Index j, Index k) const { return {plane(0, i), plane(1, j), plane(2, k)}; }
  /// Cube centre: the midpoint of its two bounding planes on each axis.
  Vec3 centre_position(Index i, Index j, Index k) const {
    return {0.5 * (plane(0, i) + plane(0, i + 1)), 0.5 * (plane(1, j) + plane(1, j + 1)),
            0.5 * (plane(2, k) + plane(2, k + 1))};
  }

 private:
  Box box_;
  std::array<Index, 3> cells_;
};

/// Orients every tet positively (swapping two nodes where needed) and builds the mesh.
TetMesh assemble(Points points, std::vector<std::array<Index, 4>>& tets);

}  // namespace tetcut::generators
