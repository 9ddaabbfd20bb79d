// The element loops: elastic energy, gradient and projected Hessian of every tet copy, assembled
// into node vectors and the block pattern. Elements go in a spatial order, in clusters; clusters
// are coloured (no two of a colour share a node), a colour's clusters run on all threads and each
// cluster's elements in order on one, so that threads never write the same entry, the sums come
// out the same on any number of threads, and a cluster's writes stay in cache.

#include "sim/simulator_state.hpp"

#include "sim/element_batch.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>

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

void SimulatorState::order_elements(const Points& rest) {
  // Morton order of the rest centroids: 21 bits per axis over the bounding box, interleaved.
  const Index count = static_cast<Index>(elements.size());
  Vec3 low = Vec3::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (Index node = 0; node < rest.rows(); ++node) {
    low = low.cwiseMin(rest.row(node).transpose());
    high = high.cwiseMax(rest.row(node).transpose());
  }
  const Vec3 extent = (high - low).cwiseMax(std::numeric_limits<double>::min());
  const auto spread = [](std::uint64_t bits) {  // the 21 low bits to every third bit
    bits &= 0x1fffff;
    bits = (bits | bits << 32) & 0x1f00000000ffffULL;
    bits = (bits | bits << 16) & 0x1f0000ff0000ffULL;
    bits = (bits | bits << 8) & 0x100f00f00f00f00fULL;
    bits = (bits | bits << 4) & 0x10c30c30c30c30c3ULL;
    bits = (bits | bits << 2) & 0x1249249249249249ULL;
    return bits;
  };
  std::vector<std::pair<std::uint64_t, Index>> keys(static_cast<std::size_t>(count));
  for (Index e = 0; e < count; ++e) {
    Vec3 centroid = Vec3::Zero();
    for (const Index node : elements[e].nodes) centroid += rest.row(node).transpose() / 4;
    const Vec3 unit = ((centroid - low).cwiseQuotient(extent)).cwiseMax(0.0).cwiseMin(1.0);
    std::uint64_t key = 0;
    for (int k = 0; k < 3; ++k) key |= spread(static_cast<std::uint64_t>(unit[k] * 2097151.0)) << k;
    keys[e] = {key, e};
  }
  std::sort(keys.begin(), keys.end());
  element_order.resize(static_cast<std::size_t>(count));
  for (Index i = 0; i < count; ++i) element_order[i] = keys[i].second;
}

void SimulatorState::order_new_copies(Index first_new, std::span<const Index> source) {
  // Each new copy right after its source: a copy is where its source is.
  std::vector<Index> copies_start(elements.size() + 1, 0), copies(source.size());
  for (const Index from : source) ++copies_start[from + 1];
  for (std::size_t e = 0; e < elements.size(); ++e) copies_start[e + 1] += copies_start[e];
  std::vector<Index> next(copies_start.begin(), copies_start.end() - 1);
  for (Index i = 0; i < static_cast<Index>(source.size()); ++i) copies[next[source[i]]++] = first_new + i;
  std::vector<Index> order;
  order.reserve(elements.size());
  // A new copy may itself be a source (split again in the same batch): follow the chain.
  const auto place = [&](Index e, const auto& self) -> void {
    order.push_back(e);
    for (Index k = copies_start[e]; k < copies_start[e + 1]; ++k) self(copies[k], self);
  };
  for (const Index e : element_order) place(e, place);
  element_order.swap(order);
}

void SimulatorState::assign_colors() {
  const Index n = num_nodes(), count = static_cast<Index>(elements.size());
  const Index clusters = (count + kCluster - 1) / kCluster;
  // The nodes of the elements of cluster k (positions k kCluster ..).
  const auto cluster_elements = [&](Index k) {
    return std::span<const OrderedElement>(ordered.data() + k * kCluster, static_cast<std::size_t>(std::min(kCluster, count - k * kCluster)));
  };
  std::vector<std::uint64_t> used(static_cast<std::size_t>(n), 0);
  std::vector<Index> color(static_cast<std::size_t>(clusters));
  // Past 64 colours: the colours of the clusters already coloured around each node, found
  // through the node-to-cluster incidence (built only if needed: a node in very many copies).
  std::vector<Index> around_start, around, forbidden;
  Index colors = 0;
  for (Index k = 0; k < clusters; ++k) {
    std::uint64_t mask = 0;
    for (const OrderedElement& e : cluster_elements(k)) {
      for (const Index node : e.element.nodes) mask |= used[node];
    }
    Index c;
    if (~mask != 0) {
      c = std::countr_zero(~mask);
    } else {
      if (around_start.empty()) {
        around_start.assign(static_cast<std::size_t>(n) + 1, 0);
        for (Index j = 0; j < clusters; ++j) {
          for (const OrderedElement& e : cluster_elements(j)) {
            for (const Index node : e.element.nodes) ++around_start[node + 1];
          }
        }
        for (Index node = 0; node < n; ++node) around_start[node + 1] += around_start[node];
        around.resize(static_cast<std::size_t>(around_start.back()));
        std::vector<Index> next(around_start.begin(), around_start.end() - 1);
        for (Index j = 0; j < clusters; ++j) {
          for (const OrderedElement& e : cluster_elements(j)) {
            for (const Index node : e.element.nodes) around[next[node]++] = j;
          }
        }
      }
      forbidden.assign(static_cast<std::size_t>(colors) + 1, 0);
      for (const OrderedElement& e : cluster_elements(k)) {
        for (const Index node : e.element.nodes) {
          for (Index i = around_start[node]; i < around_start[node + 1]; ++i) {
            if (around[i] < k) forbidden[color[around[i]]] = 1;
          }
        }
      }
      c = 64;
      while (forbidden[c]) ++c;
    }
    color[k] = c;
    colors = std::max(colors, c + 1);
    if (c < 64) {
      for (const OrderedElement& e : cluster_elements(k)) {
        for (const Index node : e.element.nodes) used[node] |= std::uint64_t{1} << c;
      }
    }
  }
  // Clusters grouped by colour, ascending within each.
  color_start.assign(static_cast<std::size_t>(colors) + 1, 0);
  for (const Index c : color) ++color_start[c + 1];
  for (Index c = 0; c < colors; ++c) color_start[c + 1] += color_start[c];
  color_clusters.resize(static_cast<std::size_t>(clusters));
  std::vector<Index> next(color_start.begin(), color_start.end() - 1);
  for (Index k = 0; k < clusters; ++k) color_clusters[next[color[k]]++] = k;
}

