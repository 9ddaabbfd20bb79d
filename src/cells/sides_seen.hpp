#pragma once
// What the sides of a set of vertices relative to a plane say together: the predicates and the
// splitting both classify cells and facets this way.

namespace tetcut::cells {

struct SidesSeen {
  bool positive = false, negative = false;
  void add(int side) {
    positive = positive || side > 0;
    negative = negative || side < 0;
  }
  bool both() const { return positive && negative; }
  /// -1 all <= 0, 0 both sides, +1 all >= 0, 2 all on the plane.
  int classification() const { return both() ? 0 : positive ? 1 : negative ? -1 : 2; }
};

}  // namespace tetcut::cells
