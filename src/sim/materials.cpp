// The public energy, stress and stress-derivative functions, over the closed forms and analytic
// eigensystems of sim/elasticity. Matrices in 9 x 9 form act on vec(F), which stacks F's columns.

#include <tetcut/error.hpp>
#include <tetcut/sim.hpp>

#include "sim/elasticity.hpp"

#include <cmath>
#include <numbers>

namespace tetcut::sim {
namespace {

using detail::Vec9;

Vec9 vec(const Mat3& m) { return Eigen::Map<const Vec9>(m.data()); }

// The eigenmatrices of dP/dF at F with their eigenvalues, in the order twist k, flip k (k = 0..2),
// then the three scaling directions along the scaling block's eigenvectors.
void eigenpairs(Model model, const Lame& p, const Mat3& F, Eigen::Matrix<double, 9, 9>* vectors, Vec9* values) {
  const detail::Svd3 svd = detail::svd3(F, detail::kSvdExact);
  const detail::StressEigensystem e = detail::stress_eigensystem(model, p, svd);
  constexpr int pairs[3][2] = {{1, 2}, {0, 2}, {0, 1}};
  for (int k = 0; k < 3; ++k) {
    const auto [i, j] = pairs[k];
    const Mat3 a = svd.U.col(i) * svd.V.col(j).transpose(), b = svd.U.col(j) * svd.V.col(i).transpose();
    vectors->col(2 * k) = vec(a - b) / std::numbers::sqrt2;
    vectors->col(2 * k + 1) = vec(a + b) / std::numbers::sqrt2;
    (*values)[2 * k] = e.twist[k];
    (*values)[2 * k + 1] = e.flip[k];
  }
  Mat3 directions = Mat3::Identity();
  Vec3 scaling;
  detail::symmetric_eigen3(e.scaling, detail::kSvdExact, &directions, &scaling);
  for (int m = 0; m < 3; ++m) {
    vectors->col(6 + m) = vec(svd.U * directions.col(m).asDiagonal() * svd.V.transpose());
    (*values)[6 + m] = scaling[m];
  }
}

}  // namespace

Lame lame_parameters(double youngs_modulus, double poissons_ratio) {
  if (!(youngs_modulus > 0) || !std::isfinite(youngs_modulus)) {
    throw Error(ErrorKind::kInvalidArgument, "Young's modulus must be a positive number");
  }
  if (!valid_poissons_ratio(poissons_ratio)) {
    throw Error(ErrorKind::kInvalidArgument, "Poisson's ratio must lie strictly between -1 and 0.5");
  }
  const double E = youngs_modulus, nu = poissons_ratio;
  return {E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))};
}

Lame model_parameters(Model model, const Lame& lame) {
  if (model == Model::kStableNeoHookean) return {4.0 / 3.0 * lame.mu, lame.lambda + 5.0 / 6.0 * lame.mu};
  return lame;
}

double energy_density(Model model, const Lame& p, const Mat3& F) { return detail::energy_and_stress(model, p, F, nullptr); }

Mat3 first_piola(Model model, const Lame& p, const Mat3& F) {
  Mat3 P;
  detail::energy_and_stress(model, p, F, &P);
  return P;
}

Mat9 stress_derivative(Model model, const Lame& p, const Mat3& F) {
  Mat9 vectors;
  Vec9 values;
  eigenpairs(model, p, F, &vectors, &values);
  return vectors * values.asDiagonal() * vectors.transpose();
}

Mat9 projected_stress_derivative(Model model, const Lame& p, const Mat3& F) {
  Mat9 vectors;
  Vec9 values;
  eigenpairs(model, p, F, &vectors, &values);
  return vectors * values.cwiseMax(0.0).asDiagonal() * vectors.transpose();
}

}  // namespace tetcut::sim
