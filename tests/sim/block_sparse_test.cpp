// The Newton system's matrix and solver: the block pattern holds exactly the couplings of tets,
// spring groups and contact's node pairs, the masked product is the dense product over free nodes, and conjugate
// gradients solve to their target with the same bits on one thread and on several.

#include <gtest/gtest.h>

#include <tetcut/generators.hpp>

#include "sim/block_sparse.hpp"

#include <Eigen/Dense>
#include <tbb/task_arena.h>

#include <map>
#include <random>
#include <set>

namespace tetcut::sim::detail {
namespace {

std::vector<std::array<Index, 4>> tets_of(const TetMesh& mesh) {
  std::vector<std::array<Index, 4>> tets(static_cast<std::size_t>(mesh.num_tets()));
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    for (int k = 0; k < 4; ++k) tets[t][k] = mesh.tets()(t, k);
  }
  return tets;
}

TEST(BlockSparseMatrix, PatternHoldsExactlyTheCouplings) {
  const TetMesh mesh = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}, 0.25);
  const auto tets = tets_of(mesh);
  const std::vector<std::array<Index, 8>> extra{{0, 1, 2, 3, mesh.num_nodes() - 4, mesh.num_nodes() - 3, mesh.num_nodes() - 2, mesh.num_nodes() - 1}};
  // Couplings (contact's blocks, kept through a build): both orders, one of them already a tet's.
  const std::vector<std::array<Index, 2>> couplings{{5, mesh.num_nodes() - 7}, {mesh.num_nodes() / 2, 1}, {tets[0][0], tets[0][1]}};
  BlockSparseMatrix a;
  std::vector<std::array<Index, 16>> slots;
  a.build(mesh.num_nodes(), tets, extra, &slots, couplings);
  std::set<std::pair<Index, Index>> expected;
  for (Index n = 0; n < mesh.num_nodes(); ++n) expected.insert({n, n});
  for (const auto& t : tets) {
    for (const Index i : t) {
      for (const Index j : t) expected.insert({i, j});
    }
  }
  for (const Index i : extra[0]) {
    for (const Index j : extra[0]) expected.insert({i, j});
  }
  for (const auto& [i, j] : couplings) {
    expected.insert({i, j});
    expected.insert({j, i});
  }
  ASSERT_EQ(a.num_blocks(), static_cast<Index>(expected.size()));
  EXPECT_EQ(a.num_added_blocks(), 0);  // all of them in the rows, none in the added blocks' table
  for (const auto& [i, j] : expected) {
    EXPECT_GE(a.slot(i, j), 0);
    EXPECT_EQ(a.transposed_slot(a.slot(i, j)), a.slot(j, i));
  }
  for (Index row = 0; row < a.num_rows(); ++row) {
    Index previous = -1;
    a.for_each_block(row, [&](Index k, Index column) {
      EXPECT_LT(previous, column);  // ascending after a build
      previous = column;
      if (column == row) {
        EXPECT_EQ(k, a.diagonal_slot(row));
      }
    });
  }
  for (std::size_t t = 0; t < tets.size(); ++t) {
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) EXPECT_EQ(slots[t][4 * i + j], a.slot(tets[t][i], tets[t][j]));
    }
  }
  EXPECT_EQ(a.slot(0, mesh.num_nodes() - 1) >= 0, true);
  // A block added after the build has no transpose until that is added too; then each names the other.
  const Index p = 2, q = mesh.num_nodes() - 9;
  ASSERT_LT(a.slot(p, q), 0);
  const Index pq = a.find_or_add(p, q);
  EXPECT_EQ(a.transposed_slot(pq), -1);
  const Index qp = a.find_or_add(q, p);
  EXPECT_EQ(a.transposed_slot(pq), qp);
  EXPECT_EQ(a.transposed_slot(qp), pq);
  a.add_rows(1);
  const Index last = a.num_rows() - 1;
  EXPECT_EQ(a.transposed_slot(a.diagonal_slot(last)), a.diagonal_slot(last));
}

// A random symmetric positive definite matrix on a mesh's pattern: per tet a random Gram matrix,
// plus a diagonal.
BlockSparseMatrix random_system(const TetMesh& mesh, Eigen::MatrixXd* dense, std::uint64_t seed) {
  const auto tets = tets_of(mesh);
  BlockSparseMatrix a;
  std::vector<std::array<Index, 16>> slots;
  a.build(mesh.num_nodes(), tets, {}, &slots);
  const Index n = mesh.num_nodes();
  *dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    Eigen::Matrix<double, 12, 12> g;
    for (int k = 0; k < 144; ++k) g.data()[k] = u(rng);
    const Eigen::Matrix<double, 12, 12> h = g * g.transpose() / 12;
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        double block[9];
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) {
            block[3 * r + c] = h(3 * i + r, 3 * j + c);
            (*dense)(3 * tets[t][i] + r, 3 * tets[t][j] + c) += h(3 * i + r, 3 * j + c);
          }
        }
        a.add(slots[t][4 * i + j], block);
      }
    }
  }
  for (Index v = 0; v < n; ++v) {
    a.add_to_diagonal(v, 0.5);
    for (int k = 0; k < 3; ++k) (*dense)(3 * v + k, 3 * v + k) += 0.5;
  }
  return a;
}

