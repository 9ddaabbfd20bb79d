#include "sim/elasticity.hpp"

#include <cmath>
#include <numbers>

namespace tetcut::sim::detail {
namespace {

// Stable Neo-Hookean's rest-stable offset: P(I) = 0.
double snh_alpha(const Lame& p) { return 1 + 0.75 * p.mu / p.lambda; }

// dJ/dF: the cofactor matrix, columns f1 x f2, f2 x f0, f0 x f1.
Mat3 cofactor(const Mat3& F) {
  Mat3 c;
  c.col(0) = F.col(1).cross(F.col(2));
  c.col(1) = F.col(2).cross(F.col(0));
  c.col(2) = F.col(0).cross(F.col(1));
  return c;
}

// Axes (i, j) of the twist and flip about axis k.
constexpr int kPairs[3][2] = {{1, 2}, {0, 2}, {0, 1}};

}  // namespace

StressEigensystem stress_eigensystem(Model model, const Lame& p, const Svd3& svd) {
  const Vec3& s = svd.sigma;
  const double J = s[0] * s[1] * s[2];
  // dJ/dsigma_i: the product of the other two.
  const Vec3 g(s[1] * s[2], s[0] * s[2], s[0] * s[1]);
  StressEigensystem e;
  if (model == Model::kStableNeoHookean) {
    const double ic = s.squaredNorm();
    const double identity = p.mu * (1 - 1 / (ic + 1));  // 2 dPsi/dI_C
    const double volume = p.lambda * (J - snh_alpha(p));  // dPsi/dJ
    for (int k = 0; k < 3; ++k) {
      e.twist[k] = identity + volume * s[k];
      e.flip[k] = identity - volume * s[k];
    }
    e.scaling = identity * Mat3::Identity() + (2 * p.mu / ((ic + 1) * (ic + 1))) * s * s.transpose() + p.lambda * g * g.transpose();
    for (int k = 0; k < 3; ++k) {
      const auto [i, j] = kPairs[k];
      e.scaling(i, j) += volume * s[k];
      e.scaling(j, i) += volume * s[k];
    }
    return e;
  }
  const double volume = p.lambda * (J - 1);
  for (int k = 0; k < 3; ++k) {
    const auto [i, j] = kPairs[k];
    const double sum = s[i] + s[j];
    e.twist[k] = std::abs(sum) > kRotationFold ? 2 * p.mu - 4 * p.mu / sum + volume * s[k] : 0.0;
    e.flip[k] = 2 * p.mu - volume * s[k];
  }
  e.scaling = 2 * p.mu * Mat3::Identity() + p.lambda * g * g.transpose();
  for (int k = 0; k < 3; ++k) {
    const auto [i, j] = kPairs[k];
    e.scaling(i, j) += volume * s[k];
    e.scaling(j, i) += volume * s[k];
  }
  return e;
}

Mat3 positive_part_factor(const Mat3& a) {
  Mat3 c = Mat3::Zero();
  if (a(0, 0) > 0) {
    c(0, 0) = std::sqrt(a(0, 0));
    c(1, 0) = a(1, 0) / c(0, 0);
    c(2, 0) = a(2, 0) / c(0, 0);
    const double d1 = a(1, 1) - c(1, 0) * c(1, 0);
    if (d1 > 0) {
      c(1, 1) = std::sqrt(d1);
      c(2, 1) = (a(2, 1) - c(2, 0) * c(1, 0)) / c(1, 1);
      const double d2 = a(2, 2) - c(2, 0) * c(2, 0) - c(2, 1) * c(2, 1);
      if (d2 > 0) {
        c(2, 2) = std::sqrt(d2);
        return c;
      }
    }
  }
  Mat3 vectors = Mat3::Identity();
  Vec3 values;
  symmetric_eigen3(a, kSvdExact, &vectors, &values);
  return vectors * values.cwiseMax(0.0).cwiseSqrt().asDiagonal();
}

double energy_and_stress(Model model, const Lame& p, const Mat3& F, Mat3* stress, const Svd3* svd) {
  if (model == Model::kStableNeoHookean) {
    const double J = F.determinant(), ic = F.squaredNorm(), alpha = snh_alpha(p);
    if (stress) *stress = p.mu * (1 - 1 / (ic + 1)) * F + p.lambda * (J - alpha) * cofactor(F);
    // Shifted by its value at rest, so that the rest state has zero energy (gradients unchanged).
    const double at_rest = 0.5 * p.lambda * (1 - alpha) * (1 - alpha) - 0.5 * p.mu * std::log(4.0);
    return 0.5 * p.mu * (ic - 3) + 0.5 * p.lambda * (J - alpha) * (J - alpha) - 0.5 * p.mu * std::log(ic + 1) - at_rest;
  }
  const Svd3 own = svd ? Svd3{} : svd3(F, kSvdExact);
  const Svd3& d = svd ? *svd : own;
  const double J = d.sigma.prod();
  // |F - R|^2 with R = U V^T is |sigma - 1|^2.
  if (stress) *stress = 2 * p.mu * (F - d.U * d.V.transpose()) + p.lambda * (J - 1) * cofactor(F);
  return p.mu * (d.sigma - Vec3::Ones()).squaredNorm() + 0.5 * p.lambda * (J - 1) * (J - 1);
}

double element_hessian_factor(Model model, const Lame& p, const Mat3& F, const ShapeWeights& w, double volume, Mat3* v_guess,
                              Mat3* stress, HessianFactor* q) {
  // Corotated's energy needs the exact polar rotation; stable Neo-Hookean's only its Hessian.
  const Svd3 svd = svd3(F, model == Model::kCorotated ? kSvdExact : kSvdForHessian, v_guess);
  *v_guess = svd.V;
  const double energy = energy_and_stress(model, p, F, stress, &svd);
  const StressEigensystem e = stress_eigensystem(model, p, svd);
  const ShapeWeights w_frame = w * svd.V;  // row a: V^T w_a
  const Mat3& U = svd.U;
  // Twist and flip about axis k: U (e_i e_j^T -/+ e_j e_i^T) V^T / sqrt 2 maps w_a to
  // (u_i (V^T w_a)_j -/+ u_j (V^T w_a)_i) / sqrt 2.
  const double half_volume = 0.5 * volume;
  for (int k = 0; k < 3; ++k) {
    const auto [i, j] = kPairs[k];
    const double twist = std::sqrt(half_volume * std::max(e.twist[k], 0.0)), flip = std::sqrt(half_volume * std::max(e.flip[k], 0.0));
    for (int a = 0; a < 4; ++a) {
      for (int r = 0; r < 3; ++r) {
        const double along_i = w_frame(a, j) * U(r, i), along_j = w_frame(a, i) * U(r, j);
        (*q)(3 * a + r, 2 * k) = twist * (along_i - along_j);
        (*q)(3 * a + r, 2 * k + 1) = flip * (along_i + along_j);
      }
    }
  }
  // Scaling direction m: U diag(factor column m) V^T w_a = U (factor column m .* V^T w_a).
  const Mat3 factor = std::sqrt(volume) * positive_part_factor(e.scaling);
  for (int a = 0; a < 4; ++a) {
    const Mat3 scaled = factor.array().colwise() * w_frame.row(a).transpose().array();
    q->block<3, 3>(3 * a, 6) = U * scaled;
  }
  return energy;
}

double element_hessian(Model model, const Lame& p, const Mat3& F, const ShapeWeights& w, double volume, Mat3* v_guess,
                       Mat3* stress, Mat12* hessian) {
  HessianFactor q;
  const double energy = element_hessian_factor(model, p, F, w, volume, v_guess, stress, &q);
  hessian->noalias() = q.lazyProduct(q.transpose());
  return energy;
}

}  // namespace tetcut::sim::detail
