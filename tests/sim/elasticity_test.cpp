// The simulator's inner loop against independent references: the rotation-variant SVD on hard
// matrices (inverted, singular, repeated singular values), the analytic eigensystems against a
// numerical projection of the 9 x 9 tangent, and the 12 x 12 element Hessian against finite
// differences of the element gradient, swept toward inversion.

#include <gtest/gtest.h>

#include <tetcut/sim.hpp>

#include "sim/elasticity.hpp"
#include "sim/element_batch.hpp"
#include "sim/svd3.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <random>
#include <vector>

namespace tetcut::sim {
namespace {

using detail::Mat12;
using detail::ShapeWeights;
using detail::Vec12;

// Matrices that break naive SVDs: rotations, inverted and flat ones, repeated and zero singular
// values, tiny and huge scales, and random ones near the identity.
std::vector<Mat3> hard_matrices() {
  std::vector<Mat3> out;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  const Mat3 R = Eigen::AngleAxisd(0.9, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  const Mat3 Q = Eigen::AngleAxisd(-2.1, Vec3(0.3, 1, 1).normalized()).toRotationMatrix();
  out.push_back(Mat3::Identity());
  out.push_back(Mat3::Zero());
  out.push_back(R);
  out.push_back(R * Vec3(2, 2, 2).asDiagonal() * Q);        // all equal
  out.push_back(R * Vec3(3, 1, 1).asDiagonal() * Q);        // two equal
  out.push_back(R * Vec3(1, 1, -1).asDiagonal() * Q);       // inverted, all equal in magnitude
  out.push_back(R * Vec3(2, 1e-9, 0).asDiagonal() * Q);     // rank one
  out.push_back(R * Vec3(1, 0.5, 0).asDiagonal() * Q);      // flat
  out.push_back(R * Vec3(1, 0.5, -1e-12).asDiagonal() * Q); // just inverted
  out.push_back(1e-150 * R * Vec3(3, 2, 1).asDiagonal() * Q);
  out.push_back(1e100 * R * Vec3(3, 2, -1).asDiagonal() * Q);
  for (int i = 0; i < 200; ++i) {
    Mat3 F = Mat3::Identity();
    for (int k = 0; k < 9; ++k) F.data()[k] += u(rng);
    if (i % 3 == 0) F.col(i % 2) *= -1;
    out.push_back(F);
  }
  return out;
}

TEST(Svd3, FactorsAreRotationsAndReproduceTheMatrix) {
  for (const Mat3& F : hard_matrices()) {
    for (const double tolerance : {detail::kSvdExact, detail::kSvdForHessian}) {
      const detail::Svd3 d = detail::svd3(F, tolerance);
      const double scale = std::max(F.norm(), 1e-300);
      EXPECT_LT((d.U.transpose() * d.U - Mat3::Identity()).norm(), 1e-14);
      EXPECT_LT((d.V.transpose() * d.V - Mat3::Identity()).norm(), 1e-14);
      EXPECT_NEAR(d.U.determinant(), 1, 1e-14);
      EXPECT_NEAR(d.V.determinant(), 1, 1e-14);
      EXPECT_GE(d.sigma[0], d.sigma[1]);
      EXPECT_GE(d.sigma[1], std::abs(d.sigma[2]) - 1e-15 * scale);
      // The sign of det F sits in the last singular value.
      const double det = F.determinant();
      if (std::abs(det) > 1e-9 * scale * scale * scale) {
        EXPECT_EQ(d.sigma[2] < 0, det < 0) << F;
      }
      // The Hessian's tolerance leaves U^T F V nearly diagonal; the exact one reproduces F.
      const double error = (d.U * d.sigma.asDiagonal() * d.V.transpose() - F).norm() / scale;
      EXPECT_LT(error, tolerance == detail::kSvdExact ? 1e-14 : 1e-7) << F;
    }
  }
}

TEST(Svd3, WarmStartGivesTheSameDecomposition) {
  // A deformation drifting as in a simulation: each SVD starts from the last V.
  Mat3 V = Mat3::Identity();
  for (int step = 0; step < 100; ++step) {
    const double t = 0.03 * step;
    const Mat3 F = Eigen::AngleAxisd(t, Vec3(0, 0, 1)).toRotationMatrix() * Vec3(1 + 0.2 * std::sin(t), 1 - 0.1 * t, 0.9).asDiagonal() *
                   Eigen::AngleAxisd(0.5 * t, Vec3(1, 0, 0)).toRotationMatrix();
    const detail::Svd3 warm = detail::svd3(F, detail::kSvdExact, &V), cold = detail::svd3(F, detail::kSvdExact);
    V = warm.V;
    EXPECT_LT((warm.sigma - cold.sigma).norm(), 1e-14 * F.norm()) << "step " << step;
    EXPECT_LT((warm.U * warm.sigma.asDiagonal() * warm.V.transpose() - F).norm(), 1e-14 * F.norm());
  }
}

TEST(PositivePartFactor, GivesTheClampedMatrix) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 100; ++trial) {
    Mat3 a;
    for (int k = 0; k < 9; ++k) a.data()[k] = u(rng);
    a = (a + a.transpose()).eval();
    if (trial % 2 == 0) a += 3 * Mat3::Identity();  // positive definite: the Cholesky path
    const Eigen::SelfAdjointEigenSolver<Mat3> eigen(a);
    const Mat3 clamped = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
    const Mat3 c = detail::positive_part_factor(a);
    EXPECT_LT((c * c.transpose() - clamped).norm(), 1e-12 * (1 + a.norm())) << a;
  }
}

class Eigensystems : public ::testing::TestWithParam<Model> {};

// Deformations from near the identity to nearly and slightly inverted ones, with repeated
// singular values.
std::vector<Mat3> sweep_to_inversion() {
  std::vector<Mat3> out;
  const Mat3 R = Eigen::AngleAxisd(0.4, Vec3(1, 1, 0).normalized()).toRotationMatrix();
  const Mat3 Q = Eigen::AngleAxisd(1.3, Vec3(0, 1, 2).normalized()).toRotationMatrix();
  for (const double last : {1.0, 0.5, 0.1, 1e-2, 1e-4, -1e-4, -1e-2, -0.3}) {
    out.push_back(R * Vec3(1.2, 0.9, last).asDiagonal() * Q);
    out.push_back(R * Vec3(1.1, 1.1, last).asDiagonal() * Q);
  }
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  for (int i = 0; i < 40; ++i) {
    Mat3 F = Mat3::Identity();
    for (int k = 0; k < 9; ++k) F.data()[k] += u(rng);
    if (i % 4 == 3) F.col(0) *= -1;
    out.push_back(F);
  }
  return out;
}

TEST_P(Eigensystems, ProjectionIsTheNumericalProjectionOfTheTangent) {
  const Lame p = model_parameters(GetParam(), lame_parameters(1e5, 0.3));
  for (const Mat3& F : sweep_to_inversion()) {
    const Mat9 D = stress_derivative(GetParam(), p, F);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(Eigen::MatrixXd(0.5 * (D + D.transpose())));
    const Eigen::MatrixXd numerical = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
    EXPECT_LT((projected_stress_derivative(GetParam(), p, F) - numerical).norm(), 1e-9 * D.norm()) << F;
  }
}

// The element: four nodes of a reference tet (rest shape X), deformed by F plus a bend.
struct TestTet {
  Eigen::Matrix<double, 3, 4> rest;
  ShapeWeights w;
  double volume;
  TestTet() {
    rest << 0, 1, 0.1, 0.2, 0, 0.1, 0.9, 0.3, 0, 0.05, 0.1, 0.8;
    Mat3 dm;
    for (int k = 0; k < 3; ++k) dm.col(k) = rest.col(k + 1) - rest.col(0);
    const Mat3 inverse = dm.inverse();
    w.bottomRows<3>() = inverse;
    w.row(0) = -inverse.colwise().sum();
    volume = dm.determinant() / 6;
  }
  Mat3 F(const Vec12& x) const {
    return detail::deformation_gradient(w, x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9));
  }
};

