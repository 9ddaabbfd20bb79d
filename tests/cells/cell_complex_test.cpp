// The cell complex: components and volumes against analytic answers on one tet, and its invariants
// (validate() after every insertion, volumes adding up, independence of the triangle order) on
// multi-tet meshes, where facets on shared faces belong to two tets at once.

#include <gtest/gtest.h>

#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <random>
#include <string>

#include <tbb/task_arena.h>

#include "cells/cell_complex.hpp"
#include "components/material_components.hpp"

namespace tetcut::cells {
namespace {

// The corner tet x, y, z >= 0, x + y + z <= 1, volume 1/6.
const std::array<Vec3, 4> kCorner = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
constexpr double kTetVolume = 1.0 / 6.0;

TetMesh one_tet(const std::array<Vec3, 4>& corners = kCorner) {
  Points p(4, 3);
  for (int k = 0; k < 4; ++k) p.row(k) = corners[k].transpose();
  Tets t(1, 4);
  t << 0, 1, 2, 3;
  return TetMesh(p, t);
}

// A mesh with its registry and complex; not movable, as the complex points into both.
struct Complex {
  explicit Complex(TetMesh m) : mesh(std::move(m)), registry(mesh.rest()), complex(mesh, registry) {}
  TetMesh mesh;
  registry::IntersectionRegistry registry;
  CellComplex complex;
  std::int32_t next_id = 0;

  // Inserts every triangle with all tets as candidates; validates after each when asked.
  void insert(const std::vector<CutTriangle>& triangles, bool validate_each = false) {
    std::vector<Index> all(static_cast<std::size_t>(mesh.num_tets()));
    std::iota(all.begin(), all.end(), 0);
    std::vector<Index> touched;
    for (CutTriangle t : triangles) {
      t.id = next_id++;  // ids name the triangles for validate()
      complex.insert_triangle(t, all, &touched);
      if (validate_each) {
        ASSERT_EQ(complex.validate(), "");
      }
    }
    ASSERT_EQ(complex.validate(), "");
  }

