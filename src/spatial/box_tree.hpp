#pragma once
// A bounding-box hierarchy over closed axis-aligned boxes, to find the tets a cut triangle may
// touch. Queries compare doubles only (no arithmetic), so the answer is exact: every box that
// meets the query box, touching included, is reported.

#include <tetcut/types.hpp>

#include <tbb/parallel_invoke.h>

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
  /// The Euclidean distance between the two boxes (0 where they meet): no point of one is nearer
  /// any point of the other.
  double gap(const Aabb& b) const {
    const Vec3 apart = (min - b.max).cwiseMax(b.min - max).cwiseMax(0.0);
    return apart.norm();
  }
  /// The box grown by `by` on every side: it meets another box when the two come within `by`.
  Aabb grown(double by) const {
    Aabb out = *this;
    out.min.array() -= by;
    out.max.array() += by;
    return out;
  }
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

  /// Calls visit(i, j) once for every pair of boxes i != j that come within `distance` of each
  /// other (i grown by it meets j), in no fixed order and from several threads at once (the
  /// upper levels of the hierarchy run as parallel tasks). A traversal of the hierarchy against
  /// itself: each pair of nodes is looked at once, where a query per box would start from the
  /// root for each and meet every pair twice.
  template <typename Visit>
  void self_join(double distance, const Visit& visit) const {
    if (!nodes_.empty()) join_within(0, distance, visit, 0);
  }

 private:
  // Below this depth the traversal forks into parallel tasks.
  static constexpr int kParallelDepth = 6;
  template <typename Visit>
  void join_within(Index node, double distance, const Visit& visit, int depth) const {
    const Node& n = nodes_[node];
    if (n.count > 0) {
      for (Index a = n.first; a < n.first + n.count; ++a) {
        const Aabb reach = boxes_[items_[a]].grown(distance);
        for (Index b = a + 1; b < n.first + n.count; ++b) {
          if (reach.meets(boxes_[items_[b]])) visit(items_[a], items_[b]);
        }
      }
      return;
    }
    if (depth < kParallelDepth) {
      tbb::parallel_invoke([&] { join_within(n.first, distance, visit, depth + 1); },
                           [&] { join_within(n.first + 1, distance, visit, depth + 1); },
                           [&] { join_between(n.first, n.first + 1, distance, visit, depth + 1); });
    } else {
      join_within(n.first, distance, visit, depth + 1);
      join_within(n.first + 1, distance, visit, depth + 1);
      join_between(n.first, n.first + 1, distance, visit, depth + 1);
    }
  }
  template <typename Visit>
  void join_between(Index p, Index q, double distance, const Visit& visit, int depth) const {
    const Node& a = nodes_[p];
    const Node& b = nodes_[q];
    if (!a.box.grown(distance).meets(b.box)) return;
    if (a.count > 0 && b.count > 0) {
      for (Index i = a.first; i < a.first + a.count; ++i) {
        const Aabb reach = boxes_[items_[i]].grown(distance);
        for (Index j = b.first; j < b.first + b.count; ++j) {
          if (reach.meets(boxes_[items_[j]])) visit(items_[i], items_[j]);
        }
      }
      return;
    }
    // Split the inner node (the larger box where both are).
    const auto size = [](const Aabb& box) { return (box.max - box.min).sum(); };
    const bool split_a = b.count > 0 || (a.count == 0 && size(a.box) >= size(b.box));
    const Index first = split_a ? a.first : b.first;
    const auto pair = [&](Index child) {
      if (split_a) {
        join_between(child, q, distance, visit, depth + 1);
      } else {
        join_between(p, child, distance, visit, depth + 1);
      }
    };
    if (depth < kParallelDepth) {
      tbb::parallel_invoke([&] { pair(first); }, [&] { pair(first + 1); });
    } else {
      pair(first);
      pair(first + 1);
    }
  }

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