TEST(BlockSparseMatrix, MaskedProductIsTheDenseProductOverFreeNodes) {
  const TetMesh mesh = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}, 0.3);
  Eigen::MatrixXd dense;
  const BlockSparseMatrix a = random_system(mesh, &dense, 3);
  const Index n = mesh.num_nodes();
  std::vector<std::uint8_t> free(static_cast<std::size_t>(n));
  Eigen::VectorXd x = Eigen::VectorXd::Random(3 * n);
  for (Index v = 0; v < n; ++v) {
    free[v] = v % 5 != 0;
    if (!free[v]) x.segment<3>(3 * v).setZero();  // the solver keeps vectors zero there
  }
  Eigen::VectorXd y(3 * n);
  a.multiply(x.data(), y.data(), free.data());
  Eigen::VectorXd expected = dense * x;
  for (Index v = 0; v < n; ++v) {
    if (!free[v]) expected.segment<3>(3 * v).setZero();
  }
  EXPECT_LT((y - expected).norm(), 1e-12 * expected.norm());
}

// Blocks added after the build (surface contact's couplings): thousands of them, in random order
// and with repeats, so that their index grows several times; each keeps its slot, blocks never
// added are not found, rows appended later take blocks too, and the product counts them all.
TEST(BlockSparseMatrix, AddedBlocksKeepTheirSlotsAndEnterTheProduct) {
  const TetMesh mesh = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}, 0.3);
  Eigen::MatrixXd dense;
  BlockSparseMatrix a = random_system(mesh, &dense, 5);
  const Index built_blocks = a.num_blocks();
  a.add_rows(3);
  const Index n = a.num_rows();
  dense.conservativeResize(3 * n, 3 * n);
  dense.rightCols(9).setZero();
  dense.bottomRows(9).setZero();
  for (Index v = n - 3; v < n; ++v) {
    a.add_to_diagonal(v, 0.5);
    for (int k = 0; k < 3; ++k) dense(3 * v + k, 3 * v + k) = 0.5;
  }
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<Index> node(0, n - 1);
  std::map<std::pair<Index, Index>, Index> slots;
  for (int i = 0; i < 20000; ++i) {
    const Index row = node(rng), column = node(rng);
    const Index before = a.slot(row, column);
    const Index k = a.find_or_add(row, column);
    ASSERT_GE(k, 0);
    if (before >= 0) {
      EXPECT_EQ(k, before);
    }
    const auto [it, inserted] = slots.emplace(std::pair{row, column}, k);
    if (!inserted) {
      EXPECT_EQ(it->second, k);
    }
    const double block[9] = {1e-3 * (i % 7), 0, 0, 0, 1e-3, 0, 0, 0, 2e-3};
    a.add(k, block);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) dense(3 * row + r, 3 * column + c) += block[3 * r + c];
    }
  }
  EXPECT_GT(a.num_added_blocks(), 10000);
  EXPECT_EQ(a.num_blocks(), built_blocks + a.num_added_blocks());
  for (const auto& [key, k] : slots) EXPECT_EQ(a.slot(key.first, key.second), k);
  // Pairs never added nor coupled by a tet: not in the pattern.
  Index absent = 0;
  for (Index row = 0; row < n; ++row) {
    for (Index column = 0; column < n; ++column) {
      if (slots.count({row, column}) || dense.block<3, 3>(3 * row, 3 * column).norm() != 0) continue;
      EXPECT_EQ(a.slot(row, column), -1);
      ++absent;
    }
  }
  EXPECT_GT(absent, 0);
  const std::vector<std::uint8_t> free(static_cast<std::size_t>(n), 1);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(3 * n);
  Eigen::VectorXd y(3 * n);
  a.multiply(x.data(), y.data(), free.data());
  const Eigen::VectorXd expected = dense * x;
  EXPECT_LT((y - expected).norm(), 1e-12 * expected.norm());
}