void SimulatorState::refresh_structure() {
  if (!structure_stale) return;
  std::vector<std::array<Index, 4>> tets(ordered.size());
  for (std::size_t pos = 0; pos < ordered.size(); ++pos) tets[pos] = ordered[pos].element.nodes;
  std::vector<std::array<Index, 8>> pairs(springs.size());
  for (std::size_t i = 0; i < springs.size(); ++i) {
    for (int k = 0; k < 4; ++k) {
      pairs[i][k] = elements[springs[i].p.tet].nodes[k];
      pairs[i][k + 4] = elements[springs[i].q.tet].nodes[k];
    }
  }
  std::vector<std::array<Index, 16>> slots;
  hessian.build(num_nodes(), tets, pairs, &slots);
  for (std::size_t pos = 0; pos < ordered.size(); ++pos) ordered[pos].slots = slots[pos];
  structure_stale = false;
}

double SimulatorState::elastic_energy(const Points& at) const {
  return detail::sum_chunks(static_cast<Index>(elements.size()), kElementChunk, &partial, [&](Index begin, Index end) {
    double sum = 0;
    for (Index i = begin; i < end; ++i) {
      const Element& e = ordered[i].element;
      sum += e.volume * detail::energy_and_stress(material.model, parameters, detail::deformation_gradient(e.weights, at.data(), e.nodes), nullptr);
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
  return by_color(*this, [&](Index begin, Index end) {
    double energy = 0;
    for (Index i = begin; i < end; ++i) {
      const Element& e = ordered[i].element;
      Mat3 P;
      const double psi = detail::energy_and_stress(material.model, parameters, detail::deformation_gradient(e.weights, at.data(), e.nodes), &P);
      scatter(e.nodes, detail::element_gradient(e.weights, e.volume, P), gradient->data());
      energy += e.volume * psi;
    }
    return energy;
  });
}

namespace {

// Adds a tet's 10 distinct Hessian blocks (row-major, in LaneBatch order) into the pattern; each
// off-diagonal block also goes, transposed, to its mirror.
void scatter_blocks(const std::array<Index, 16>& slots, const double (&blocks)[10][9], detail::BlockSparseMatrix* hessian) {
  int b = 0;
  for (int r = 0; r < 4; ++r) {
    for (int c = r; c < 4; ++c, ++b) {
      const double* block = blocks[b];
      double* upper = hessian->block(slots[4 * r + c]);
      for (int k = 0; k < 9; ++k) upper[k] += block[k];
      if (c == r) continue;
      double* lower = hessian->block(slots[4 * c + r]);
      for (int y = 0; y < 3; ++y) {
        for (int z = 0; z < 3; ++z) lower[3 * z + y] += block[3 * y + z];
      }
    }
  }
}

}  // namespace

double SimulatorState::assemble_hessian(const Points& at, std::vector<double>* gradient) {
  hessian.set_zero();
  detail::LaneMaterial lane_material;
  lane_material.corotated = material.model == Model::kCorotated;
  lane_material.mu = parameters.mu;
  lane_material.lambda = parameters.lambda;
  lane_material.svd_tolerance = lane_material.corotated ? detail::kSvdExact : detail::kSvdForHessian;
  lane_material.rotation_fold = detail::kRotationFold;
  const bool lanes = detail::element_lanes_available();
  return by_color(*this, [&](Index begin, Index end) {
    double energy = 0;
    detail::LaneBatch batch;
    // Elements kLaneBatch at a time (the last group of a cluster may be short).
    for (Index i = begin; i < end; i += detail::kLaneBatch) {
      const int group = static_cast<int>(std::min<Index>(detail::kLaneBatch, end - i));
      for (int lane = 0; lane < group; ++lane) {
        const Element& el = ordered[i + lane].element;
        const Mat3 F = detail::deformation_gradient(el.weights, at.data(), el.nodes);
        const Mat3& V = ordered_v[i + lane];
        for (int r = 0; r < 3; ++r) {
          for (int k = 0; k < 3; ++k) {
            batch.F[lane][3 * r + k] = F(r, k);
            batch.V[lane][3 * r + k] = V(r, k);
          }
        }
        for (int a = 0; a < 4; ++a) {
          for (int k = 0; k < 3; ++k) batch.weights[lane][3 * a + k] = el.weights(a, k);
        }
        batch.volume[lane] = el.volume;
        batch.fallback[lane] = true;
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
          for (int k = 0; k < 9; ++k) V(k / 3, k % 3) = batch.V[lane][k];
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
