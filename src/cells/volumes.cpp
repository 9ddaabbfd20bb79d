// Cell volumes: rounded, with an exact fallback for cells thinner than rounding.

#include "cells/cell_complex.hpp"

#include "mesh/local_index.hpp"
#include "util/broken.hpp"

#include <tetcut/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tetcut::cells {

using geometry::Plane;
using registry::OrientedPlane;

double CellComplex::cell_volume6(CellId cell, const Vec3& origin) const {
  // Floating-point sum with a bound on its error: rounded corners are off by at most `delta`
  // each, and every product rounds. A cell far smaller than that rounding (it happens: input
  // planes at 0.3 and 0.55 meet a mesh edge y = x + 0.25 in three points 1e-17 apart) would come
  // out with an arbitrary sign, so then the volume is summed exactly in rationals.
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  double sum = 0, bound = 0, largest = origin.cwiseAbs().maxCoeff();
  for (const FacetId f : cells_[cell].facets) {
    for (const Corner& corner : facets_[f].corners) largest = std::max(largest, registry_->position(corner.vertex).cwiseAbs().maxCoeff());
  }
  const double delta = 2 * registry::IntersectionRegistry::position_tolerance() * largest;
  for (const FacetId f : cells_[cell].facets) {
    const Facet& facet = facets_[f];
    const auto& corners = facet.corners;
    const double sign = facet.back == cell ? 1 : -1;  // stored order is outward for the back cell
    const Vec3 a = registry_->position(corners[0].vertex) - origin;
    for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
      const Vec3 b = registry_->position(corners[i].vertex) - origin;
      const Vec3 c = registry_->position(corners[i + 1].vertex) - origin;
      sum += sign * a.dot(b.cross(c));
      const double na = a.norm(), nb = b.norm(), nc = c.norm();
      bound += delta * (nb * nc + na * nc + na * nb) + 8 * kEps * (na * nb * nc + largest * (nb * nc + na * nc + na * nb));
    }
  }
  if (std::abs(sum) > bound) return sum;
  return exact_cell_volume6(cell);
}

double CellComplex::exact_cell_volume6(CellId cell) const {
  // With exact points the fan volumes add up to the cell's volume from any origin, so take the
  // coordinate origin: the fan triangle (a, b, c) gives det(Xa, Xb, Xc) / (Wa Wb Wc) over the
  // points' exact homogeneous coordinates. Summing those fractions as rationals costs a gcd per
  // operation; instead each is divided out in 2048-bit floating point (relative error below
  // 2^-2000 per term and per addition), which settles the sign unless the sum is within
  // 2^-1900 of the terms' magnitudes, and only then are the rationals summed.

  // The cell's distinct points, each converted once (no growth afterwards, so references hold).
  std::vector<VertexId> ids;
  for (const FacetId f : cells_[cell].facets) {
    for (const Corner& corner : facets_[f].corners) ids.push_back(corner.vertex);
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<geometry::ExactPoint> points;
  points.reserve(ids.size());
  for (const VertexId v : ids) points.push_back(registry_->exact_homogeneous(v));
  const auto exact = [&](VertexId v) -> const geometry::ExactPoint& {
    return points[static_cast<std::size_t>(std::lower_bound(ids.begin(), ids.end(), v) - ids.begin())];
  };
  struct Term {
    mpz_class numerator, denominator;
  };
  std::vector<Term> terms;
  for (const FacetId f : cells_[cell].facets) {
    const Facet& facet = facets_[f];
    const auto& corners = facet.corners;
    for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
      const geometry::ExactPoint& a = exact(corners[0].vertex);
      const geometry::ExactPoint& b = exact(corners[i].vertex);
      const geometry::ExactPoint& c = exact(corners[i + 1].vertex);
      Term t;
      t.numerator = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
      if (facet.back != cell) t.numerator = -t.numerator;  // stored order is outward for the back cell
      t.denominator = a[3] * b[3] * c[3];
      terms.push_back(std::move(t));
    }
  }
  constexpr mp_bitcnt_t kBits = 2048;
  mpf_class sum(0, kBits), magnitude(0, kBits);
  for (const Term& t : terms) {
    mpf_class term(t.numerator, kBits);
    term /= mpf_class(t.denominator, kBits);
    sum += term;
    magnitude += abs(term);
  }
  mpf_class margin(magnitude, kBits);
  mpf_div_2exp(margin.get_mpf_t(), margin.get_mpf_t(), 1900);
  if (abs(sum) > margin) return sum.get_d();
  mpq_class rational = 0;
  for (const Term& t : terms) rational += mpq_class(t.numerator, t.denominator);  // canonicalised
  return rational.get_d();
}

}  // namespace tetcut::cells
