// The structure the element loops run on: the elements in a spatial order, cut into clusters;
// the clusters' colours; the block pattern and each element's slots in it. Built from scratch for
// a new mesh, and updated after a cut in proportion to what the cut changed: new copies are
// appended to the order (so no element moves and no slot changes), only clusters whose elements
// changed nodes are recoloured, and only the changed elements' blocks are looked up or added.

#include "sim/simulator_state.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>

namespace tetcut::sim {
namespace {

std::uint64_t bit(Index color) { return std::uint64_t{1} << color; }

}  // namespace

std::span<const SimulatorState::OrderedElement> SimulatorState::cluster(Index k) const {
  const Index count = static_cast<Index>(ordered.size());
  return {ordered.data() + k * kCluster, static_cast<std::size_t>(std::min(kCluster, count - k * kCluster))};
}

void SimulatorState::compute_masses() {
  mass = Eigen::VectorXd::Zero(num_nodes());
  for (const Element& e : elements) {
    for (const Index n : e.nodes) mass[n] += material.density * e.volume / 4;
  }
}

void SimulatorState::order_from_scratch(const Points& rest_positions) {
  // Morton order of the rest centroids: 21 bits per axis over the bounding box, interleaved.
  const Index count = static_cast<Index>(elements.size());
  Vec3 low = Vec3::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (Index node = 0; node < rest_positions.rows(); ++node) {
    low = low.cwiseMin(rest_positions.row(node).transpose());
    high = high.cwiseMax(rest_positions.row(node).transpose());
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
    for (const Index node : elements[e].nodes) centroid += rest_positions.row(node).transpose() / 4;
    const Vec3 unit = ((centroid - low).cwiseQuotient(extent)).cwiseMax(0.0).cwiseMin(1.0);
    std::uint64_t key = 0;
    for (int k = 0; k < 3; ++k) key |= spread(static_cast<std::uint64_t>(unit[k] * 2097151.0)) << k;
    keys[e] = {key, e};
  }
  std::sort(keys.begin(), keys.end());
  // Warm starts follow their elements (tet ids stay over a remesh); new ones start from scratch.
  std::vector<Mat3> carried(static_cast<std::size_t>(count), Mat3::Identity());
  for (Index pos = 0; pos < count; ++pos) {
    const Index id = keys[pos].second;
    if (id < static_cast<Index>(element_position.size())) carried[pos] = ordered_v[element_position[id]];
  }
  ordered_v.swap(carried);
  // Room for the copies cuts will append before the next sort (a quarter of the mesh), so that
  // appending never moves these arrays during a live session.
  const std::size_t room = static_cast<std::size_t>(count) + static_cast<std::size_t>(count) / 4 + kCluster;
  element_order.reserve(room);
  element_position.reserve(room);
  ordered.reserve(room);
  ordered_v.reserve(room);
  elements.reserve(room);
  element_order.resize(static_cast<std::size_t>(count));
  element_position.resize(static_cast<std::size_t>(count));
  ordered.resize(static_cast<std::size_t>(count));
  for (Index pos = 0; pos < count; ++pos) {
    const Index id = keys[pos].second;
    element_order[pos] = id;
    element_position[id] = pos;
    ordered[pos].element = elements[id];
  }
  appended_since_order = 0;
  color_from_scratch();
  pattern_rebuild = true;
}

void SimulatorState::color_from_scratch() {
  const Index n = num_nodes(), clusters = num_clusters();
  node_colors.assign(static_cast<std::size_t>(n), 0);
  cluster_color.assign(static_cast<std::size_t>(clusters), 0);
  colors_past_64 = false;
  // Past 64 colours: the colours of the clusters already coloured around each node, found
  // through the node-to-cluster incidence (built only if needed: a node in very many copies).
  std::vector<Index> around_start, around, forbidden;
  Index colors = 0;
  for (Index k = 0; k < clusters; ++k) {
    std::uint64_t mask = 0;
    for (const OrderedElement& e : cluster(k)) {
      for (const Index node : e.element.nodes) mask |= node_colors[node];
    }
    Index c;
    if (~mask != 0) {
      c = std::countr_zero(~mask);
    } else {
      colors_past_64 = true;
      if (around_start.empty()) {
        around_start.assign(static_cast<std::size_t>(n) + 1, 0);
        for (Index j = 0; j < clusters; ++j) {
          for (const OrderedElement& e : cluster(j)) {
            for (const Index node : e.element.nodes) ++around_start[node + 1];
          }
        }
        for (Index node = 0; node < n; ++node) around_start[node + 1] += around_start[node];
        around.resize(static_cast<std::size_t>(around_start.back()));
        std::vector<Index> next(around_start.begin(), around_start.end() - 1);
        for (Index j = 0; j < clusters; ++j) {
          for (const OrderedElement& e : cluster(j)) {
            for (const Index node : e.element.nodes) around[next[node]++] = j;
          }
        }
      }
      forbidden.assign(static_cast<std::size_t>(colors) + 1, 0);
      for (const OrderedElement& e : cluster(k)) {
        for (const Index node : e.element.nodes) {
          for (Index i = around_start[node]; i < around_start[node + 1]; ++i) {
            if (around[i] < k) forbidden[cluster_color[around[i]]] = 1;
          }
        }
      }
      c = 64;
      while (forbidden[c]) ++c;
    }
    cluster_color[k] = c;
    colors = std::max(colors, c + 1);
    if (c < 64) {
      for (const OrderedElement& e : cluster(k)) {
        for (const Index node : e.element.nodes) node_colors[node] |= bit(c);
      }
    }
  }
  group_colors();
}

void SimulatorState::group_colors() {
  Index colors = 0;
  for (const Index c : cluster_color) colors = std::max(colors, c + 1);
  color_start.assign(static_cast<std::size_t>(colors) + 1, 0);
  for (const Index c : cluster_color) ++color_start[c + 1];
  for (Index c = 0; c < colors; ++c) color_start[c + 1] += color_start[c];
  color_clusters.resize(cluster_color.size());
  std::vector<Index> next(color_start.begin(), color_start.end() - 1);
  for (Index k = 0; k < static_cast<Index>(cluster_color.size()); ++k) color_clusters[next[cluster_color[k]]++] = k;
}

void SimulatorState::update_after_cut(Index old_count, std::span<const Index> new_source, std::span<const Index> renoded,
                                      std::span<const Index> rebuilt) {
  const Index count = static_cast<Index>(elements.size());
  if (colors_past_64 || 4 * (appended_since_order + count - old_count) > count) {
    // Many copies appended since the last spatial sort (or colours past the fast path's 64):
    // sort again and start over, O(T log T) once in a while.
    order_from_scratch(rest);  // and the pattern is built again: no matrix to reuse
    return;
  }
  // Clusters whose nodes change: those holding a re-noded element, and the last one when new
  // elements join it. Their colours come off their current nodes first (in a valid colouring
  // a cluster is the only one of its colour at each of its nodes).
  std::vector<Index> dirty;
  for (const Index id : renoded) dirty.push_back(element_position[id] / kCluster);
  if (old_count % kCluster != 0 && count > old_count) dirty.push_back(old_count / kCluster);
  std::sort(dirty.begin(), dirty.end());
  dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
  for (const Index k : dirty) {
    for (const OrderedElement& e : cluster(k)) {
      for (const Index node : e.element.nodes) node_colors[node] &= ~bit(cluster_color[k]);
    }
  }
  node_colors.resize(static_cast<std::size_t>(num_nodes()), 0);
  // A reusable Newton matrix holds the rebuilt elements as they were: they come out of it, and
  // go back in as they are now, with the new copies (after the pattern has their slots).
  if (reusable) {
    for (const Index id : rebuilt) {
      if (id < old_count) reuse_take_out.emplace_back(ordered[element_position[id]], ordered_v[element_position[id]]);
    }
  }
  // Changed elements in place; new copies appended, each with its source's warm start.
  for (const Index id : rebuilt) {
    if (id < old_count) ordered[element_position[id]].element = elements[id];
  }
  for (Index id = old_count; id < count; ++id) {
    const Index pos = static_cast<Index>(ordered.size());
    const Index source = new_source[id - old_count];
    element_order.push_back(id);
    element_position.push_back(pos);
    ordered.push_back({elements[id], {}});
    ordered_v.push_back(source >= 0 && source < id ? ordered_v[element_position[source]] : Mat3::Identity());
    pattern_pending.push_back(pos);
  }
  for (const Index id : renoded) pattern_pending.push_back(element_position[id]);
  if (reusable) {
    for (const Index id : rebuilt) {
      if (id < old_count) reuse_put_in.push_back(element_position[id]);
    }
    for (Index id = old_count; id < count; ++id) reuse_put_in.push_back(element_position[id]);
  }
  appended_since_order += count - old_count;
  const Index old_clusters = static_cast<Index>(cluster_color.size());
  cluster_color.resize(static_cast<std::size_t>(num_clusters()), 0);
  for (Index k = old_clusters; k < num_clusters(); ++k) dirty.push_back(k);
  // Recolour them, greedily, with the colours their new nodes leave free.
  for (const Index k : dirty) {
    std::uint64_t mask = 0;
    for (const OrderedElement& e : cluster(k)) {
      for (const Index node : e.element.nodes) mask |= node_colors[node];
    }
    if (~mask == 0) {
      color_from_scratch();  // a colour past 64 is needed
      return;
    }
    cluster_color[k] = std::countr_zero(~mask);
    for (const OrderedElement& e : cluster(k)) {
      for (const Index node : e.element.nodes) node_colors[node] |= bit(cluster_color[k]);
    }
  }
  group_colors();
}

void SimulatorState::build_pattern() {
  std::vector<std::array<Index, 4>> tets(ordered.size());
  for (std::size_t pos = 0; pos < ordered.size(); ++pos) tets[pos] = ordered[pos].element.nodes;
  std::vector<std::array<Index, 8>> pairs(springs.size());
  for (std::size_t i = 0; i < springs.size(); ++i) {
    for (int k = 0; k < 4; ++k) {
      pairs[i][k] = elements[springs[i].p.tet].nodes[k];
      pairs[i][k + 4] = elements[springs[i].q.tet].nodes[k];
    }
  }
  // The blocks of the last assembly's constraint terms (surface contact's pairs, couplings no
  // element has): most are wanted again at the next. Left out, they were added back one by one
  // after every build, and as contact's added blocks passed a tenth of the build's, the sliced
  // hand built its pattern afresh every step and added 35k blocks each assembly through the
  // hash of added blocks (most of the 2.2 ms contact's scatter took of a 20 ms step).
  std::vector<std::array<Index, 2>> couplings;
  for (const ConstraintTerm& t : ledger_constraints) {
    for (int a = 0; a < t.count; ++a) {
      for (int b = a + 1; b < t.count; ++b) {
        if (t.nodes[a] < num_nodes() && t.nodes[b] < num_nodes()) couplings.push_back({t.nodes[a], t.nodes[b]});
      }
    }
  }
  std::vector<std::array<Index, 16>> slots;
  hessian.build(num_nodes(), tets, pairs, &slots, couplings);
  for (std::size_t pos = 0; pos < ordered.size(); ++pos) ordered[pos].slots = slots[pos];
  blocks_at_build = hessian.num_blocks();
  pattern_rebuild = false;
  reusable = false;  // the values are gone
  reuse_take_out.clear();
  reuse_put_in.clear();
  springs_pending = false;
  pattern_pending.clear();
}

void SimulatorState::refresh_structure() {
  // Blocks added since the build are kept apart (see BlockSparseMatrix), and couplings a cut
  // removed stay as zeros; once the added ones reach a tenth of the build, build afresh.
  if (pattern_rebuild || 10 * hessian.num_added_blocks() > blocks_at_build) {
    build_pattern();
    return;
  }
  if (hessian.num_rows() < num_nodes()) hessian.add_rows(num_nodes() - hessian.num_rows());
  for (const Index pos : pattern_pending) {
    OrderedElement& o = ordered[pos];
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) o.slots[4 * a + b] = hessian.find_or_add(o.element.nodes[a], o.element.nodes[b]);
    }
  }
  pattern_pending.clear();
  if (springs_pending) {
    for (const Spring& spring : springs) {
      for (const Index a : elements[spring.p.tet].nodes) {
        for (const Index b : elements[spring.q.tet].nodes) {
          hessian.find_or_add(a, b);
          hessian.find_or_add(b, a);
        }
      }
    }
    springs_pending = false;
  }
}

void SimulatorState::add_element_hessian(const Element& e, const std::array<Index, 16>& slots, Mat3* warm, const Points& at, double sign) {
  Mat3 P;
  detail::HessianFactor q;
  detail::element_hessian_factor(material.model, parameters, detail::deformation_gradient(e.weights, at.data(), e.nodes), e.weights,
                                 e.volume, warm, &P, &q);
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      double block[9];
      detail::factor_block(q, a, b, block);
      hessian.add(slots[4 * a + b], block, sign);
    }
  }
}

void SimulatorState::apply_cut_to_reused_matrix() {
  for (auto& [old, warm] : reuse_take_out) add_element_hessian(old.element, old.slots, &warm, assembled_at, -1);
  for (const Index pos : reuse_put_in) {
    Mat3 warm = ordered_v[pos];
    add_element_hessian(ordered[pos].element, ordered[pos].slots, &warm, assembled_at, 1);
  }
  reuse_take_out.clear();
  reuse_put_in.clear();
}

}  // namespace tetcut::sim