  // Component volumes over all tets, largest first.
  std::vector<double> component_volumes() const {
    const components::MaterialComponents c = components::find_components(complex);
    std::vector<double> volumes;
    for (Index t = 0; t < mesh.num_tets(); ++t) {
      std::vector<double> v(static_cast<std::size_t>(c.count[t]), 0.0);
      if (!complex.refined(t)) {
        const auto& p = mesh.rest();
        const auto& tt = mesh.tets();
        v[0] = signed_volume(p.row(tt(t, 0)), p.row(tt(t, 1)), p.row(tt(t, 2)), p.row(tt(t, 3)));
      } else {
        for (CellId cell = complex.first_cell(t); cell >= 0; cell = complex.cells()[cell].next_in_tet) {
          v[c.cell_component[cell]] += c.cell_volume6[cell] / 6;
        }
      }
      volumes.insert(volumes.end(), v.begin(), v.end());
    }
    std::sort(volumes.rbegin(), volumes.rend());
    return volumes;
  }
};

CutTriangle tri(const Vec3& a, const Vec3& b, const Vec3& c, std::int32_t id = 0) { return {a, b, c, id}; }

// A triangle in the plane {x[axis] = value} large enough to cover the box [-1, 3]^3.
CutTriangle covering(int axis, double value) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  Vec3 a, b, c;
  a[axis] = b[axis] = c[axis] = value;
  a[u] = -5, a[v] = -5;
  b[u] = 10, b[v] = -5;
  c[u] = -5, c[v] = 10;
  return {a, b, c, 0};
}

std::vector<double> cut_one_tet(const std::vector<CutTriangle>& triangles) {
  Complex c(one_tet());
  c.insert(triangles, true);
  return c.component_volumes();
}

void expect_volumes(const std::vector<double>& actual, std::vector<double> expected) {
  std::sort(expected.rbegin(), expected.rend());
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(actual[i], expected[i], 1e-14) << "component " << i;
}

TEST(CellComplex, UncutTetIsOneComponentAndStaysUnrefined) {
  Complex c(one_tet());
  c.insert({tri(Vec3(2, 2, 2), Vec3(3, 2, 2), Vec3(2, 3, 2))});
  EXPECT_FALSE(c.complex.refined(0));
  expect_volumes(c.component_volumes(), {kTetVolume});
}

TEST(CellComplex, PlaneThroughTheMiddle) {
  const double top = 0.5 * 0.5 * 0.5 / 6;
  expect_volumes(cut_one_tet({covering(2, 0.5)}), {top, kTetVolume - top});
}

TEST(CellComplex, PartialCutLeavesOneComponent) {
  expect_volumes(cut_one_tet({tri(Vec3(0.1, 0.1, 0.25), Vec3(0.4, 0.1, 0.25), Vec3(0.1, 0.4, 0.25))}), {kTetVolume});
  // A cut entering through a face but not leaving the tet.
  expect_volumes(cut_one_tet({tri(Vec3(-1, 0.1, 0.2), Vec3(0.3, 0.1, 0.2), Vec3(-1, 0.3, 0.2))}), {kTetVolume});
}

TEST(CellComplex, TwoCrossingPlanesGiveFourPieces) {
  const double a = std::pow(0.6, 3) / 6, b = std::pow(0.8, 3) / 6 - a;
  expect_volumes(cut_one_tet({covering(0, 0.2), covering(1, 0.2)}), {a, b, b, kTetVolume - a - 2 * b});
}

TEST(CellComplex, TCutGivesThreePieces) {
  // Full cut x = 0.2, and a cut y = 0.2 only where x > 0.2 (it ends exactly on the first cut).
  const CutTriangle half = tri(Vec3(0.2, 0.2, -5), Vec3(10, 0.2, -5), Vec3(0.2, 0.2, 10));
  const double a = std::pow(0.6, 3) / 6, b = std::pow(0.8, 3) / 6 - a;
  expect_volumes(cut_one_tet({covering(0, 0.2), half}), {a, b, kTetVolume - a - b});
  // The same T-cut with the stem inserted first.
  expect_volumes(cut_one_tet({half, covering(0, 0.2)}), {a, b, kTetVolume - a - b});
}

std::vector<CutTriangle> octahedron(const Vec3& o, double r) {
  const Vec3 px = o + Vec3(r, 0, 0), nx = o - Vec3(r, 0, 0), py = o + Vec3(0, r, 0), ny = o - Vec3(0, r, 0),
             pz = o + Vec3(0, 0, r), nz = o - Vec3(0, 0, r);
  return {tri(px, py, pz), tri(py, nx, pz), tri(nx, ny, pz), tri(ny, px, pz),
          tri(py, px, nz), tri(nx, py, nz), tri(ny, nx, nz), tri(px, ny, nz)};
}

TEST(CellComplex, ClosedSurfaceInsideTheTetFloats) {
  const double r = 0.0625;
  const auto surface = octahedron(Vec3(0.2, 0.2, 0.2), r);
  const double inner = 4.0 / 3.0 * r * r * r;
  expect_volumes(cut_one_tet(surface), {inner, kTetVolume - inner});
  // With one face missing the surface is open and the material stays in one piece.
  expect_volumes(cut_one_tet({surface.begin(), surface.end() - 1}), {kTetVolume});
}

TEST(CellComplex, CutThroughAnEdgeAndAVertex) {
  // The plane x = y contains the tet's edge from (0,0,0) to (0,0,1) and halves the tet.
  expect_volumes(cut_one_tet({tri(Vec3(-1, -1, -1), Vec3(2, 2, -1), Vec3(0.5, 0.5, 5))}), {kTetVolume / 2, kTetVolume / 2});
  // A cut touching the tet only at its corner (1,0,0) changes nothing.
  expect_volumes(cut_one_tet({tri(Vec3(1, 0, 0), Vec3(2, 1, 0), Vec3(2, 0, 1))}), {kTetVolume});
  // A cut along the tet's face x = 0 changes nothing inside the tet.
  expect_volumes(cut_one_tet({covering(0, 0.0)}), {kTetVolume});
}

TEST(CellComplex, RepeatedAndOverlappingCoplanarCuts) {
  const double top = 0.5 * 0.5 * 0.5 / 6;
  const CutTriangle full = covering(2, 0.5);
  expect_volumes(cut_one_tet({full, full, full}), {top, kTetVolume - top});
  // Two coplanar triangles that only together cover the tet's section at z = 0.5.
  const CutTriangle left = tri(Vec3(-1, -1, 0.5), Vec3(3, -1, 0.5), Vec3(-1, 3, 0.5));
  const CutTriangle right = tri(Vec3(3, 3, 0.5), Vec3(-1, 3, 0.5), Vec3(3, -1, 0.5));
  expect_volumes(cut_one_tet({tri(Vec3(-1, -1, 0.5), Vec3(0.3, -1, 0.5), Vec3(-1, 2, 0.5)), right}), {kTetVolume});
  expect_volumes(cut_one_tet({left, right}), {top, kTetVolume - top});
}

// Regression: a thin horizontal triangle pointing at the tet from beside it. Each of its walls has
// part of the tet on its inner side, but the part inside the first wall lies outside the third;
// an early version split that part by the triangle's plane anyway and covered a facet outside the
// triangle, making a second component.
TEST(CellComplex, ATriangleBesideTheTetCutsNothing) {
  expect_volumes(cut_one_tet({tri(Vec3(-0.05, 0.3, 0.2), Vec3(-1, 0.25, 0.2), Vec3(-1, 0.35, 0.2))}), {kTetVolume});
}

TEST(CellComplex, CutEndingExactlyOnTheTetFaces) {
  // A triangle whose corners lie on the tet's edges: it cuts off the corner at the origin exactly.
  const double s = 0.25;
  expect_volumes(cut_one_tet({tri(Vec3(s, 0, 0), Vec3(0, s, 0), Vec3(0, 0, s))}),
                 {kTetVolume - s * s * s / 6, s * s * s / 6});
}

TEST(CellComplex, CoveringIsCountedOncePerTriangleWithItsOrientation) {
  // The same plane from both sides and twice: the winding jump across the facet adds up.
  Complex c(one_tet());
  const CutTriangle up = covering(2, 0.5);
  const CutTriangle down{up.a, up.c, up.b, 1};
  c.insert({up, up, down, up});
  int covered = 0;
  for (const Facet& f : c.complex.facets()) {
    if (!f.covered()) continue;
    ++covered;
    const int sign = geometry::normal_component_sign(c.registry.plane(f.plane), 2);
    EXPECT_EQ(f.winding * sign, 2);
    EXPECT_EQ(c.complex.cut_id(f), 0);  // the first triangle that covered it
  }
  EXPECT_EQ(covered, 1);
}

// A cut along an interior face of a mesh separates the two tets that share it.
TEST(CellComplex, CutAlongASharedFaceCoversItForBothTets) {
  // Two tets sharing the face z = 0 triangle (0,0,0), (1,0,0), (0,1,0).
  Points p(5, 3);
  p << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1;
  Tets t(2, 4);
  t << 0, 1, 2, 3, 0, 2, 1, 4;
  Complex c(TetMesh(p, t));
  c.insert({covering(2, 0.0)});
  int covered = 0;
  for (const Facet& f : c.complex.facets()) {
    if (!f.covered()) continue;
    ++covered;
    EXPECT_TRUE(is_cell(f.front) && is_cell(f.back));
    EXPECT_NE(c.complex.cells()[f.front].tet, c.complex.cells()[f.back].tet);
    EXPECT_GE(f.mesh_face, 0);
  }
  EXPECT_GE(covered, 1);
}

struct Soup {
  std::vector<CutTriangle> triangles;
};

Soup random_soup(std::mt19937_64& rng, int count, double lo, double hi) {
  std::uniform_real_distribution<double> coord(lo, hi);
  Soup soup;
  const auto point = [&] { return Vec3(coord(rng), coord(rng), coord(rng)); };
  for (int i = 0; i < count; ++i) soup.triangles.push_back({point(), point(), point(), i});
  // Degenerate extras: a repeat, and a triangle sharing a corner and an edge with another.
  soup.triangles.push_back(soup.triangles[0]);
  soup.triangles.push_back({soup.triangles[1].a, soup.triangles[1].b, point(), count + 1});
  return soup;
}

double total(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

// Random soups in one tet: piece volumes add up to the tet volume and do not depend on order.
class RandomSoupInOneTet : public ::testing::TestWithParam<int> {};

TEST_P(RandomSoupInOneTet, VolumeIsConservedAndOrderDoesNotMatter) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(GetParam()));
  Soup soup = random_soup(rng, 3 + GetParam() % 6, -0.3, 1.0);
  Complex first(one_tet());
  first.insert(soup.triangles, true);
  const std::vector<double> volumes = first.component_volumes();
  for (const double v : volumes) EXPECT_GT(v, 0);
  EXPECT_NEAR(total(volumes), kTetVolume, 1e-12 * kTetVolume);
  std::shuffle(soup.triangles.begin(), soup.triangles.end(), rng);
  Complex second(one_tet());
  second.insert(soup.triangles);
  const std::vector<double> shuffled = second.component_volumes();
  ASSERT_EQ(shuffled.size(), volumes.size());
  for (std::size_t i = 0; i < volumes.size(); ++i) EXPECT_NEAR(shuffled[i], volumes[i], 1e-13);
}

