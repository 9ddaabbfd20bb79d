// The element loops: elastic energy, gradient and projected Hessian of every tet copy, assembled
// into node vectors and the block pattern. Elements go in a spatial order, in clusters; clusters
// are coloured (no two of a colour share a node), a colour's clusters run on all threads and each
// cluster's elements in order on one, so that threads never write the same entry, the sums come
// out the same on any number of threads, and a cluster's writes stay in cache.

#include "sim/simulator_state.hpp"

#include "sim/element_batch.hpp"

#include <algorithm>
#include <cstdint>

namespace tetcut::sim {
namespace {

// Elements per chunk of the energy sum.
constexpr Index kElementChunk = 128;

// Adds a tet's 12-vector into a 3-per-node array.
void scatter(const std::array<Index, 4>& nodes, const detail::Vec12& g, double* out) {
  for (int a = 0; a < 4; ++a) {
    double* o = out + 3 * static_cast<std::size_t>(nodes[a]);
    o[0] += g[3 * a];
    o[1] += g[3 * a + 1];
    o[2] += g[3 * a + 2];
  }
}

}  // namespace

double SimulatorState::energy_at(Index pos, const Mat3& F, Mat3* stress) const {
  if (material.model != Model::kCorotated) return detail::energy_and_stress(material.model, parameters, F, stress);
  // Corotated needs the polar rotation: its SVD starts from the element's last V (read only, so
  // trial points do not move the warm start).
  const detail::Svd3 svd = detail::svd3(F, detail::kSvdExact, &ordered_v[pos]);
  return detail::energy_and_stress(material.model, parameters, F, stress, &svd);
}

double SimulatorState::elastic_energy(const Points& at) const {
  return detail::sum_chunks(static_cast<Index>(elements.size()), kElementChunk, &partial, [&](Index begin, Index end) {
    double sum = 0;
    for (Index i = begin; i < end; ++i) {
      const Element& e = ordered[i].element;
      sum += e.volume * energy_at(i, detail::deformation_gradient(e.weights, at.data(), e.nodes), nullptr);
    }
    return sum;
  });
}

namespace {

// Runs body(begin, end) over the elements element_order[begin .. end) of each cluster, colour
// by colour, the clusters of a colour on all threads; returns the total of the energies it
// returns in (colour, cluster) order.
template <typename Body>
double by_color(const SimulatorState& s, const Body& body) {
  const Index count = static_cast<Index>(s.element_order.size());
  double total = 0;
  for (std::size_t c = 0; c + 1 < s.color_start.size(); ++c) {
    const Index first = s.color_start[c];
    total += detail::sum_chunks(s.color_start[c + 1] - first, 1, &s.partial, [&](Index begin, Index end) {
      double sum = 0;
      for (Index i = begin; i < end; ++i) {
        const Index k = s.color_clusters[first + i];
        sum += body(k * SimulatorState::kCluster, std::min(count, (k + 1) * SimulatorState::kCluster));
      }
      return sum;
    });
  }
  return total;
}

}  // namespace

double SimulatorState::elastic_gradient(const Points& at, std::vector<double>* gradient) const {
  // Four at a time in the lane kernel, as for the Hessian (corotated's stress needs an SVD per
  // element; stable Neo-Hookean's none, and the kernel skips it).
  const bool lanes = detail::element_lanes_available();
  const detail::LaneMaterial lane_material = lane_parameters();
  return by_color(*this, [&](Index begin, Index end) {
    double energy = 0;
    if (!lanes) {
      for (Index i = begin; i < end; ++i) {
        const Element& e = ordered[i].element;
        Mat3 P;
        const double psi = energy_at(i, detail::deformation_gradient(e.weights, at.data(), e.nodes), &P);
        scatter(e.nodes, detail::element_gradient(e.weights, e.volume, P), gradient->data());
        energy += e.volume * psi;
      }
      return energy;
    }
    detail::LaneBatch batch;
    batch.with_hessian = false;
    for (Index i = begin; i < end; i += detail::kLaneBatch) {
      const int group = static_cast<int>(std::min<Index>(detail::kLaneBatch, end - i));
      pack(at, i, group, &batch);
      detail::element_hessian_lanes(lane_material, &batch, group);
      for (int lane = 0; lane < group; ++lane) {
        const Element& e = ordered[i + lane].element;
        if (batch.fallback[lane]) {
          Mat3 F, P;
          for (int k = 0; k < 9; ++k) F(k / 3, k % 3) = batch.F[lane][k];
          batch.energy[lane] = energy_at(i + lane, F, &P);
          const detail::Vec12 g = detail::element_gradient(e.weights, e.volume, P);
          for (int k = 0; k < 12; ++k) batch.gradient[lane][k] = g[k];
        }
        energy += e.volume * batch.energy[lane];
        scatter(e.nodes, Eigen::Map<const detail::Vec12>(batch.gradient[lane]), gradient->data());
      }
    }
    return energy;
  });
}

detail::LaneMaterial SimulatorState::lane_parameters() const {
  detail::LaneMaterial m;
  m.corotated = material.model == Model::kCorotated;
  m.mu = parameters.mu;
  m.lambda = parameters.lambda;
  m.svd_tolerance = m.corotated ? detail::kSvdExact : detail::kSvdForHessian;
  m.rotation_fold = detail::kRotationFold;
  return m;
}

void SimulatorState::pack(const Points& at, Index first, int count, detail::LaneBatch* batch) const {
  for (int lane = 0; lane < count; ++lane) {
    const Element& el = ordered[first + lane].element;
    // The weights and V are stored as the kernel reads them; F = sum_a x_a w_a^T straight into it.
    const double* w = el.weights.data();
    std::copy(w, w + 12, batch->weights[lane]);
    std::copy(ordered_v[first + lane].data(), ordered_v[first + lane].data() + 9, batch->V[lane]);
    double* F = batch->F[lane];
    std::fill(F, F + 9, 0.0);
    for (int a = 0; a < 4; ++a) {
      const double* node = at.data() + 3 * static_cast<std::size_t>(el.nodes[a]);
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) F[3 * r + c] += node[r] * w[3 * a + c];
      }
    }
    batch->volume[lane] = el.volume;
    batch->fallback[lane] = true;
  }
}

