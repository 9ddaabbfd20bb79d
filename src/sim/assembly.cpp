// The element loops: elastic energy, gradient and projected Hessian of every tet copy, assembled
// into node vectors and the block pattern. Work is split by colour (elements sharing no node) and
// within a colour into fixed chunks, so that threads never write the same entry and the sums come
// out the same on any number of threads.

#include "sim/simulator_state.hpp"

#include "sim/element_batch.hpp"

#include <bit>
#include <cstdint>

namespace tetcut::sim {
namespace {

// Elements per task within a colour: large enough that a task outweighs its scheduling, small
// enough that a colour of a 10k-tet mesh spreads over both cores.
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

void SimulatorState::assign_colors() {
  const Index n = num_nodes(), count = static_cast<Index>(elements.size());
  std::vector<std::uint64_t> used(static_cast<std::size_t>(n), 0);
  std::vector<Index> color(static_cast<std::size_t>(count));
  // Past 64 colours: the colours of the elements already coloured around each node, found
  // through the node-to-element incidence (built only if needed).
  std::vector<Index> around_start, around, forbidden;
  Index colors = 0;
  for (Index e = 0; e < count; ++e) {
    std::uint64_t mask = 0;
    for (const Index node : elements[e].nodes) mask |= used[node];
    Index c;
    if (~mask != 0) {
      c = std::countr_zero(~mask);
    } else {
      if (around_start.empty()) {
        around_start.assign(static_cast<std::size_t>(n) + 1, 0);
        for (const Element& el : elements) {
          for (const Index node : el.nodes) ++around_start[node + 1];
        }
        for (Index node = 0; node < n; ++node) around_start[node + 1] += around_start[node];
        around.resize(static_cast<std::size_t>(around_start.back()));
        std::vector<Index> next(around_start.begin(), around_start.end() - 1);
        for (Index i = 0; i < count; ++i) {
          for (const Index node : elements[i].nodes) around[next[node]++] = i;
        }
      }
      forbidden.assign(static_cast<std::size_t>(colors) + 1, 0);
      for (const Index node : elements[e].nodes) {
        for (Index i = around_start[node]; i < around_start[node + 1]; ++i) {
          if (around[i] < e) forbidden[color[around[i]]] = 1;
        }
      }
      c = 64;
      while (forbidden[c]) ++c;
    }
    color[e] = c;
    colors = std::max(colors, c + 1);
    if (c < 64) {
      for (const Index node : elements[e].nodes) used[node] |= std::uint64_t{1} << c;
    }
  }
  // Elements grouped by colour, ascending within each.
  color_start.assign(static_cast<std::size_t>(colors) + 1, 0);
  for (const Index c : color) ++color_start[c + 1];
  for (Index c = 0; c < colors; ++c) color_start[c + 1] += color_start[c];
  color_elements.resize(static_cast<std::size_t>(count));
  std::vector<Index> next(color_start.begin(), color_start.end() - 1);
  for (Index e = 0; e < count; ++e) color_elements[next[color[e]]++] = e;
}

void SimulatorState::refresh_structure() {
  if (!structure_stale) return;
  std::vector<std::array<Index, 4>> tets(elements.size());
  for (std::size_t e = 0; e < elements.size(); ++e) tets[e] = elements[e].nodes;
  std::vector<std::array<Index, 8>> pairs(springs.size());
  for (std::size_t i = 0; i < springs.size(); ++i) {
    for (int k = 0; k < 4; ++k) {
      pairs[i][k] = elements[springs[i].p.tet].nodes[k];
      pairs[i][k + 4] = elements[springs[i].q.tet].nodes[k];
    }
  }
  hessian.build(num_nodes(), tets, pairs, &element_slots);
  structure_stale = false;
}

double SimulatorState::elastic_energy(const Points& at) const {
  return detail::sum_chunks(static_cast<Index>(elements.size()), kElementChunk, &partial, [&](Index begin, Index end) {
    double sum = 0;
    for (Index i = begin; i < end; ++i) {
      const Element& e = elements[i];
      sum += e.volume * detail::energy_and_stress(material.model, parameters, detail::deformation_gradient(e.weights, at.data(), e.nodes), nullptr);
    }
    return sum;
  });
}

namespace {

// Runs body(element, &energy) over all elements, colour by colour, each colour in fixed chunks on
// all threads; returns the total of the energies in (colour, chunk, element) order.
template <typename Body>
double by_color(const std::vector<Index>& color_start, const std::vector<Index>& color_elements, std::vector<double>* partial,
                const Body& body) {
  double total = 0;
  for (std::size_t c = 0; c + 1 < color_start.size(); ++c) {
    const Index first = color_start[c], count = color_start[c + 1] - first;
    total += detail::sum_chunks(count, kElementChunk, partial, [&](Index begin, Index end) {
      double sum = 0;
      for (Index i = begin; i < end; ++i) sum += body(color_elements[first + i]);
      return sum;
    });
  }
  return total;
}

}  // namespace

double SimulatorState::elastic_gradient(const Points& at, std::vector<double>* gradient) const {
  return by_color(color_start, color_elements, &partial, [&](Index i) {
    const Element& e = elements[i];
    Mat3 P;
    const double psi = detail::energy_and_stress(material.model, parameters, detail::deformation_gradient(e.weights, at.data(), e.nodes), &P);
    scatter(e.nodes, detail::element_gradient(e.weights, e.volume, P), gradient->data());
    return e.volume * psi;
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
  double total = 0;
  for (std::size_t c = 0; c + 1 < color_start.size(); ++c) {
    const Index first = color_start[c], count = color_start[c + 1] - first;
    total += detail::sum_chunks(count, kElementChunk, &partial, [&](Index begin, Index end) {
      double energy = 0;
      detail::LaneBatch batch;
      // Elements kLaneBatch at a time (the last group of a chunk may be short).
      for (Index i = begin; i < end; i += detail::kLaneBatch) {
        const int group = static_cast<int>(std::min<Index>(detail::kLaneBatch, end - i));
        for (int lane = 0; lane < group; ++lane) {
          const Index e = color_elements[first + i + lane];
          const Element& el = elements[e];
          const Mat3 F = detail::deformation_gradient(el.weights, at.data(), el.nodes);
          for (int r = 0; r < 3; ++r) {
            for (int k = 0; k < 3; ++k) {
              batch.F[lane][3 * r + k] = F(r, k);
              batch.V[lane][3 * r + k] = element_v[e](r, k);
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
          const Index e = color_elements[first + i + lane];
          const Element& el = elements[e];
          if (batch.fallback[lane]) {
            // The scalar kernel: no lane kernel here, or a lane it cannot take.
            Mat3 F, P;
            for (int k = 0; k < 9; ++k) F(k / 3, k % 3) = batch.F[lane][k];
            detail::HessianFactor q;
            batch.energy[lane] = detail::element_hessian_factor(material.model, parameters, F, el.weights, el.volume, &element_v[e], &P, &q);
            const detail::Vec12 g = detail::element_gradient(el.weights, el.volume, P);
            for (int k = 0; k < 12; ++k) batch.gradient[lane][k] = g[k];
            int b = 0;
            for (int r = 0; r < 4; ++r) {
              for (int col = r; col < 4; ++col) detail::factor_block(q, r, col, batch.blocks[lane][b++]);
            }
          } else {
            for (int k = 0; k < 9; ++k) element_v[e](k / 3, k % 3) = batch.V[lane][k];
          }
          energy += el.volume * batch.energy[lane];
          scatter(el.nodes, Eigen::Map<const detail::Vec12>(batch.gradient[lane]), gradient->data());
          scatter_blocks(element_slots[e], batch.blocks[lane], &hessian);
        }
      }
      return energy;
    });
  }
  return total;
}

}  // namespace tetcut::sim
