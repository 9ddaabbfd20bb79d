// One tet cut by triangles: components and volumes against analytic answers, and invariants
// (volumes add up, results independent of triangle order) on random and degenerate soups.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "cells/cell_complex.hpp"

namespace tetcut::cells {
namespace {

// The corner tet x, y, z >= 0, x + y + z <= 1, volume 1/6.
const std::array<Vec3, 4> kCorner = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
constexpr double kTetVolume = 1.0 / 6.0;

struct Tri {
  Vec3 a, b, c;
};

// A triangle in the plane {x[axis] = value} large enough to cover the unit box.
Tri covering(int axis, double value) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  Vec3 a, b, c;
  a[axis] = b[axis] = c[axis] = value;
  a[u] = -5, a[v] = -5;
  b[u] = 10, b[v] = -5;
  c[u] = -5, c[v] = 10;
  return {a, b, c};
}

// Component volumes, largest first.
std::vector<double> component_volumes(const CellComplex& complex) {
  std::int32_t count = 0;
  const auto component = complex.components(&count);
  std::vector<double> volumes(static_cast<std::size_t>(count), 0.0);
  for (CellId c = 0; c < static_cast<CellId>(complex.cells().size()); ++c) volumes[component[c]] += complex.cell_volume(c);
  std::sort(volumes.rbegin(), volumes.rend());
  return volumes;
}

std::vector<double> cut(const std::vector<Tri>& triangles, const std::array<Vec3, 4>& tet = kCorner) {
  CellComplex complex(tet);
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    complex.insert_triangle(triangles[i].a, triangles[i].b, triangles[i].c, static_cast<std::int32_t>(i));
  }
  EXPECT_EQ(complex.validate(), "");
  return component_volumes(complex);
}

void expect_volumes(const std::vector<double>& actual, std::vector<double> expected) {
  std::sort(expected.rbegin(), expected.rend());
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(actual[i], expected[i], 1e-14) << "component " << i;
}

TEST(CellComplex, UncutTetIsOneComponent) { expect_volumes(cut({}), {kTetVolume}); }

TEST(CellComplex, PlaneThroughTheMiddle) {
  const double top = 0.5 * 0.5 * 0.5 / 6;
  expect_volumes(cut({covering(2, 0.5)}), {top, kTetVolume - top});
}

TEST(CellComplex, PartialCutLeavesOneComponent) {
  expect_volumes(cut({{Vec3(0.1, 0.1, 0.25), Vec3(0.4, 0.1, 0.25), Vec3(0.1, 0.4, 0.25)}}), {kTetVolume});
  // A cut entering through a face but not leaving the tet.
  expect_volumes(cut({{Vec3(-1, 0.1, 0.2), Vec3(0.3, 0.1, 0.2), Vec3(-1, 0.3, 0.2)}}), {kTetVolume});
}

TEST(CellComplex, TwoCrossingPlanesGiveFourPieces) {
  const double a = std::pow(0.6, 3) / 6, b = std::pow(0.8, 3) / 6 - a;
  expect_volumes(cut({covering(0, 0.2), covering(1, 0.2)}), {a, b, b, kTetVolume - a - 2 * b});
}

TEST(CellComplex, TCutGivesThreePieces) {
  // Full cut x = 0.2, and a cut y = 0.2 only where x > 0.2 (it ends exactly on the first cut).
  const Tri half{Vec3(0.2, 0.2, -5), Vec3(10, 0.2, -5), Vec3(0.2, 0.2, 10)};
  const double a = std::pow(0.6, 3) / 6, b = std::pow(0.8, 3) / 6 - a;
  expect_volumes(cut({covering(0, 0.2), half}), {a, b, kTetVolume - a - b});
  // The same T-cut with the stem inserted first.
  expect_volumes(cut({half, covering(0, 0.2)}), {a, b, kTetVolume - a - b});
}

TEST(CellComplex, ClosedSurfaceInsideTheTetFloats) {
  // An octahedron of radius r around (0.2, 0.2, 0.2), wholly inside the tet.
  const Vec3 o(0.2, 0.2, 0.2);
  const double r = 0.0625;
  const Vec3 px = o + Vec3(r, 0, 0), nx = o - Vec3(r, 0, 0), py = o + Vec3(0, r, 0), ny = o - Vec3(0, r, 0),
             pz = o + Vec3(0, 0, r), nz = o - Vec3(0, 0, r);
  const std::vector<Tri> octahedron = {{px, py, pz}, {py, nx, pz}, {nx, ny, pz}, {ny, px, pz},
                                       {py, px, nz}, {nx, py, nz}, {ny, nx, nz}, {px, ny, nz}};
  const double inner = 4.0 / 3.0 * r * r * r;
  expect_volumes(cut(octahedron), {inner, kTetVolume - inner});
  // With one face missing the surface is open and the material stays in one piece.
  expect_volumes(cut({octahedron.begin(), octahedron.end() - 1}), {kTetVolume});
}