INSTANTIATE_TEST_SUITE_P(Seeds, RandomSoupInOneTet, ::testing::Range(1, 101));

// Random soups across a 2x2x2 grid of 5-tet cubes: the complex stays valid across shared faces,
// edges and vertices, and the tets' components add up to the box.
class RandomSoupInAGrid : public ::testing::TestWithParam<int> {};

TEST_P(RandomSoupInAGrid, ComplexStaysValidAndVolumeIsConserved) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(1000 + GetParam()));
  Soup soup = random_soup(rng, 2 + GetParam() % 4, -0.2, 1.2);
  // Triangles through grid nodes and along grid faces, the degenerate cases of a structured mesh.
  soup.triangles.push_back(tri(Vec3(0.5, 0.5, 0.5), Vec3(1, 0, 0.5), Vec3(0, 1, 0.25), 100));
  soup.triangles.push_back(tri(Vec3(0.5, -1, -1), Vec3(0.5, 3, -1), Vec3(0.5, 0.75, 0.9), 101));
  Complex c(make_grid(Box{}, {2, 2, 2}, 5));
  c.insert(soup.triangles, true);
  const std::vector<double> volumes = c.component_volumes();
  for (const double v : volumes) EXPECT_GT(v, 0);
  EXPECT_NEAR(total(volumes), 1.0, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Seeds, RandomSoupInAGrid, ::testing::Range(1, 41));

