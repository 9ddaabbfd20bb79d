#pragma once
// A bounding-box hierarchy over closed axis-aligned boxes, to find the tets a cut triangle may
// touch. Queries compare doubles only (no arithmetic), so the answer is exact: every box that
// meets the query box, touching included, is reported.

#include <tetcut/types.hpp>

#include <vector>

namespace tetcut::spatial {

struct Aabb {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

  void extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void extend(const Aabb& b) {
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  bool meets(const Aabb& b) const { return (min.array() <= b.max.array()).all() && (b.min.array() <= max.array()).all(); }
};

class BoxTree {
 public:
  BoxTree() = default;
  /// Builds the hierarchy by median splits on the longest axis of the centres. O(n log n).
  explicit BoxTree(std::vector<Aabb> boxes);

  /// Appends to `out` the index of every box that meets `query`, in increasing order.
  /// O(log n + answers) for well-spread boxes.
  void query(const Aabb& query, std::vector<Index>* out) const;

  /// Replaces the boxes (same count, same order) and recomputes the node boxes bottom-up,
  /// keeping the hierarchy: O(n), for boxes that move a little (a deforming mesh).
  void refit(std::vector<Aabb> boxes);
  /// The same in place: write the new boxes into mutable_boxes() (same count, same order), then
  /// refit(). Nothing is allocated.
  std::vector<Aabb>& mutable_boxes() { return boxes_; }
  void refit();

  Index size() const { return static_cast<Index>(boxes_.size()); }

 private:
  struct Node {
    Aabb box;
    Index first = 0;  ///< leaf: first item; inner: first child (the second is first + 1)
    Index count = 0;  ///< leaf: number of items; inner: 0
  };
  void build(Index node, Index begin, Index end, const std::vector<Vec3>& centres);
  void refit_node(Index node);

  std::vector<Aabb> boxes_;
  std::vector<Index> items_;
  std::vector<Node> nodes_;
};

}  // namespace tetcut::spatial