TEST(CellComplex, CutThroughAnEdgeAndAVertex) {
  // The plane x = y contains the tet's edge from (0,0,0) to (0,0,1) and halves the tet.
  const Tri diagonal{Vec3(-1, -1, -1), Vec3(2, 2, -1), Vec3(0.5, 0.5, 5)};
  expect_volumes(cut({diagonal}), {kTetVolume / 2, kTetVolume / 2});
  // A cut touching the tet only at its corner (1,0,0) changes nothing.
  expect_volumes(cut({{Vec3(1, 0, 0), Vec3(2, 1, 0), Vec3(2, 0, 1)}}), {kTetVolume});
  // A cut along the tet's face x = 0 changes nothing inside the tet.
  expect_volumes(cut({covering(0, 0.0)}), {kTetVolume});
}

TEST(CellComplex, RepeatedAndOverlappingCoplanarCuts) {
  const double top = 0.5 * 0.5 * 0.5 / 6;
  const Tri full = covering(2, 0.5);
  expect_volumes(cut({full, full, full}), {top, kTetVolume - top});
  // Two coplanar triangles that only together cover the tet's section at z = 0.5.
  const Tri left{Vec3(-1, -1, 0.5), Vec3(3, -1, 0.5), Vec3(-1, 3, 0.5)};
  const Tri right{Vec3(3, 3, 0.5), Vec3(-1, 3, 0.5), Vec3(3, -1, 0.5)};
  expect_volumes(cut({{Vec3(-1, -1, 0.5), Vec3(0.3, -1, 0.5), Vec3(-1, 2, 0.5)}, right}), {kTetVolume});
  expect_volumes(cut({left, right}), {top, kTetVolume - top});
}

TEST(CellComplex, CutEndingExactlyOnTheTetFaces) {
  // A triangle whose corners lie on the tet's edges: it cuts off the corner at the origin exactly.
  const double s = 0.25;
  expect_volumes(cut({{Vec3(s, 0, 0), Vec3(0, s, 0), Vec3(0, 0, s)}}), {kTetVolume - s * s * s / 6, s * s * s / 6});
}

// Random soups: piece volumes add up to the tet volume and do not depend on triangle order.
class RandomSoup : public ::testing::TestWithParam<int> {};

TEST_P(RandomSoup, VolumeIsConservedAndOrderDoesNotMatter) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(GetParam()));
  std::uniform_real_distribution<double> coord(-0.3, 1.0);
  const int count = 3 + GetParam() % 6;
  std::vector<Tri> soup;
  for (int i = 0; i < count; ++i) {
    soup.push_back({Vec3(coord(rng), coord(rng), coord(rng)), Vec3(coord(rng), coord(rng), coord(rng)),
                    Vec3(coord(rng), coord(rng), coord(rng))});
  }
  // Degenerate extras: a repeat, and a triangle sharing a corner and an edge with another.
  soup.push_back(soup[0]);
  soup.push_back({soup[1].a, soup[1].b, Vec3(coord(rng), coord(rng), coord(rng))});
  const std::vector<double> volumes = cut(soup);
  double total = 0;
  for (const double v : volumes) {
    EXPECT_GT(v, 0);
    total += v;
  }
  EXPECT_NEAR(total, kTetVolume, 1e-12 * kTetVolume);
  std::shuffle(soup.begin(), soup.end(), rng);
  const std::vector<double> shuffled = cut(soup);
  ASSERT_EQ(shuffled.size(), volumes.size());
  for (std::size_t i = 0; i < volumes.size(); ++i) EXPECT_NEAR(shuffled[i], volumes[i], 1e-13);
}

INSTANTIATE_TEST_SUITE_P(Seeds, RandomSoup, ::testing::Range(1, 201));

// The paper's Figure 2: one tet sliced by 50 random triangles, many of which only partly enter it.
TEST(CellComplex, Figure2FiftyRandomTriangles) {
  // Each triangle lies in a random plane through a random point of the tet, around that point, with
  // a random size: large ones slice through, small ones end inside.
  std::mt19937_64 rng(2007);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> gauss;
  std::vector<Tri> soup;
  for (int i = 0; i < 50; ++i) {
    double w[4];
    double sum = 0;
    for (double& x : w) sum += x = -std::log(unit(rng));
    Vec3 centre = Vec3::Zero();
    for (int k = 0; k < 4; ++k) centre += w[k] / sum * kCorner[k];
    const Vec3 normal = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const Vec3 u = normal.unitOrthogonal(), v = normal.cross(u);
    const double radius = 0.2 + 1.3 * unit(rng);
    const double turn = 2 * M_PI * unit(rng);
    Vec3 corners[3];
    for (int k = 0; k < 3; ++k) {
      const double angle = turn + 2 * M_PI * k / 3;
      corners[k] = centre + radius * (std::cos(angle) * u + std::sin(angle) * v);
    }
    soup.push_back({corners[0], corners[1], corners[2]});
  }
  const std::vector<double> volumes = cut(soup);
  double total = 0;
  for (const double v : volumes) total += v;
  EXPECT_NEAR(total, kTetVolume, 1e-12 * kTetVolume);
  EXPECT_GT(volumes.size(), 1000u);
  std::printf("Figure 2: %zu pieces\n", volumes.size());
}

}  // namespace
}  // namespace tetcut::cells