TEST_P(Eigensystems, ElementHessianIsTheProjectedTangentAndTheGradientsDerivative) {
  const Lame p = model_parameters(GetParam(), lame_parameters(1e5, 0.3));
  const TestTet tet;
  for (const Mat3& A : sweep_to_inversion()) {
    Vec12 x;
    for (int a = 0; a < 4; ++a) x.segment<3>(3 * a) = A * tet.rest.col(a);
    const Mat3 F = tet.F(x);
    Mat3 V = Mat3::Identity(), P;
    Mat12 H;
    const double psi = detail::element_hessian(GetParam(), p, F, tet.w, tet.volume, &V, &P, &H);
    EXPECT_NEAR(psi, energy_density(GetParam(), p, F), 1e-12 * (std::abs(psi) + p.mu));
    // H = volume B^T D+ B, with D+ the projected tangent and (B^T m)_a = m w_a.
    Eigen::Matrix<double, 9, 12> B = Eigen::Matrix<double, 9, 12>::Zero();
    for (int a = 0; a < 4; ++a) {
      for (int i = 0; i < 3; ++i) {
        for (int l = 0; l < 3; ++l) B(3 * l + i, 3 * a + i) = tet.w(a, l);
      }
    }
    const Mat12 expected = tet.volume * B.transpose() * projected_stress_derivative(GetParam(), p, F) * B;
    EXPECT_LT((H - expected).norm(), 1e-7 * expected.norm()) << A;
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(H)).eigenvalues().minCoeff(), -1e-10 * H.norm());
    // The gradient is the derivative of volume * Psi, by central differences.
    const Vec12 g = detail::element_gradient(tet.w, tet.volume, P);
    const double step = 1e-6;
    for (int k = 0; k < 12; ++k) {
      Vec12 plus = x, minus = x;
      plus[k] += step;
      minus[k] -= step;
      const double numeric =
          tet.volume * (energy_density(GetParam(), p, tet.F(plus)) - energy_density(GetParam(), p, tet.F(minus))) / (2 * step);
      EXPECT_NEAR(g[k], numeric, 1e-5 * (std::abs(numeric) + p.mu * tet.volume)) << A << "\ncoordinate " << k;
    }
    // Where no eigenvalue is clamped, H is the gradient's derivative.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> tangent(Eigen::MatrixXd(stress_derivative(GetParam(), p, F)));
    if (tangent.eigenvalues().minCoeff() > 1e-6 * p.mu) {
      for (int k = 0; k < 12; ++k) {
        Vec12 plus = x, minus = x;
        plus[k] += step;
        minus[k] -= step;
        Mat3 Pp, Pm;
        detail::energy_and_stress(GetParam(), p, tet.F(plus), &Pp);
        detail::energy_and_stress(GetParam(), p, tet.F(minus), &Pm);
        const Vec12 column = (detail::element_gradient(tet.w, tet.volume, Pp) - detail::element_gradient(tet.w, tet.volume, Pm)) / (2 * step);
        EXPECT_LT((H.col(k) - column).norm(), 1e-5 * H.norm()) << A << "\ncoordinate " << k;
      }
    }
  }
}

