// Closest points by regions: a point's nearest point on a triangle lies in one of seven regions
// (three corners, three edges, the face), told apart by the signs of a few dot products; two
// segments' nearest points by the unconstrained line-line solution clamped to the parameter
// square, one parameter at a time. O(1) each.

#include "collision/proximity.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace tetcut::collision {
namespace {

Proximity finish(Proximity p, const std::array<Vec3, 4>& y) {
  p.r = Vec3::Zero();
  for (int k = 0; k < 4; ++k) p.r += p.w[k] * y[k];
  p.distance = p.r.norm();
  return p;
}

// Parameter t in [0, 1] of the point of segment (a, b) nearest p.
double nearest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double length2 = ab.squaredNorm();
  return length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
}

// The weights of r = p - q for q on triangle corners i, j (1-based corner slots of y) at
// q = (1 - t) y_i + t y_j, with t free when strictly inside the edge.
Proximity on_edge(int i, int j, double t) {
  Proximity p;
  p.w = {1, 0, 0, 0};
  p.w[i] = -(1 - t);
  p.w[j] = -t;
  if (t > 0 && t < 1) {
    p.free = 1;
    p.dw[0] = {0, 0, 0, 0};
    p.dw[0][i] = 1;
    p.dw[0][j] = -1;
  }
  return p;
}

// num / den for an edge parameter, 0 where the edge has no length (den = 0: two corners at one
// point, and num is then 0 too), so that a triangle with coincident corners gives its nearest
// remaining corner or edge, not 0 / 0.
double edge_parameter(double num, double den) { return den > 0 ? num / den : 0.0; }

Proximity on_corner(int i) {
  Proximity p;
  p.w = {1, 0, 0, 0};
  p.w[i] = -1;
  return p;
}

}  // namespace

Proximity point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const std::array<Vec3, 4> y{p, a, b, c};
  // Collinear or coincident corners: the nearest of the three edges (the regions below assume a
  // triangle with an area).
  const auto nearest_edge = [&] {
    Proximity best;
    best.distance = std::numeric_limits<double>::infinity();
    const std::array<std::array<int, 2>, 3> edges{{{1, 2}, {1, 3}, {2, 3}}};
    for (const auto& [i, j] : edges) {
      const Proximity candidate = finish(on_edge(i, j, nearest_on_segment(p, y[i], y[j])), y);
      if (candidate.distance < best.distance) best = candidate;
    }
    return best;
  };
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  if (!(ab.cross(ac).squaredNorm() > 0)) return nearest_edge();
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return finish(on_corner(1), y);
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return finish(on_corner(2), y);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return finish(on_edge(1, 2, edge_parameter(d1, d1 - d3)), y);
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return finish(on_corner(3), y);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return finish(on_edge(1, 3, edge_parameter(d2, d2 - d6)), y);
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return finish(on_edge(2, 3, edge_parameter(d4 - d3, (d4 - d3) + (d5 - d6))), y);
  const double denominator = va + vb + vc;  // (2 area)^2 up to rounding
  if (!(denominator > 0)) return nearest_edge();
  const double v = vb / denominator, w = vc / denominator;
  Proximity out;
  out.w = {1, -(1 - v - w), -v, -w};
  out.free = 2;
  out.dw[0] = {0, 1, -1, 0};
  out.dw[1] = {0, 1, 0, -1};
  return finish(out, y);
}

Proximity segment_segment(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  const std::array<Vec3, 4> y{a0, a1, b0, b1};
  const Vec3 da = a1 - a0, db = b1 - b0, r0 = a0 - b0;
  const double aa = da.squaredNorm(), bb = db.squaredNorm(), f = db.dot(r0);
  double s = 0, t = 0;
  if (aa <= 0 && bb <= 0) {
    // Two points.
  } else if (aa <= 0) {
    t = std::clamp(f / bb, 0.0, 1.0);
  } else {
    const double c = da.dot(r0);
    if (bb <= 0) {
      s = std::clamp(-c / aa, 0.0, 1.0);
    } else {
      const double ab = da.dot(db), denominator = aa * bb - ab * ab;
      // Parallel (denominator 0): any s; take 0 and the t it gives.
      s = denominator > 0 ? std::clamp((ab * f - c * bb) / denominator, 0.0, 1.0) : 0.0;
      t = (ab * s + f) / bb;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / aa, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((ab - c) / aa, 0.0, 1.0);
      }
    }
  }
  Proximity p;
  p.w = {1 - s, s, -(1 - t), -t};
  if (s > 0 && s < 1) p.dw[p.free++] = {-1, 1, 0, 0};
  if (t > 0 && t < 1) p.dw[p.free++] = {0, 0, 1, -1};
  return finish(p, y);
}

Vec12 distance_gradient(const Proximity& p) {
  Vec12 g;
  const Vec3 n = p.r / p.distance;
  for (int k = 0; k < 4; ++k) g.segment<3>(3 * k) = p.w[k] * n;
  return g;
}

Mat12 distance_hessian(const Proximity& p, const std::array<Vec3, 4>& y) {
  Mat12 D2 = Mat12::Zero();
  for (int k = 0; k < 4; ++k) {
    for (int l = 0; l < 4; ++l) D2.block<3, 3>(3 * k, 3 * l) = 2 * p.w[k] * p.w[l] * Eigen::Matrix3d::Identity();
  }
  if (p.free > 0) {
    Eigen::Matrix<double, 3, Eigen::Dynamic> E(3, p.free);
    Eigen::Matrix<double, 12, Eigen::Dynamic> G(12, p.free);
    for (int j = 0; j < p.free; ++j) {
      Vec3 e = Vec3::Zero();
      for (int k = 0; k < 4; ++k) e += p.dw[j][k] * y[k];
      E.col(j) = e;
    }
    for (int j = 0; j < p.free; ++j) {
      for (int k = 0; k < 4; ++k) G.block<3, 1>(3 * k, j) = p.dw[j][k] * p.r + p.w[k] * E.col(j);
    }
    const Eigen::MatrixXd EtE = E.transpose() * E;
    D2 -= 2 * G * EtE.inverse() * G.transpose();
  }
  Vec12 D1;
  for (int k = 0; k < 4; ++k) D1.segment<3>(3 * k) = 2 * p.w[k] * p.r;
  const double d = p.distance;
  return D2 / (2 * d) - D1 * D1.transpose() / (4 * d * d * d);
}

}  // namespace tetcut::collision
