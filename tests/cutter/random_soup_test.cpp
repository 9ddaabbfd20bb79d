// Property tests on thousands of seeded random soups, mixing generic triangles with the degenerate
// kinds a structured mesh invites: corners on grid nodes, triangles on grid planes, corners lying
// exactly on other triangles, repeats, reversed copies and zero-area triangles. Each result must
// pass the shared invariants and must not depend on the order of the triangles or of their corners.

#include <gtest/gtest.h>

#include <tetcut/cutter.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/quality.hpp>

#include <algorithm>
#include <random>

#include "support/cut_invariants.hpp"

namespace tetcut {
namespace {

using testing::Triangle;

class SoupMaker {
 public:
  explicit SoupMaker(std::uint64_t seed) : rng_(seed) {}

  std::vector<Triangle> make() {
    std::vector<Triangle> soup;
    const int count = 2 + static_cast<int>(rng_() % 6);
    for (int i = 0; i < count; ++i) soup.push_back(next(soup));
    return soup;
  }

  // The same triangles in another order, each with its corners rotated (orientation kept, so
  // windings agree; the cutter does not care, but the surface areas must match exactly).
  std::vector<Triangle> shuffled(std::vector<Triangle> soup) {
    std::shuffle(soup.begin(), soup.end(), rng_);
    for (Triangle& t : soup) std::rotate(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(rng_() % 3), t.end());
    return soup;
  }

 private:
  double coordinate() { return std::uniform_real_distribution<double>(-0.3, 1.3)(rng_); }
  // A value of the 2x2x2 grid's node planes, or just outside the unit cube.
  double grid_value() {
    static constexpr double kValues[] = {-0.5, 0, 0.5, 1, 1.5};
    return kValues[rng_() % 5];
  }
  Vec3 point() { return {coordinate(), coordinate(), coordinate()}; }

  Triangle next(const std::vector<Triangle>& soup) {
    switch (rng_() % 8) {
      case 0: {  // corners on grid nodes
        return {Vec3(grid_value(), grid_value(), grid_value()), Vec3(grid_value(), grid_value(), grid_value()),
                Vec3(grid_value(), grid_value(), grid_value())};
      }
      case 1: {  // in a grid plane (along mesh faces), or an axis plane between grid planes
        const int axis = static_cast<int>(rng_() % 3);
        const double value = rng_() % 2 ? grid_value() : coordinate();
        Triangle t = {point(), point(), point()};
        for (Vec3& p : t) p[axis] = value;
        return t;
      }
      case 2:  // a repeat, reversed
        if (!soup.empty()) {
          const Triangle& t = soup[rng_() % soup.size()];
          return {t[0], t[2], t[1]};
        }
        return {point(), point(), point()};
      case 3:  // sharing an edge with another
        if (!soup.empty()) {
          const Triangle& t = soup[rng_() % soup.size()];
          return {t[0], t[1], point()};
        }
        return {point(), point(), point()};
      case 4: {  // a large axis-parallel triangle, which later corners may lie on (case 5)
        const int axis = static_cast<int>(rng_() % 3);
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        Triangle host;
        host[0][axis] = host[1][axis] = host[2][axis] = coordinate();
        host[0][u] = -1, host[0][v] = -1;
        host[1][u] = 3, host[1][v] = -1;
        host[2][u] = -1, host[2][v] = 3;
        return host;
      }
      case 5: {  // one corner exactly on the plane of an earlier axis-parallel triangle
        for (const Triangle& t : soup) {
          for (int axis = 0; axis < 3; ++axis) {
            if (t[0][axis] == t[1][axis] && t[1][axis] == t[2][axis]) {
              Vec3 on = point();
              on[axis] = t[0][axis];
              return {on, point(), point()};
            }
          }
        }
        return {point(), point(), point()};
      }
      case 6: {  // zero area: collinear or repeated corners
        const Vec3 a = point(), b = point();
        return rng_() % 2 ? Triangle{a, b, a} : Triangle{a, b, b};
      }
      default:
        return {point(), point(), point()};
    }
  }

  std::mt19937_64 rng_;
};


struct Summary {
  Index pieces, copies, nodes;
  std::vector<double> volumes;
  double area;
};

Summary cut_and_check(const TetMesh& mesh, const std::vector<Triangle>& soup, int batches) {
  Cutter cutter(mesh);
  // Split the soup into `batches` consecutive batches: cutting in batches must not matter either.
  const std::size_t per = (soup.size() + static_cast<std::size_t>(batches) - 1) / static_cast<std::size_t>(batches);
  for (std::size_t i = 0; i < soup.size(); i += per) {
    cutter.cut(testing::soup({soup.begin() + static_cast<std::ptrdiff_t>(i),
                           soup.begin() + static_cast<std::ptrdiff_t>(std::min(soup.size(), i + per))}));
  }
  const CutResult r = cutter.result();
  EXPECT_EQ(testing::check_cut_invariants(mesh, r), "");
  // What a simulator reads after a batch, copy by copy, is what the result gives (the same bits).
  const std::vector<double> fractions = r.mesh.material_fractions();
  std::vector<Index> listed(fractions.size(), 0);
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    for (const Index c : cutter.copies_of(t)) {
      EXPECT_EQ(r.mesh.tet_parent[c], t);
      ++listed[c];
    }
  }
  for (std::size_t c = 0; c < fractions.size(); ++c) {
    EXPECT_EQ(cutter.material_fraction(static_cast<Index>(c)), fractions[c]) << "copy " << c;
    EXPECT_EQ(listed[c], 1) << "copy " << c;
  }
  return {r.mesh.num_pieces(), r.mesh.mesh.num_tets(), r.mesh.mesh.num_nodes(), r.mesh.piece_volumes,
          measure_surface(r.surface.surface).area};
}

void run_soups(const TetMesh& mesh, std::uint64_t first_seed, int count) {
  for (int i = 0; i < count; ++i) {
    const std::uint64_t seed = first_seed + static_cast<std::uint64_t>(i);
    SCOPED_TRACE("seed " + std::to_string(seed));
    SoupMaker maker(seed);
    const std::vector<Triangle> soup = maker.make();
    const Summary a = cut_and_check(mesh, soup, 1);
    const Summary b = cut_and_check(mesh, maker.shuffled(soup), 1 + static_cast<int>(seed % 3));
    ASSERT_EQ(a.pieces, b.pieces);
    ASSERT_EQ(a.copies, b.copies);
    ASSERT_EQ(a.nodes, b.nodes);
    for (std::size_t k = 0; k < a.volumes.size(); ++k) ASSERT_NEAR(a.volumes[k], b.volumes[k], 1e-13) << "piece " << k;
    ASSERT_NEAR(a.area, b.area, 1e-12 * std::max(1.0, a.area));
    if (::testing::Test::HasFailure()) return;
  }
}

TEST(RandomSoups, InAGridOfFiveTetCubes) { run_soups(make_grid(Box{}, {2, 2, 2}, 5), 1, 1000); }

TEST(RandomSoups, InAGridOfSixTetCubes) { run_soups(make_grid(Box{}, {2, 2, 2}, 6), 100001, 500); }

TEST(RandomSoups, InABccLattice) { run_soups(make_bcc(Box{}, 0.5), 200001, 500); }

}  // namespace
}  // namespace tetcut
