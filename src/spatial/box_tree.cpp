#include "spatial/box_tree.hpp"

#include <algorithm>
#include <numeric>

namespace tetcut::spatial {
namespace {

// Leaves hold a few boxes: testing four boxes costs less than descending two more levels.
constexpr Index kLeafSize = 4;

}  // namespace

BoxTree::BoxTree(std::vector<Aabb> boxes) : boxes_(std::move(boxes)) {
  items_.resize(boxes_.size());
  std::iota(items_.begin(), items_.end(), 0);
  std::vector<Vec3> centres(boxes_.size());
  for (std::size_t i = 0; i < boxes_.size(); ++i) centres[i] = 0.5 * (boxes_[i].min + boxes_[i].max);
  if (!boxes_.empty()) {
    nodes_.reserve(2 * boxes_.size() / kLeafSize + 2);
    nodes_.emplace_back();
    build(0, 0, static_cast<Index>(boxes_.size()), centres);
  }
}

void BoxTree::build(Index node, Index begin, Index end, const std::vector<Vec3>& centres) {
  Aabb box, centre_box;
  for (Index i = begin; i < end; ++i) {
    box.extend(boxes_[items_[i]]);
    centre_box.extend(centres[items_[i]]);
  }
  nodes_[node].box = box;
  if (end - begin <= kLeafSize) {
    nodes_[node].first = begin;
    nodes_[node].count = end - begin;
    return;
  }
  int axis = 0;
  const Vec3 extent = centre_box.max - centre_box.min;
  if (extent[1] > extent[axis]) axis = 1;
  if (extent[2] > extent[axis]) axis = 2;
  const Index middle = begin + (end - begin) / 2;
  std::nth_element(items_.begin() + begin, items_.begin() + middle, items_.begin() + end,
                   [&](Index a, Index b) { return centres[a][axis] < centres[b][axis]; });
  const Index children = static_cast<Index>(nodes_.size());
  nodes_[node].first = children;
  nodes_[node].count = 0;
  nodes_.emplace_back();
  nodes_.emplace_back();
  build(children, begin, middle, centres);
  build(children + 1, middle, end, centres);
}

void BoxTree::query(const Aabb& query, std::vector<Index>* out) const {
  if (nodes_.empty()) return;
  const std::size_t first_answer = out->size();
  Index stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!node.box.meets(query)) continue;
    if (node.count > 0) {
      for (Index i = node.first; i < node.first + node.count; ++i) {
        if (boxes_[items_[i]].meets(query)) out->push_back(items_[i]);
      }
    } else {
      stack[top++] = node.first;
      stack[top++] = node.first + 1;
    }
  }
  std::sort(out->begin() + static_cast<std::ptrdiff_t>(first_answer), out->end());
}

void BoxTree::refit(std::vector<Aabb> boxes) {
  boxes_ = std::move(boxes);
  refit();
}

void BoxTree::refit() {
  if (!nodes_.empty()) refit_node(0);
}

void BoxTree::refit_node(Index index) {
  Node& node = nodes_[index];
  Aabb box;
  if (node.count > 0) {
    for (Index i = node.first; i < node.first + node.count; ++i) box.extend(boxes_[items_[i]]);
  } else {
    refit_node(node.first);
    refit_node(node.first + 1);
    box.extend(nodes_[node.first].box);
    box.extend(nodes_[node.first + 1].box);
  }
  nodes_[index].box = box;
}

}  // namespace tetcut::spatial