TEST_P(Eigensystems, WarmStartedHessiansMatchColdOnes) {
  // Along a path toward inversion, each Hessian starting from the last V equals one from scratch.
  const Lame p = model_parameters(GetParam(), lame_parameters(1e5, 0.3));
  const TestTet tet;
  Mat3 V = Mat3::Identity();
  for (int s = 0; s <= 40; ++s) {
    const double t = s / 40.0;
    const Mat3 A = Eigen::AngleAxisd(t, Vec3(1, 2, 3).normalized()).toRotationMatrix() * Vec3(1 + 0.3 * t, 1 - 0.2 * t, 1 - 1.05 * t).asDiagonal();
    Vec12 x;
    for (int a = 0; a < 4; ++a) x.segment<3>(3 * a) = A * tet.rest.col(a);
    Mat3 cold_v = Mat3::Identity(), P;
    Mat12 warm, cold;
    detail::element_hessian(GetParam(), p, tet.F(x), tet.w, tet.volume, &V, &P, &warm);
    detail::element_hessian(GetParam(), p, tet.F(x), tet.w, tet.volume, &cold_v, &P, &cold);
    EXPECT_LT((warm - cold).norm(), 1e-7 * cold.norm()) << "t = " << t;
  }
}

TEST_P(Eigensystems, LaneKernelGivesTheScalarKernelsResults) {
  // Four elements at a time, as assembly runs them: generic ones, and lanes the fast path must
  // hand back (zero F, rank one, an indefinite scaling block under strong compression).
  const Lame p = model_parameters(GetParam(), lame_parameters(1e5, 0.3));
  const TestTet tet;
  std::vector<Mat3> cases = sweep_to_inversion();
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 0, 1).normalized()).toRotationMatrix();
  cases.push_back(Mat3::Zero());
  cases.push_back(R * Vec3(1.5, 0, 0).asDiagonal());
  cases.push_back(R * Vec3(0.2, 0.2, 0.2).asDiagonal());
  cases.push_back(R * Vec3(0.05, 0.9, -0.4).asDiagonal());
  detail::LaneMaterial material;
  material.corotated = GetParam() == Model::kCorotated;
  material.mu = p.mu;
  material.lambda = p.lambda;
  material.svd_tolerance = material.corotated ? detail::kSvdExact : detail::kSvdForHessian;
  material.rotation_fold = detail::kRotationFold;
  int handed_back = 0;
  for (std::size_t first = 0; first < cases.size(); first += detail::kLaneBatch) {
    const int count = static_cast<int>(std::min<std::size_t>(detail::kLaneBatch, cases.size() - first));
    detail::LaneBatch batch;
    for (int lane = 0; lane < count; ++lane) {
      for (int k = 0; k < 9; ++k) {
        batch.F[lane][k] = cases[first + lane](k / 3, k % 3);
        batch.V[lane][k] = k % 4 == 0 ? 1.0 : 0.0;
      }
      for (int k = 0; k < 12; ++k) batch.weights[lane][k] = tet.w(k / 3, k % 3);
      batch.volume[lane] = tet.volume;
    }
    detail::element_hessian_lanes(material, &batch, count);
    for (int lane = 0; lane < count; ++lane) {
      const Mat3& F = cases[first + lane];
      // Where the fast path cannot go: a zero or rank-one F, or a scaling block that is not
      // positive definite (its Cholesky factorisation fails).
      const detail::Svd3 svd = detail::svd3(F, detail::kSvdExact);
      const Mat3 scaling = detail::stress_eigensystem(GetParam(), p, svd).scaling;
      const bool expected_back = !(svd.sigma[1] > 1e-12 * svd.sigma[0]) || scaling.llt().info() != Eigen::Success;
      if (!detail::element_lanes_available()) {
        EXPECT_TRUE(batch.fallback[lane]);  // built or running without the kernel: all to scalar
        continue;
      }
      EXPECT_EQ(batch.fallback[lane], expected_back) << F;
      if (batch.fallback[lane]) {
        ++handed_back;
        continue;
      }
      ASSERT_TRUE(detail::element_lanes_available()) << "a lane was computed without the kernel";
      Mat3 V = Mat3::Identity(), P;
      detail::HessianFactor q;
      const double psi = detail::element_hessian_factor(GetParam(), p, F, tet.w, tet.volume, &V, &P, &q);
      EXPECT_NEAR(batch.energy[lane], psi, 1e-12 * (std::abs(psi) + p.mu)) << F;
      const Vec12 g = detail::element_gradient(tet.w, tet.volume, P);
      for (int k = 0; k < 12; ++k) EXPECT_NEAR(batch.gradient[lane][k], g[k], 1e-10 * (g.norm() + p.mu * tet.volume));
      double scale = 0, worst = 0;
      int b = 0;
      for (int r = 0; r < 4; ++r) {
        for (int c = r; c < 4; ++c, ++b) {
          double expected[9];
          detail::factor_block(q, r, c, expected);
          for (int k = 0; k < 9; ++k) {
            scale = std::max(scale, std::abs(expected[k]));
            worst = std::max(worst, std::abs(expected[k] - batch.blocks[lane][b][k]));
          }
        }
      }
      EXPECT_LT(worst, 1e-7 * scale) << F;
      // The warm start handed back: a rotation that diagonalises F^T F (up to the tolerance; the
      // signs of a pair of columns are free, as in any rotation-variant SVD).
      Mat3 lane_v;
      for (int k = 0; k < 9; ++k) lane_v(k % 3, k / 3) = batch.V[lane][k];  // column-major
      EXPECT_LT((lane_v.transpose() * lane_v - Mat3::Identity()).norm(), 1e-13);
      EXPECT_NEAR(lane_v.determinant(), 1, 1e-13);
      Mat3 d = lane_v.transpose() * F.transpose() * F * lane_v;
      const double diagonal = d.diagonal().norm();
      d.diagonal().setZero();
      EXPECT_LT(d.norm(), 1e-6 * diagonal) << F;
    }
  }
  // The zero and the rank-one matrix at least went to the scalar kernel.
  if (detail::element_lanes_available()) {
    EXPECT_GE(handed_back, 2);
  }
}