// The paper's Figure 2: one tet sliced by 50 random triangles, many of which only partly enter it.
TEST(CellComplex, Figure2FiftyRandomTriangles) {
  const TriangleSurface soup = figures::figure2_triangles();
  std::vector<CutTriangle> triangles;
  for (Index i = 0; i < soup.num_triangles(); ++i) {
    triangles.push_back({soup.vertices.row(soup.triangles(i, 0)), soup.vertices.row(soup.triangles(i, 1)),
                         soup.vertices.row(soup.triangles(i, 2)), i});
  }
  Complex c(figures::figure2_tet());
  c.insert(triangles);
  const std::vector<double> volumes = c.component_volumes();
  EXPECT_NEAR(total(volumes), kTetVolume, 1e-12 * kTetVolume);
  EXPECT_GT(volumes.size(), 1000u);
}

// A slab one ulp thick: its rounded volume is far below the rounding of its corners, so the
// volume comes from exact points, and must be the slab's (thickness times the section's area).
TEST(CellComplex, CellThinnerThanRoundingHasItsExactVolume) {
  const double z = 0.5, thickness = std::nextafter(z, 1.0) - z;
  Complex c(one_tet());
  c.insert({covering(2, z), covering(2, z + thickness)});
  std::vector<double> volumes;
  for (CellId cell = c.complex.first_cell(0); cell >= 0; cell = c.complex.cells()[cell].next_in_tet) {
    const double rounded = c.complex.cell_volume6(cell, Vec3::Zero()) / 6;
    const double exact = c.complex.exact_cell_volume6(cell) / 6;
    EXPECT_NEAR(rounded, exact, 1e-15) << "cell " << cell;
    volumes.push_back(exact);
  }
  ASSERT_EQ(volumes.size(), 3u);
  std::sort(volumes.begin(), volumes.end());
  // The section at height z of the corner tet is a right triangle with legs 1 - z.
  EXPECT_NEAR(volumes[0], thickness * (1 - z) * (1 - z) / 2, 1e-6 * thickness);
  EXPECT_NEAR(volumes[0] + volumes[1] + volumes[2], kTetVolume, 1e-15);
}

