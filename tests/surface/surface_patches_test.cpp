// The material surface kept in patches: after every batch, the surface assembled from patches
// rebuilt only where the batch changed them is the very surface built at once from the same
// state. Any patch left out of date (a neighbour whose face or edge a batch split, a copy whose
// nodes were renumbered) shows up as a difference here.

#include <gtest/gtest.h>

#include <tetcut/cutter.hpp>
#include <tetcut/generators.hpp>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "support/cut_invariants.hpp"

namespace tetcut {
namespace {

using testing::Triangle;

// Empty when the two surfaces are identical (same numbering, same doubles), else what differs.
std::string difference(const MaterialSurface& a, const MaterialSurface& b) {
  if (a.surface.vertices.rows() != b.surface.vertices.rows()) {
    return "vertex counts " + std::to_string(a.surface.vertices.rows()) + " vs " + std::to_string(b.surface.vertices.rows());
  }
  if (a.surface.triangles.rows() != b.surface.triangles.rows()) {
    return "triangle counts " + std::to_string(a.surface.triangles.rows()) + " vs " +
           std::to_string(b.surface.triangles.rows());
  }
  if (a.surface.vertices != b.surface.vertices) return "vertex positions";
  if (a.surface.triangles != b.surface.triangles) return "triangles";
  if (a.vertex_tet != b.vertex_tet) return "vertex embedding copies";
  if (a.vertex_weights != b.vertex_weights) return "vertex weights";
  if (a.triangle_source != b.triangle_source) return "triangle sources";
  if (a.triangle_tet != b.triangle_tet) return "triangle copies";
  return "";
}

// Random batches with degenerate ingredients on a lattice of spacing 1/4: corners on mesh nodes,
// edges and faces, axis-parallel triangles along mesh faces, repeats.
class BatchMaker {
 public:
  explicit BatchMaker(std::uint64_t seed) : rng_(seed) {}

  std::vector<Triangle> batch(int size) {
    std::vector<Triangle> out;
    for (int i = 0; i < size; ++i) out.push_back(triangle());
    return out;
  }

 private:
  double coordinate() {
    return rng_() % 2 ? static_cast<double>(rng_() % 9) / 8.0 - 0.0625 * static_cast<double>(rng_() % 2)
                      : std::uniform_real_distribution<double>(-0.2, 1.2)(rng_);
  }
  Vec3 point() { return {coordinate(), coordinate(), coordinate()}; }
  Triangle triangle() {
    Triangle t{point(), point(), point()};
    if (rng_() % 3 == 0) {  // axis-parallel, often along mesh faces
      const int axis = static_cast<int>(rng_() % 3);
      for (Vec3& p : t) p[axis] = t[0][axis];
    }
    return t;
  }

  std::mt19937_64 rng_;
};

TEST(SurfacePatches, AfterEveryBatchTheSurfaceEqualsOneBuiltAtOnce) {
  for (const bool bcc : {false, true}) {
    const TetMesh mesh = bcc ? make_bcc(Box{}, 0.5) : make_grid(Box{}, {2, 2, 2}, 5);
    for (std::uint64_t seed = 1; seed <= 40; ++seed) {
      SCOPED_TRACE((bcc ? "bcc, seed " : "grid, seed ") + std::to_string(seed));
      BatchMaker maker(seed);
      Cutter progressive(mesh);
      std::vector<std::vector<Triangle>> batches;
      for (int b = 0; b < 6; ++b) {
        batches.push_back(maker.batch(1 + static_cast<int>(seed % 3)));
        progressive.cut(testing::soup(batches.back()));
        const MaterialSurface incremental = progressive.surface();
        Cutter at_once(mesh);
        for (const auto& batch : batches) at_once.cut(testing::soup(batch));
        ASSERT_EQ(difference(incremental, at_once.surface()), "") << "after batch " << b;
      }
      EXPECT_EQ(testing::check_cut_invariants(mesh, progressive.result()), "");
    }
  }
}

// The same in world space on a mesh that moves between batches, where copies split apart.
TEST(SurfacePatches, WorldSpaceBatchesOnAMovingMesh) {
  const TetMesh mesh = make_bcc(Box{}, 0.25);
  const auto bend = [](const Vec3& x, double t) -> Vec3 { return {x[0] + 0.2 * t * x[2] * x[2], x[1], x[2] + 0.1 * t * x[0]}; };
  const auto positions = [&](const Cutter& cutter, double t) {
    Points now(cutter.num_nodes(), 3);
    for (Index n = 0; n < cutter.num_nodes(); ++n) now.row(n) = bend(mesh.rest().row(cutter.node_parent()[n]).transpose(), t).transpose();
    return now;
  };
  std::vector<std::vector<Triangle>> batches;
  for (int frame = 0; frame < 8; ++frame) {
    const double x = 0.1 + 0.1 * frame;
    batches.push_back({{Vec3(x, -0.1, -0.1), Vec3(x + 0.05, 1.1, -0.1), Vec3(x, 0.5, 1.1)},
                       {Vec3(-1, -1, 0.12 * frame), Vec3(5, -1, 0.12 * frame), Vec3(-1, 5, 0.12 * frame)}});
  }
  Cutter progressive(mesh);
  for (std::size_t b = 0; b < batches.size(); ++b) {
    const double t = static_cast<double>(b) / 8.0;
    progressive.cut_deformed(testing::soup(batches[b]), positions(progressive, t));
    const MaterialSurface incremental = progressive.surface();
    Cutter at_once(mesh);
    for (std::size_t k = 0; k <= b; ++k) {
      at_once.cut_deformed(testing::soup(batches[k]), positions(at_once, static_cast<double>(k) / 8.0));
    }
    ASSERT_EQ(difference(incremental, at_once.surface()), "") << "after batch " << b;
  }
  const CutResult r = progressive.result();
  EXPECT_EQ(testing::check_cut_invariants(mesh, r), "");
  EXPECT_GT(r.mesh.num_pieces(), 5);  // the world planes z = 0.12 k slice the block
}

}  // namespace
}  // namespace tetcut
