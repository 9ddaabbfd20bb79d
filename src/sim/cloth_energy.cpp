#include "sim/cloth_energy.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace tetcut::sim::detail {

MembraneElement make_membrane(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, double fraction) {
  Eigen::Matrix2d dm;
  dm.col(0) = b - a;
  dm.col(1) = c - a;
  const Eigen::Matrix2d inverse = dm.inverse();
  MembraneElement e;
  // F = Ds Dm^-1, Ds = [x1 - x0, x2 - x0]: x1 enters with row 0 of Dm^-1, x2 with row 1.
  e.shape[1] = inverse.row(0).transpose();
  e.shape[2] = inverse.row(1).transpose();
  e.shape[0] = -(e.shape[1] + e.shape[2]);
  e.area = 0.5 * dm.determinant() * fraction;
  return e;
}

double membrane_energy(const MembraneElement& e, double mu, double lambda, const std::array<Vec3, 3>& x, Vec9* gradient,
                       Mat9* hessian, bool project) {
  Eigen::Matrix<double, 3, 2> f = Eigen::Matrix<double, 3, 2>::Zero();
  for (int a = 0; a < 3; ++a) f += x[a] * e.shape[a].transpose();
  const Eigen::Matrix2d strain = 0.5 * (f.transpose() * f - Eigen::Matrix2d::Identity());
  const double trace = strain.trace();
  const double psi = mu * strain.squaredNorm() + 0.5 * lambda * trace * trace;
  const Eigen::Matrix2d stress = 2 * mu * strain + lambda * trace * Eigen::Matrix2d::Identity();  // S
  if (gradient != nullptr) {
    const Eigen::Matrix<double, 3, 2> p = f * stress;  // first Piola-Kirchhoff, dpsi/dF
    for (int a = 0; a < 3; ++a) gradient->segment<3>(3 * a) += e.area * p * e.shape[a];
  }
  if (hessian != nullptr) {
    // d2psi/dF2 column by column: dP = dF S + F dS, dS = 2 mu dE + lambda tr(dE) I,
    // dE = (dF^T F + F^T dF) / 2. F is indexed (i, j) -> 3 j + i.
    Eigen::Matrix<double, 6, 6> c;
    for (int col = 0; col < 6; ++col) {
      Eigen::Matrix<double, 3, 2> df = Eigen::Matrix<double, 3, 2>::Zero();
      df(col % 3, col / 3) = 1;
      const Eigen::Matrix2d de = 0.5 * (df.transpose() * f + f.transpose() * df);
      const Eigen::Matrix2d ds = 2 * mu * de + lambda * de.trace() * Eigen::Matrix2d::Identity();
      const Eigen::Matrix<double, 3, 2> dp = df * stress + f * ds;
      for (int row = 0; row < 6; ++row) c(row, col) = dp(row % 3, row / 3);
    }
    // Projected in F's space: H = area J^T C J with J = dF/dx of full row rank, so H has C's
    // inertia (Sylvester) and clamping C's negative eigenvalues makes H positive semi-definite,
    // exactly where it already was. 6 x 6 instead of 9 x 9.
    if (project) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(c);
      c = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
    }
    // dF(i, j)/dx(a, k) = delta_ik shape[a](j), so block (a, b) of H is
    // area sum_{j, m} shape[a](j) shape[b](m) C[(., j), (., m)].
    Mat9 h;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
        for (int j = 0; j < 2; ++j) {
          for (int m = 0; m < 2; ++m) block += e.shape[a][j] * e.shape[b][m] * c.block<3, 3>(3 * j, 3 * m);
        }
        h.block<3, 3>(3 * a, 3 * b) = e.area * block;
      }
    }
    *hessian += h;
  }
  return e.area * psi;
}

namespace {
double signed_area(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const Eigen::Vector2d u = b - a, v = c - a;
  return 0.5 * (u.x() * v.y() - u.y() * v.x());
}
}  // namespace

Hinge make_hinge(const std::array<Index, 4>& nodes, const std::array<Eigen::Vector2d, 4>& rest, double bending_stiffness) {
  Hinge h;
  h.nodes = nodes;
  h.k = {signed_area(rest[1], rest[2], rest[3]), -signed_area(rest[0], rest[2], rest[3]),
         signed_area(rest[0], rest[1], rest[3]), -signed_area(rest[0], rest[1], rest[2])};
  const double a1 = std::abs(h.k[3]), a2 = std::abs(h.k[2]);  // the wings' triangles (0, 1, 2) and (0, 1, 3)
  const double edge2 = (rest[1] - rest[0]).squaredNorm();
  h.weight = 3 * bending_stiffness * edge2 * edge2 / (4 * a1 * a1 * a2 * a2 * (a1 + a2));
  return h;
}

double hinge_energy(const Hinge& h, const std::array<Vec3, 4>& x, Eigen::Matrix<double, 12, 1>* gradient) {
  Vec3 b = Vec3::Zero();
  for (int i = 0; i < 4; ++i) b += h.k[i] * x[i];
  if (gradient != nullptr) {
    for (int i = 0; i < 4; ++i) gradient->segment<3>(3 * i) += 2 * h.weight * h.k[i] * b;
  }
  return h.weight * b.squaredNorm();
}

}  // namespace tetcut::sim::detail
