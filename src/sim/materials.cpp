// Hyperelastic energy densities, stresses and stress derivatives. Matrices in 9 x 9 form act on
// vec(F), which stacks F's columns.

#include <tetcut/error.hpp>
#include <tetcut/sim.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include <cmath>
#include <string>

namespace tetcut::sim {
namespace {

Mat3 cross_matrix(const Vec3& v) {
  Mat3 m;
  m << 0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0;
  return m;
}

Eigen::Matrix<double, 9, 1> vec(const Mat3& m) { return Eigen::Map<const Eigen::Matrix<double, 9, 1>>(m.data()); }

// dJ/dF: the cofactor matrix, columns f1 x f2, f2 x f0, f0 x f1.
Mat3 cofactor(const Mat3& F) {
  Mat3 c;
  c.col(0) = F.col(1).cross(F.col(2));
  c.col(1) = F.col(2).cross(F.col(0));
  c.col(2) = F.col(0).cross(F.col(1));
  return c;
}

// d^2 J / dF^2: block (a, b) is d(dJ/df_a)/df_b, a cross-product matrix of the third column.
Mat9 determinant_hessian(const Mat3& F) {
  Mat9 h = Mat9::Zero();
  const Mat3 x0 = cross_matrix(F.col(0)), x1 = cross_matrix(F.col(1)), x2 = cross_matrix(F.col(2));
  h.block<3, 3>(0, 3) = -x2;
  h.block<3, 3>(0, 6) = x1;
  h.block<3, 3>(3, 0) = x2;
  h.block<3, 3>(3, 6) = -x0;
  h.block<3, 3>(6, 0) = -x1;
  h.block<3, 3>(6, 3) = x0;
  return h;
}

// Polar decomposition F = R S with R a rotation (det +1); S is symmetric, indefinite when F is
// inverted.
void polar(const Mat3& F, Mat3* R, Mat3* S) {
  Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU(), V = svd.matrixV();
  Vec3 sigma = svd.singularValues();
  if (U.determinant() < 0) {
    U.col(2) *= -1;
    sigma[2] *= -1;
  }
  if (V.determinant() < 0) {
    V.col(2) *= -1;
    sigma[2] *= -1;
  }
  *R = U * V.transpose();
  *S = V * sigma.asDiagonal() * V.transpose();
}

// dR/dF as a 9 x 9 matrix. With dR = R [w]x, the skew part of R^T dF gives
// (tr(S) I - S) w = axial(R^T dF - dF^T R); where tr(S) I - S is singular (two singular values
// summing to zero) R does not vary smoothly, and that direction is dropped.
Mat9 rotation_derivative(const Mat3& R, const Mat3& S) {
  const Mat3 G = S.trace() * Mat3::Identity() - S;
  const Eigen::CompleteOrthogonalDecomposition<Mat3> solve(G);
  Mat9 d;
  for (int k = 0; k < 9; ++k) {
    Mat3 dF = Mat3::Zero();
    dF(k % 3, k / 3) = 1;
    const Mat3 A = R.transpose() * dF;
    const Vec3 w = solve.solve(Vec3(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1)));
    d.col(k) = vec(R * cross_matrix(w));
  }
  return d;
}

}  // namespace

Lame lame_parameters(double youngs_modulus, double poissons_ratio) {
  if (!(youngs_modulus > 0) || !std::isfinite(youngs_modulus)) {
    throw Error(ErrorKind::kInvalidArgument, "Young's modulus must be a positive number");
  }
  if (!(poissons_ratio > -1 && poissons_ratio < 0.5)) {
    throw Error(ErrorKind::kInvalidArgument, "Poisson's ratio must lie strictly between -1 and 0.5");
  }
  const double E = youngs_modulus, nu = poissons_ratio;
  return {E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))};
}

Lame model_parameters(Model model, const Lame& lame) {
  if (model == Model::kStableNeoHookean) return {4.0 / 3.0 * lame.mu, lame.lambda + 5.0 / 6.0 * lame.mu};
  return lame;
}

namespace {
// Stable Neo-Hookean's rest-stable offset: P(I) = 0.
double snh_alpha(const Lame& p) { return 1 + 0.75 * p.mu / p.lambda; }
}  // namespace

double energy_density(Model model, const Lame& p, const Mat3& F) {
  const double J = F.determinant();
  if (model == Model::kCorotated) {
    Mat3 R, S;
    polar(F, &R, &S);
    return p.mu * (F - R).squaredNorm() + 0.5 * p.lambda * (J - 1) * (J - 1);
  }
  const double ic = F.squaredNorm(), alpha = snh_alpha(p);
  // Shifted by its value at rest, so that the rest state has zero energy (gradients unchanged).
  const double at_rest = 0.5 * p.lambda * (1 - alpha) * (1 - alpha) - 0.5 * p.mu * std::log(4.0);
  return 0.5 * p.mu * (ic - 3) + 0.5 * p.lambda * (J - alpha) * (J - alpha) - 0.5 * p.mu * std::log(ic + 1) - at_rest;
}

Mat3 first_piola(Model model, const Lame& p, const Mat3& F) {
  const double J = F.determinant();
  if (model == Model::kCorotated) {
    Mat3 R, S;
    polar(F, &R, &S);
    return 2 * p.mu * (F - R) + p.lambda * (J - 1) * cofactor(F);
  }
  const double ic = F.squaredNorm();
  return p.mu * (1 - 1 / (ic + 1)) * F + p.lambda * (J - snh_alpha(p)) * cofactor(F);
}

Mat9 stress_derivative(Model model, const Lame& p, const Mat3& F) {
  const double J = F.determinant();
  const Eigen::Matrix<double, 9, 1> g = vec(cofactor(F));
  if (model == Model::kCorotated) {
    Mat3 R, S;
    polar(F, &R, &S);
    return 2 * p.mu * (Mat9::Identity() - rotation_derivative(R, S)) + p.lambda * g * g.transpose() +
           p.lambda * (J - 1) * determinant_hessian(F);
  }
  const double ic = F.squaredNorm();
  const Eigen::Matrix<double, 9, 1> f = vec(F);
  return p.mu * (1 - 1 / (ic + 1)) * Mat9::Identity() + (2 * p.mu / ((ic + 1) * (ic + 1))) * f * f.transpose() +
         p.lambda * g * g.transpose() + p.lambda * (J - snh_alpha(p)) * determinant_hessian(F);
}

Mat9 projected_stress_derivative(Model model, const Lame& p, const Mat3& F) {
  const Mat9 d = stress_derivative(model, p, F);
  const Eigen::SelfAdjointEigenSolver<Mat9> eigen(0.5 * (d + d.transpose()));
  const Eigen::Matrix<double, 9, 1> clamped = eigen.eigenvalues().cwiseMax(0.0);
  return eigen.eigenvectors() * clamped.asDiagonal() * eigen.eigenvectors().transpose();
}

}  // namespace tetcut::sim
