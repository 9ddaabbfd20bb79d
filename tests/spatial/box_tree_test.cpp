// The box hierarchy: queries and the self-join against brute force on random boxes.

#include "spatial/box_tree.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <random>
#include <vector>

namespace tetcut::spatial {
namespace {

std::vector<Aabb> random_boxes(int count, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> where(0, 1), size(0, 0.05);
  std::vector<Aabb> boxes(static_cast<std::size_t>(count));
  for (Aabb& box : boxes) {
    const Vec3 corner(where(random), where(random), where(random));
    box.extend(corner);
    box.extend(Vec3(corner + Vec3(size(random), size(random), size(random))));
  }
  return boxes;
}

// The gap between two boxes: 0 where they meet, else the distance of their nearest points, which
// no two points of them beat (sampled).
TEST(Aabb, GapIsTheDistanceOfTheNearestPoints) {
  Aabb unit;
  unit.extend(Vec3(0, 0, 0));
  unit.extend(Vec3(1, 1, 1));
  Aabb beside;
  beside.extend(Vec3(3, 0.5, 0.5));
  beside.extend(Vec3(4, 2, 2));
  EXPECT_DOUBLE_EQ(unit.gap(beside), 2);
  EXPECT_DOUBLE_EQ(beside.gap(unit), 2);
  Aabb corner;
  corner.extend(Vec3(2, 3, 1.5));
  EXPECT_DOUBLE_EQ(unit.gap(corner), std::sqrt(1 + 4 + 0.25));
  EXPECT_EQ(unit.gap(unit.grown(-0.25)), 0);  // inside
  const std::vector<Aabb> boxes = random_boxes(40, 7);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> share(0, 1);
  for (const Aabb& a : boxes) {
    for (const Aabb& b : boxes) {
      const double gap = a.gap(b);
      EXPECT_EQ(gap == 0, a.meets(b));
      for (int k = 0; k < 20; ++k) {
        const Vec3 p = a.min + (a.max - a.min).cwiseProduct(Vec3(share(random), share(random), share(random)));
        const Vec3 q = b.min + (b.max - b.min).cwiseProduct(Vec3(share(random), share(random), share(random)));
        EXPECT_GE((p - q).norm(), gap * (1 - 1e-12));
      }
    }
  }
}

TEST(BoxTree, QueryFindsEveryBoxThatMeetsInOrder) {
  const std::vector<Aabb> boxes = random_boxes(500, 1);
  const BoxTree tree(boxes);
  for (std::size_t q = 0; q < 50; ++q) {
    const Aabb query = boxes[q].grown(0.02);
    std::vector<Index> found, expected;
    tree.query(query, &found);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (query.meets(boxes[i])) expected.push_back(static_cast<Index>(i));
    }
    EXPECT_EQ(found, expected);
  }
}

// Every pair within the distance, each once, as a query per box finds them; also after the boxes
// moved and the hierarchy was refitted, and with a box touching another at one face.
TEST(BoxTree, SelfJoinFindsEveryPairWithinTheDistanceOnce) {
  std::vector<Aabb> boxes = random_boxes(2000, 2);
  boxes[1] = boxes[0];
  boxes[1].min.x() = boxes[0].max.x() + 0.01;  // exactly the distance apart along x
  boxes[1].max.x() = boxes[1].min.x() + 0.01;
  BoxTree tree(boxes);
  for (int round = 0; round < 2; ++round) {
    if (round == 1) {
      boxes = random_boxes(2000, 3);
      tree.refit(boxes);
    }
    for (const double distance : {0.0, 0.01, 0.05}) {
      std::vector<std::array<Index, 2>> joined, expected;
      std::mutex lock;
      tree.self_join(distance, [&](Index i, Index j) {
        const std::lock_guard<std::mutex> hold(lock);
        joined.push_back({std::min(i, j), std::max(i, j)});
      });
      std::sort(joined.begin(), joined.end());
      for (std::size_t i = 0; i < boxes.size(); ++i) {
        std::vector<Index> hits;
        tree.query(boxes[i].grown(distance), &hits);
        for (const Index j : hits) {
          if (j > static_cast<Index>(i)) expected.push_back({static_cast<Index>(i), j});
        }
      }
      EXPECT_EQ(joined, expected) << "round " << round << ", distance " << distance;
      EXPECT_GT(expected.size(), 200u);  // enough pairs to cross many nodes
      if (round == 0 && distance > 0) {
        EXPECT_TRUE(std::binary_search(joined.begin(), joined.end(), std::array<Index, 2>{0, 1}));
      }
    }
  }
}

}  // namespace
}  // namespace tetcut::spatial