INSTANTIATE_TEST_SUITE_P(BothModels, Eigensystems, ::testing::Values(Model::kCorotated, Model::kStableNeoHookean));

TEST(StableNeoHookean, TangentIsTheClosedForm) {
  // Smith et al. 2018 give dP/dF directly: mu (1 - 1/(I_C + 1)) I + 2 mu / (I_C + 1)^2 f f^T +
  // lambda g g^T + lambda (J - alpha) d^2J/dF^2, with f = vec F, g = vec cof F. The eigensystem
  // must add up to it.
  const Lame p = model_parameters(Model::kStableNeoHookean, lame_parameters(2e5, 0.4));
  const double alpha = 1 + 0.75 * p.mu / p.lambda;
  const auto cross = [](const Vec3& v) {
    Mat3 m;
    m << 0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0;
    return m;
  };
  for (const Mat3& F : sweep_to_inversion()) {
    Mat3 cof;
    cof.col(0) = F.col(1).cross(F.col(2));
    cof.col(1) = F.col(2).cross(F.col(0));
    cof.col(2) = F.col(0).cross(F.col(1));
    Mat9 hj = Mat9::Zero();
    hj.block<3, 3>(0, 3) = -cross(F.col(2));
    hj.block<3, 3>(0, 6) = cross(F.col(1));
    hj.block<3, 3>(3, 0) = cross(F.col(2));
    hj.block<3, 3>(3, 6) = -cross(F.col(0));
    hj.block<3, 3>(6, 0) = -cross(F.col(1));
    hj.block<3, 3>(6, 3) = cross(F.col(0));
    const Eigen::Map<const Eigen::Matrix<double, 9, 1>> f(F.data()), g(cof.data());
    const double ic = F.squaredNorm();
    const Mat9 closed = p.mu * (1 - 1 / (ic + 1)) * Mat9::Identity() + (2 * p.mu / ((ic + 1) * (ic + 1))) * f * f.transpose() +
                        p.lambda * g * g.transpose() + p.lambda * (F.determinant() - alpha) * hj;
    EXPECT_LT((stress_derivative(Model::kStableNeoHookean, p, F) - closed).norm(), 1e-10 * closed.norm()) << F;
  }
}

}  // namespace
}  // namespace tetcut::sim
