// The assembled elastic energy, gradient and Hessian of a whole mesh against finite differences,
// on a smoothly deformed block and on one with nearly inverted and inverted elements; and the
// element colouring (no two elements of a colour share a node).

#include <gtest/gtest.h>

#include <tetcut/generators.hpp>
#include <tetcut/sim.hpp>

#include "sim/simulator_state.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <random>
#include <set>

namespace tetcut::sim {
namespace {

class Assembly : public ::testing::TestWithParam<Model> {
 protected:
  // A state over a BCC block with one element a sliver copy (1% material) at positions `x`.
  SimulatorState state(const TetMesh& mesh, const Points& x) const {
    SimulatorState s;
    s.material.model = GetParam();
    s.parameters = model_parameters(GetParam(), lame_parameters(s.material.youngs_modulus, s.material.poissons_ratio));
    s.x = x;
    s.v = Points::Zero(mesh.num_nodes(), 3);
    s.constraint.assign(static_cast<std::size_t>(mesh.num_nodes()), -1);
    s.target = Points::Zero(mesh.num_nodes(), 3);
    std::vector<double> fraction(static_cast<std::size_t>(mesh.num_tets()), 1.0);
    fraction[3] = 0;
    s.build(mesh, fraction);
    s.refresh_structure();
    return s;
  }
};

// A smooth bend and stretch of the block, and the same with a few nodes pushed through the
// opposite faces of their tets (inverted elements).
Points deformed(const TetMesh& mesh, bool invert) {
  Points x = mesh.rest();
  for (Index v = 0; v < x.rows(); ++v) {
    const Vec3 X = mesh.rest().row(v).transpose();
    x.row(v) = Vec3(X[0] * 1.1 + 0.05 * X[2] * X[2], X[1] * 0.95 + 0.02 * X[0], X[2] * 1.05 + 0.03 * std::sin(3 * X[0])).transpose();
  }
  if (invert) {
    for (Index t = 0; t < mesh.num_tets(); t += 37) {
      const Index a = mesh.tets()(t, 0);
      Vec3 opposite = Vec3::Zero();
      for (int k = 1; k < 4; ++k) opposite += x.row(mesh.tets()(t, k)).transpose() / 3;
      // Node a moved 1.2 of the way to the opposite face's centre: through it.
      x.row(a) = (x.row(a).transpose() + 1.2 * (opposite - x.row(a).transpose())).transpose();
    }
  }
  return x;
}

TEST_P(Assembly, GradientIsTheEnergysDerivative) {
  const TetMesh mesh = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}, 0.34);
  for (const bool invert : {false, true}) {
    SimulatorState s = state(mesh, deformed(mesh, invert));
    std::vector<double> g(3 * static_cast<std::size_t>(mesh.num_nodes()), 0.0);
    const double energy = s.elastic_gradient(s.x, &g);
    EXPECT_NEAR(energy, s.elastic_energy(s.x), 1e-12 * std::abs(energy));
    const double step = 1e-7;
    double worst = 0, largest = 0;
    for (Index v = 0; v < mesh.num_nodes(); ++v) {
      for (int k = 0; k < 3; ++k) {
        Points plus = s.x, minus = s.x;
        plus(v, k) += step;
        minus(v, k) -= step;
        const double numeric = (s.elastic_energy(plus) - s.elastic_energy(minus)) / (2 * step);
        worst = std::max(worst, std::abs(numeric - g[3 * v + k]));
        largest = std::max(largest, std::abs(numeric));
      }
    }
    EXPECT_LT(worst, 1e-5 * largest) << (invert ? "with inverted elements" : "smooth");
  }
}

TEST_P(Assembly, HessianIsTheGradientsDerivativeAndPositiveSemiDefinite) {
  const TetMesh mesh = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}, 0.34);
  const Index n = mesh.num_nodes();
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const bool invert : {false, true}) {
    SimulatorState s = state(mesh, deformed(mesh, invert));
    std::vector<double> g(3 * static_cast<std::size_t>(n), 0.0);
    s.assemble_hessian(s.x, &g);
    // The assembled matrix, dense, from its blocks.
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    for (Index row = 0; row < n; ++row) {
      s.hessian.for_each_block(row, [&](Index k, Index column) {
        double b[9];
        s.hessian.read(k, b);
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) H(3 * row + i, 3 * column + j) = b[3 * i + j];
        }
      });
    }
    EXPECT_LT((H - H.transpose()).norm(), 1e-12 * H.norm());
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues().minCoeff(), -1e-9 * H.norm());
    // Sum of the element Hessians = the assembly (checked per element through the kernel).
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    for (std::size_t e = 0; e < s.elements.size(); ++e) {
      const SimulatorState::Element& el = s.elements[e];
      Mat3 V = Mat3::Identity(), P;
      detail::Mat12 h;
      detail::element_hessian(GetParam(), s.parameters, s.deformation_gradient(el, s.x), el.weights, el.volume, &V, &P, &h);
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) sum.block<3, 3>(3 * el.nodes[a], 3 * el.nodes[b]) += h.block<3, 3>(3 * a, 3 * b);
      }
    }
    EXPECT_LT((H - sum).norm(), 1e-7 * H.norm());
    if (invert) continue;  // projected there: not the gradient's derivative
    // Smooth stretch: nothing is clamped but the elements' rest-like twists, so H times a random
    // direction is the gradient's directional derivative up to those.
    Eigen::VectorXd dir(3 * n);
    for (Index k = 0; k < 3 * n; ++k) dir[k] = u(rng);
    const double step = 1e-6;
    Points plus = s.x, minus = s.x;
    for (Index v = 0; v < n; ++v) {
      plus.row(v) += step * dir.segment<3>(3 * v).transpose();
      minus.row(v) -= step * dir.segment<3>(3 * v).transpose();
    }
    std::vector<double> gp(g.size(), 0.0), gm(g.size(), 0.0);
    s.elastic_gradient(plus, &gp);
    s.elastic_gradient(minus, &gm);
    Eigen::VectorXd numeric(3 * n);
    for (Index k = 0; k < 3 * n; ++k) numeric[k] = (gp[k] - gm[k]) / (2 * step);
    EXPECT_LT((H * dir - numeric).norm(), 1e-2 * numeric.norm());
  }
}