// ---- Parallel insertion ------------------------------------------------------------------------

// A bar of 40 x 2 x 2 five-tet cubes, long enough for several blocks of one colour to run at once.
TetMesh long_bar() { return make_grid(Box{Vec3::Zero(), Vec3(4, 0.2, 0.2)}, {40, 2, 2}, 5); }

// Small random triangles all along the bar, with the degenerate cases of a structured mesh: cuts
// along grid planes (facets on faces shared by two tets, which only one of them may cover; the
// planes x = 0.7, 1.4, ... separate blocks of the parallel insertion, so the two tets insert at
// different times), planes a rounding error off the grid, cuts through grid nodes and along grid
// edges, repeated and overlapping coplanar cuts, and closed spheres.
std::vector<CutTriangle> bar_soup(const TetMesh& bar) {
  std::vector<double> grid_x(bar.rest().col(0).begin(), bar.rest().col(0).end());
  std::sort(grid_x.begin(), grid_x.end());
  grid_x.erase(std::unique(grid_x.begin(), grid_x.end()), grid_x.end());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> along(-0.1, 4.1), across(-0.1, 0.3), near(-0.15, 0.15);
  std::vector<CutTriangle> soup;
  for (int i = 0; i < 300; ++i) {
    const Vec3 centre(along(rng), across(rng), across(rng));
    const auto corner = [&] { return Vec3(centre + Vec3(near(rng), near(rng), near(rng))); };
    soup.push_back(tri(corner(), corner(), corner()));
  }
  for (int k = 3; k < 40; k += 4) {
    for (const double x : {grid_x[static_cast<std::size_t>(k) / 4 * 7 % 40], 0.1 * k}) {
      soup.push_back(tri(Vec3(x, -1, -1), Vec3(x, 2, -1), Vec3(x, 0.1, 0.15)));             // a plane
      soup.push_back(tri(Vec3(x, 0.1, 0.1), Vec3(x + 0.1, 0, 0), Vec3(x - 0.1, 0.2, 0.05)));  // through a node
      soup.push_back(tri(Vec3(x, 0, 0), Vec3(x + 0.1, 0.1, 0.1), Vec3(x, 0.2, 0)));          // along grid edges
      soup.push_back(soup[soup.size() - 3]);                                                 // a repeat
      soup.push_back(tri(Vec3(x, 0.05, 0.05), Vec3(x, 0.3, 0.05), Vec3(x, 0.05, 0.3)));      // overlapping it
    }
  }
  for (const double x : {0.55, 2.05, 3.3}) {
    const TriangleSurface sphere = figures::icosphere(Vec3(x, 0.1, 0.1), 0.07, 2);
    for (Index t = 0; t < sphere.num_triangles(); ++t) {
      soup.push_back(tri(sphere.vertices.row(sphere.triangles(t, 0)), sphere.vertices.row(sphere.triangles(t, 1)),
                         sphere.vertices.row(sphere.triangles(t, 2))));
    }
  }
  for (std::size_t i = 0; i < soup.size(); ++i) soup[i].id = static_cast<std::int32_t>(i);
  return soup;
}