namespace {

// Adds a tet's 10 distinct Hessian blocks (row-major, in LaneBatch order) into the pattern; each
// off-diagonal block also goes, transposed, to its mirror.
void scatter_blocks(const std::array<Index, 16>& slots, const double (&blocks)[10][9], detail::BlockSparseMatrix* hessian) {
  int b = 0;
  for (int r = 0; r < 4; ++r) {
    for (int c = r; c < 4; ++c, ++b) {
      hessian->add(slots[4 * r + c], blocks[b]);
      if (c != r) hessian->add_transposed(slots[4 * c + r], blocks[b]);
    }
  }
}

}  // namespace

double SimulatorState::assemble_hessian(const Points& at, std::vector<double>* gradient) {
  hessian.set_zero();
  const detail::LaneMaterial lane_material = lane_parameters();
  const bool lanes = detail::element_lanes_available();
  return by_color(*this, [&](Index begin, Index end) {
    double energy = 0;
    detail::LaneBatch batch;
    // Elements kLaneBatch at a time (the last group of a cluster may be short).
    for (Index i = begin; i < end; i += detail::kLaneBatch) {
      const int group = static_cast<int>(std::min<Index>(detail::kLaneBatch, end - i));
      pack(at, i, group, &batch);
      // The 64 blocks these elements add into: fetched while the kernel computes (the adds were
      // waiting on these cache misses at 100k tets).
      for (int lane = 0; lane < group; ++lane) {
        for (const Index slot : ordered[i + lane].slots) {
          const char* block = static_cast<const char*>(hessian.address(slot));
          __builtin_prefetch(block, 1);
          __builtin_prefetch(block + 64, 1);
        }
      }
      if (lanes) detail::element_hessian_lanes(lane_material, &batch, group);
      for (int lane = 0; lane < group; ++lane) {
        const OrderedElement& o = ordered[i + lane];
        const Element& el = o.element;
        Mat3& V = ordered_v[i + lane];
        if (batch.fallback[lane]) {
          // The scalar kernel: no lane kernel here, or a lane it cannot take.
          Mat3 F, P;
          for (int k = 0; k < 9; ++k) F(k / 3, k % 3) = batch.F[lane][k];
          detail::HessianFactor q;
          batch.energy[lane] = detail::element_hessian_factor(material.model, parameters, F, el.weights, el.volume, &V, &P, &q);
          const detail::Vec12 g = detail::element_gradient(el.weights, el.volume, P);
          for (int k = 0; k < 12; ++k) batch.gradient[lane][k] = g[k];
          int b = 0;
          for (int r = 0; r < 4; ++r) {
            for (int col = r; col < 4; ++col) detail::factor_block(q, r, col, batch.blocks[lane][b++]);
          }
        } else {
          std::copy(batch.V[lane], batch.V[lane] + 9, V.data());
        }
        energy += el.volume * batch.energy[lane];
        scatter(el.nodes, Eigen::Map<const detail::Vec12>(batch.gradient[lane]), gradient->data());
        scatter_blocks(o.slots, batch.blocks[lane], &hessian);
      }
    }
    return energy;
  });
}

}  // namespace tetcut::sim
