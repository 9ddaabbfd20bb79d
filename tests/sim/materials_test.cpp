// Energy densities against their derivatives by central differences, rest stability, and the
// small-strain limit against linear elasticity.

#include <gtest/gtest.h>

#include <tetcut/error.hpp>
#include <tetcut/sim.hpp>

#include <Eigen/Eigenvalues>

#include <random>

namespace tetcut::sim {
namespace {

Mat3 random_deformation(std::mt19937_64& rng, bool inverted) {
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  Mat3 F = Mat3::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) F(i, j) += u(rng);
  }
  if (inverted) F.col(0) *= -1;
  return F;
}

class Materials : public ::testing::TestWithParam<Model> {};

TEST_P(Materials, StressIsTheEnergyGradient) {
  const Lame p = model_parameters(GetParam(), lame_parameters(2e5, 0.35));
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const Mat3 F = random_deformation(rng, trial % 4 == 3);
    const Mat3 P = first_piola(GetParam(), p, F);
    const double h = 1e-6;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        Mat3 plus = F, minus = F;
        plus(i, j) += h;
        minus(i, j) -= h;
        const double numeric = (energy_density(GetParam(), p, plus) - energy_density(GetParam(), p, minus)) / (2 * h);
        EXPECT_NEAR(P(i, j), numeric, 1e-6 * (std::abs(numeric) + p.mu)) << "trial " << trial << " entry " << i << j;
      }
    }
  }
}

TEST_P(Materials, StressDerivativeIsTheStressGradient) {
  const Lame p = model_parameters(GetParam(), lame_parameters(2e5, 0.35));
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 40; ++trial) {
    const Mat3 F = random_deformation(rng, trial % 4 == 3);
    const Mat9 D = stress_derivative(GetParam(), p, F);
    const double h = 1e-6;
    for (int k = 0; k < 9; ++k) {
      Mat3 plus = F, minus = F;
      plus(k % 3, k / 3) += h;
      minus(k % 3, k / 3) -= h;
      const Mat3 column = (first_piola(GetParam(), p, plus) - first_piola(GetParam(), p, minus)) / (2 * h);
      for (int r = 0; r < 9; ++r) {
        EXPECT_NEAR(D(r, k), column(r % 3, r / 3), 1e-5 * (std::abs(column(r % 3, r / 3)) + p.mu))
            << "trial " << trial << " entry " << r << "," << k;
      }
    }
    // A Hessian: symmetric.
    EXPECT_LT((D - D.transpose()).norm(), 1e-9 * D.norm());
  }
}

TEST_P(Materials, RestIsStressFreeAndRotationsCostNothing) {
  const Lame p = model_parameters(GetParam(), lame_parameters(1e5, 0.3));
  EXPECT_NEAR(energy_density(GetParam(), p, Mat3::Identity()), 0, 1e-9 * p.mu);
  EXPECT_LT(first_piola(GetParam(), p, Mat3::Identity()).norm(), 1e-9 * p.mu);
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_NEAR(energy_density(GetParam(), p, R), energy_density(GetParam(), p, Mat3::Identity()), 1e-9 * p.mu);
  EXPECT_LT(first_piola(GetParam(), p, R).norm(), 1e-9 * p.mu);
}

TEST_P(Materials, SmallStrainsAreLinearElasticity) {
  // At rest, dP/dF is the linear elasticity tensor mu (I + T) + lambda vec(I) vec(I)^T, with T
  // the transposition, for the Lamé parameters given (after the model's own mapping).
  const Lame lame = lame_parameters(3e5, 0.25);
  const Mat9 D = stress_derivative(GetParam(), model_parameters(GetParam(), lame), Mat3::Identity());
  Mat9 linear = lame.mu * Mat9::Identity();
  Eigen::Matrix<double, 9, 1> identity = Eigen::Matrix<double, 9, 1>::Zero();
  for (int i = 0; i < 3; ++i) {
    identity[4 * i] = 1;
    for (int j = 0; j < 3; ++j) linear(3 * j + i, 3 * i + j) += lame.mu;
  }
  linear += lame.lambda * identity * identity.transpose();
  EXPECT_LT((D - linear).norm(), 1e-9 * linear.norm()) << D << "\n\n" << linear;
}

TEST_P(Materials, ProjectionIsPositiveSemiDefiniteAndKeepsDefiniteOnes) {
  const Lame p = model_parameters(GetParam(), lame_parameters(1e5, 0.3));
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Mat3 F = random_deformation(rng, trial % 2 == 1);
    const Mat9 projected = projected_stress_derivative(GetParam(), p, F);
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat9>(projected).eigenvalues().minCoeff(), -1e-9 * p.mu);
  }
  const Mat9 rest = stress_derivative(GetParam(), p, Mat3::Identity());
  EXPECT_LT((projected_stress_derivative(GetParam(), p, Mat3::Identity()) - rest).norm(), 1e-9 * rest.norm());
}

INSTANTIATE_TEST_SUITE_P(BothModels, Materials, ::testing::Values(Model::kCorotated, Model::kStableNeoHookean));

TEST(Lame, FromYoungsModulusAndPoissonsRatio) {
  const Lame p = lame_parameters(1e6, 0.25);
  EXPECT_NEAR(p.mu, 4e5, 1e-6);
  EXPECT_NEAR(p.lambda, 4e5, 1e-6);
  EXPECT_THROW(lame_parameters(-1, 0.3), Error);
  EXPECT_THROW(lame_parameters(1e5, 0.5), Error);
  EXPECT_THROW(lame_parameters(1e5, std::nan("")), Error);
}

}  // namespace
}  // namespace tetcut::sim