TEST_P(Assembly, ClustersOfAColourShareNoNode) {
  const TetMesh mesh = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}, 0.1);
  const SimulatorState s = state(mesh, mesh.rest());
  const Index count = static_cast<Index>(s.elements.size());
  // The order is a permutation of the elements.
  std::vector<Index> sorted = s.element_order;
  std::sort(sorted.begin(), sorted.end());
  for (Index e = 0; e < count; ++e) ASSERT_EQ(sorted[e], e);
  std::vector<Index> seen(static_cast<std::size_t>(mesh.num_nodes()), -1);
  std::set<Index> clusters;
  for (std::size_t c = 0; c + 1 < s.color_start.size(); ++c) {
    for (Index i = s.color_start[c]; i < s.color_start[c + 1]; ++i) {
      const Index k = s.color_clusters[i];
      clusters.insert(k);
      for (Index j = k * SimulatorState::kCluster; j < std::min(count, (k + 1) * SimulatorState::kCluster); ++j) {
        for (const Index v : s.ordered[j].element.nodes) {
          // A node may appear twice in one cluster, never in two clusters of one colour.
          EXPECT_TRUE(seen[v] == -1 || seen[v] == k || s.color_clusters[s.color_start[c]] > seen[v] ||
                      std::find(s.color_clusters.begin() + s.color_start[c], s.color_clusters.begin() + i, seen[v]) ==
                          s.color_clusters.begin() + i)
              << "node " << v << " in two clusters of colour " << c;
          seen[v] = k;
        }
      }
    }
  }
  EXPECT_EQ(static_cast<Index>(clusters.size()), (count + SimulatorState::kCluster - 1) / SimulatorState::kCluster);
  EXPECT_GT(s.color_start.size(), 2u);  // more than one colour: clusters next to each other conflict
}

INSTANTIATE_TEST_SUITE_P(BothModels, Assembly, ::testing::Values(Model::kCorotated, Model::kStableNeoHookean));

TEST(Assembly, ManyCopiesAroundOneNodeNeedMoreThan64Colours) {
  // 70 clusters' worth of copies of one tet sharing one node (as a tet cut into very many pieces
  // makes: copies overlap in rest space): every two clusters conflict, so 70 colours, past the
  // 64 the fast path tracks.
  const Index tets_around = 70 * SimulatorState::kCluster;
  Points rest(1 + 3 * tets_around, 3);
  Tets tets(tets_around, 4);
  rest.row(0) = Vec3(0, 0, 0).transpose();
  for (Index t = 0; t < tets_around; ++t) {
    rest.row(1 + 3 * t) = Vec3(1, 0, 0).transpose();
    rest.row(2 + 3 * t) = Vec3(0, 1, 0).transpose();
    rest.row(3 + 3 * t) = Vec3(0, 0, 1).transpose();
    tets.row(t) << 0, 1 + 3 * t, 2 + 3 * t, 3 + 3 * t;
  }
  const TetMesh mesh(rest, tets);
  SimulatorState s;
  s.x = mesh.rest();
  s.build(mesh, {});
  ASSERT_EQ(s.color_start.size(), 71u);
  for (Index c = 0; c < 70; ++c) EXPECT_EQ(s.color_start[c + 1] - s.color_start[c], 1);
  Simulator sim(mesh, Material{});
  sim.pin(0);
  StepOptions options;
  options.dt = 0.01;
  EXPECT_TRUE(sim.step(options).converged);
  // All of it swings down about node 0, which holds.
  EXPECT_LT(sim.positions()(5, 2), rest(5, 2));
  EXPECT_LT(sim.positions()(3 * tets_around, 2), rest(3 * tets_around, 2));
  EXPECT_EQ(sim.positions()(0, 2), 0.0);
}

}  // namespace
}  // namespace tetcut::sim