// Each triangle's candidate tets: those whose boxes meet its box.
std::vector<std::vector<Index>> candidates(const TetMesh& mesh, const std::vector<CutTriangle>& soup) {
  std::vector<std::vector<Index>> out(soup.size());
  for (std::size_t i = 0; i < soup.size(); ++i) {
    const Vec3 lo = soup[i].a.cwiseMin(soup[i].b).cwiseMin(soup[i].c), hi = soup[i].a.cwiseMax(soup[i].b).cwiseMax(soup[i].c);
    for (Index t = 0; t < mesh.num_tets(); ++t) {
      Vec3 tlo = Vec3::Constant(1e300), thi = Vec3::Constant(-1e300);
      for (int k = 0; k < 4; ++k) {
        tlo = tlo.cwiseMin(mesh.rest().row(mesh.tets()(t, k)).transpose());
        thi = thi.cwiseMax(mesh.rest().row(mesh.tets()(t, k)).transpose());
      }
      if ((tlo.array() <= hi.array()).all() && (lo.array() <= thi.array()).all()) out[i].push_back(t);
    }
  }
  return out;
}

// Inserts the soup in parallel on `threads` threads.
void insert_in_parallel(Complex* c, const std::vector<CutTriangle>& soup, int threads) {
  std::vector<PreparedTriangle> prepared;
  for (const CutTriangle& t : soup) prepared.push_back(c->complex.prepare(t));
  const std::vector<std::vector<Index>> tets = candidates(c->mesh, soup);
  std::vector<Index> touched;
  tbb::task_arena arena(threads);
  arena.execute([&] { c->complex.insert_triangles(prepared, tets, &touched); });
}

// Per tet, in order: its cells in order, each with its facets in order (covering, winding and
// corner positions, rounded), and the number of cells and covered facets.
std::string describe(const CellComplex& complex) {
  std::string out;
  for (Index t = 0; t < complex.mesh().num_tets(); ++t) {
    out.append("tet ").append(std::to_string(t)).append("\n");
    for (CellId c = complex.first_cell(t); c >= 0; c = complex.cells()[c].next_in_tet) {
      out.append(" cell\n");
      for (const FacetId f : complex.cells()[c].facets) {
        const Facet& facet = complex.facets()[f];
        out.append("  ").append(facet.covered() ? "covered " : "open ").append(std::to_string(facet.winding));
        for (const Corner& corner : facet.corners) {
          const Vec3& x = complex.registry().position(corner.vertex);
          out.append(" (").append(std::to_string(x[0])).append(",").append(std::to_string(x[1])).append(",");
          out.append(std::to_string(x[2])).append(")");
        }
        out.append("\n");
      }
    }
  }
  return out;
}