TEST(BlockSparseMatrix, SinglePrecisionStorageIsTheProductToFloatRounding) {
  const TetMesh mesh = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 1)}, 0.3);
  Eigen::MatrixXd dense;
  BlockSparseMatrix a = random_system(mesh, &dense, 5);
  const BlockSparseMatrix doubles = a;
  a.set_single_precision(true);  // zeroes the values: assemble again
  EXPECT_TRUE(a.single_precision());
  const BlockSparseMatrix refill = random_system(mesh, &dense, 5);
  for (Index row = 0; row < refill.num_rows(); ++row) {
    refill.for_each_block(row, [&](Index k, Index) {
      double block[9];
      refill.read(k, block);
      a.add(k, block);
    });
  }
  const Index n = mesh.num_nodes();
  std::vector<std::uint8_t> free(static_cast<std::size_t>(n), 1);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(3 * n);
  Eigen::VectorXd y_single(3 * n), y_double(3 * n);
  a.multiply(x.data(), y_single.data(), free.data());
  doubles.multiply(x.data(), y_double.data(), free.data());
  EXPECT_LT((y_single - y_double).norm(), 1e-6 * y_double.norm());
  EXPECT_GT((y_single - y_double).norm(), 0.0);  // it is float storage
  // CG on it still reaches a tight target.
  std::vector<double> b(3 * static_cast<std::size_t>(n)), d(b.size(), 0.0), weight(static_cast<std::size_t>(n), 1.0);
  for (std::size_t k = 0; k < b.size(); ++k) b[k] = x[static_cast<Index>(k)];
  ConjugateGradientOptions options;
  options.relative_target = 1e-8;
  ConjugateGradientWorkspace workspace;
  EXPECT_TRUE(conjugate_gradients(a, b, d, free, weight, options, &workspace).reached_target);
}

TEST(ConjugateGradients, SolveToTheTargetAndDoNotDependOnThreads) {
  const TetMesh mesh = make_bcc(Box{Vec3(0, 0, 0), Vec3(1, 1, 2)}, 0.2);
  Eigen::MatrixXd dense;
  const BlockSparseMatrix a = random_system(mesh, &dense, 8);
  const Index n = mesh.num_nodes();
  std::vector<std::uint8_t> free(static_cast<std::size_t>(n), 1);
  for (Index v = 0; v < n; v += 7) free[v] = 0;
  std::vector<double> b(3 * static_cast<std::size_t>(n)), weight(static_cast<std::size_t>(n), 1.0);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  for (Index v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) b[3 * v + k] = free[v] ? u(rng) : 0.0;
  }
  ConjugateGradientOptions options;
  options.relative_target = 1e-10;
  const auto solve = [&](int threads) {
    std::vector<double> d(b.size(), 0.0);
    ConjugateGradientWorkspace workspace;
    ConjugateGradientReport report;
    tbb::task_arena(threads).execute([&] { report = conjugate_gradients(a, b, d, free, weight, options, &workspace); });
    EXPECT_TRUE(report.reached_target);
    return std::pair(d, report.iterations);
  };
  const auto [one, iterations_one] = solve(1);
  const auto [two, iterations_two] = solve(2);
  EXPECT_EQ(one, two);  // bit for bit
  EXPECT_EQ(iterations_one, iterations_two);
  // The solution of the free nodes' system.
  std::vector<Index> dof;
  for (Index v = 0; v < n; ++v) {
    if (free[v]) {
      for (int k = 0; k < 3; ++k) dof.push_back(3 * v + k);
    }
  }
  Eigen::MatrixXd reduced(dof.size(), dof.size());
  Eigen::VectorXd rhs(dof.size());
  for (std::size_t i = 0; i < dof.size(); ++i) {
    rhs[i] = b[dof[i]];
    for (std::size_t j = 0; j < dof.size(); ++j) reduced(i, j) = dense(dof[i], dof[j]);
  }
  const Eigen::VectorXd exact = reduced.llt().solve(rhs);
  double error = 0;
  for (std::size_t i = 0; i < dof.size(); ++i) error = std::max(error, std::abs(one[dof[i]] - exact[i]));
  EXPECT_LT(error, 1e-8 * exact.cwiseAbs().maxCoeff());
  for (Index v = 0; v < n; ++v) {
    if (!free[v]) {
      EXPECT_EQ(one[3 * v], 0.0);
    }
  }
  // A budget stops it early, short of the target.
  options.max_iterations = 3;
  std::vector<double> d(b.size(), 0.0);
  ConjugateGradientWorkspace workspace;
  const ConjugateGradientReport capped = conjugate_gradients(a, b, d, free, weight, options, &workspace);
  EXPECT_EQ(capped.iterations, 3);
  EXPECT_FALSE(capped.reached_target);
  EXPECT_GT(capped.weighted_residual, 0);
}

}  // namespace
}  // namespace tetcut::sim::detail