// What the parallel insertion must keep from the sequential one, tet by tet: the cells (their count
// and volumes) and the components (count and volumes), and overall the covered area with winding.
struct TetSummary {
  std::size_t cells = 0;
  std::vector<double> cell_volumes, component_volumes;
};
std::vector<TetSummary> summarise(const Complex& c) {
  const components::MaterialComponents comp = components::find_components(c.complex);
  std::vector<TetSummary> out(static_cast<std::size_t>(c.mesh.num_tets()));
  for (Index t = 0; t < c.mesh.num_tets(); ++t) {
    TetSummary& s = out[t];
    s.component_volumes.assign(static_cast<std::size_t>(comp.count[t]), 0.0);
    for (CellId cell = c.complex.first_cell(t); cell >= 0; cell = c.complex.cells()[cell].next_in_tet) {
      ++s.cells;
      s.cell_volumes.push_back(comp.cell_volume6[cell] / 6);
      s.component_volumes[comp.cell_component[cell]] += comp.cell_volume6[cell] / 6;
    }
    std::sort(s.cell_volumes.begin(), s.cell_volumes.end());
    std::sort(s.component_volumes.begin(), s.component_volumes.end());
  }
  return out;
}

// Sum over covered facets of winding times area: what the winding flood of an embedding sees.
double covered_winding_area(const CellComplex& complex) {
  double sum = 0;
  for (const Facet& f : complex.facets()) {
    if (!f.covered()) continue;
    const Vec3 a = complex.registry().position(f.corners[0].vertex);
    Vec3 normal = Vec3::Zero();
    for (std::size_t i = 1; i + 1 < f.corners.size(); ++i) {
      normal += (complex.registry().position(f.corners[i].vertex) - a).cross(complex.registry().position(f.corners[i + 1].vertex) - a);
    }
    sum += f.winding * normal.norm() / 2;
  }
  return sum;
}

TEST(CellComplexParallel, SameCellsAndComponentsAsInsertingInOrder) {
  const std::vector<CutTriangle> soup = bar_soup(long_bar());
  Complex sequential(long_bar());
  sequential.insert(soup);
  Complex parallel(long_bar());
  insert_in_parallel(&parallel, soup, 2);
  ASSERT_EQ(parallel.complex.validate(), "");

  const std::vector<TetSummary> a = summarise(sequential), b = summarise(parallel);
  std::size_t refined = 0, split = 0;
  for (Index t = 0; t < sequential.mesh.num_tets(); ++t) {
    ASSERT_EQ(sequential.complex.refined(t), parallel.complex.refined(t)) << "tet " << t;
    ASSERT_EQ(a[t].cells, b[t].cells) << "tet " << t;
    ASSERT_EQ(a[t].component_volumes.size(), b[t].component_volumes.size()) << "tet " << t;
    for (std::size_t i = 0; i < a[t].cells; ++i) EXPECT_NEAR(a[t].cell_volumes[i], b[t].cell_volumes[i], 1e-15) << "tet " << t;
    for (std::size_t i = 0; i < a[t].component_volumes.size(); ++i) {
      EXPECT_NEAR(a[t].component_volumes[i], b[t].component_volumes[i], 1e-15) << "tet " << t;
    }
    refined += sequential.complex.refined(t) ? 1 : 0;
    split += a[t].component_volumes.size() > 1 ? 1 : 0;
  }
  // The soup reaches all along the bar and really separates material.
  EXPECT_GT(refined, 500u);
  EXPECT_GT(split, 100u);
  EXPECT_EQ(sequential.complex.cells().size(), parallel.complex.cells().size());
  // Facets may differ in number: a facet on a shared face is split by a triangle's edges only
  // where it is still inside the triangle, and which pieces exist then depends on the order in
  // which the two tets insert. What they cover, with its winding, does not.
  EXPECT_NEAR(covered_winding_area(sequential.complex), covered_winding_area(parallel.complex), 1e-12);
}

TEST(CellComplexParallel, ResultDoesNotDependOnTheThreads) {
  const std::vector<CutTriangle> soup = bar_soup(long_bar());
  Complex one(long_bar()), two(long_bar()), again(long_bar());
  insert_in_parallel(&one, soup, 1);
  insert_in_parallel(&two, soup, 2);
  insert_in_parallel(&again, soup, 2);
  const std::string expected = describe(one.complex);
  EXPECT_EQ(describe(two.complex), expected);
  EXPECT_EQ(describe(again.complex), expected);
}

}  // namespace
}  // namespace tetcut::cells
