#include "sim/block_sparse.hpp"

#include <tbb/enumerable_thread_specific.h>

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace tetcut::sim::detail {
namespace {

// Per-thread scratch of the pattern build: a stamp per node (which row last saw it) and its
// position in that row.
struct RowScratch {
  std::vector<Index> stamp, position;
  std::vector<Index> row;
};

}  // namespace

void BlockSparseMatrix::build(Index num_nodes, std::span<const std::array<Index, 4>> tets, std::span<const std::array<Index, 8>> extra,
                              std::vector<std::array<Index, 16>>* tet_slots, std::span<const std::array<Index, 2>> couplings) {
  std::vector<Index> tet_start, tet_of, extra_start, extra_of, coupling_start, coupling_of;
  incidence<4>(num_nodes, tets, &tet_start, &tet_of);
  incidence<8>(num_nodes, extra, &extra_start, &extra_of);
  incidence<2>(num_nodes, couplings, &coupling_start, &coupling_of);
  tbb::enumerable_thread_specific<RowScratch> scratch([&] {
    RowScratch s;
    s.stamp.assign(static_cast<std::size_t>(num_nodes), -1);
    s.position.assign(static_cast<std::size_t>(num_nodes), -1);
    return s;
  });
  // The columns of row r, sorted, into s.row; marks them with `mark` (distinct per pass and row).
  const auto collect = [&](Index r, Index mark, RowScratch& s) {
    s.row.clear();
    const auto add = [&](Index n) {
      if (s.stamp[n] == mark) return;
      s.stamp[n] = mark;
      s.row.push_back(n);
    };
    add(r);
    for (Index i = tet_start[r]; i < tet_start[r + 1]; ++i) {
      for (const Index n : tets[tet_of[i]]) add(n);
    }
    for (Index i = extra_start[r]; i < extra_start[r + 1]; ++i) {
      for (const Index n : extra[extra_of[i]]) add(n);
    }
    for (Index i = coupling_start[r]; i < coupling_start[r + 1]; ++i) {
      for (const Index n : couplings[coupling_of[i]]) add(n);
    }
  };
  row_start_.assign(static_cast<std::size_t>(num_nodes) + 1, 0);
  for_chunks(num_nodes, kNodeChunk, [&](Index begin, Index end, Index) {
    RowScratch& s = scratch.local();
    for (Index r = begin; r < end; ++r) {
      collect(r, r, s);
      row_start_[r + 1] = static_cast<Index>(s.row.size());
    }
  });
  for (Index r = 0; r < num_nodes; ++r) row_start_[r + 1] += row_start_[r];
  columns_.resize(static_cast<std::size_t>(row_start_.back()));
  diagonal_.resize(static_cast<std::size_t>(num_nodes));
  tet_slots->resize(tets.size());
  for_chunks(num_nodes, kNodeChunk, [&](Index begin, Index end, Index) {
    RowScratch& s = scratch.local();
    for (Index r = begin; r < end; ++r) {
      collect(r, r + num_nodes, s);
      std::sort(s.row.begin(), s.row.end());
      const Index first = row_start_[r];
      for (Index k = 0; k < static_cast<Index>(s.row.size()); ++k) {
        columns_[first + k] = s.row[k];
        s.position[s.row[k]] = first + k;
      }
      diagonal_[r] = s.position[r];
      for (Index i = tet_start[r]; i < tet_start[r + 1]; ++i) {
        const Index t = tet_of[i];
        const auto& nodes = tets[t];
        const int a = static_cast<int>(std::find(nodes.begin(), nodes.end(), r) - nodes.begin());
        for (int b = 0; b < 4; ++b) (*tet_slots)[t][4 * a + b] = s.position[nodes[b]];
      }
    }
  });
  added_.assign(static_cast<std::size_t>(num_nodes), {});
  added_columns_.clear();
  added_keys_.clear();
  added_key_slots_.clear();
  values_.clear();
  single_values_.clear();
  added_values_.clear();
  single_added_values_.clear();
  resize_values();
  // The pattern is structurally symmetric: every block's transpose is in it.
  transposed_.resize(columns_.size());
  for_chunks(num_nodes, kNodeChunk, [&](Index begin, Index end, Index) {
    for (Index r = begin; r < end; ++r) {
      for (Index k = row_start_[r]; k < row_start_[r + 1]; ++k) transposed_[static_cast<std::size_t>(k)] = slot(columns_[k], r);
    }
  });
}

void BlockSparseMatrix::resize_values() {
  if (single_) {
    single_values_.resize(9 * columns_.size(), 0.0f);
    single_added_values_.resize(9 * added_columns_.size(), 0.0f);
  } else {
    values_.resize(9 * columns_.size(), 0.0);
    added_values_.resize(9 * added_columns_.size(), 0.0);
  }
}

void BlockSparseMatrix::set_single_precision(bool single) {
  if (single == single_) return;
  single_ = single;
  values_ = {};
  single_values_ = {};
  added_values_ = {};
  single_added_values_ = {};
  resize_values();
}

void BlockSparseMatrix::add_rows(Index count) {
  for (Index i = 0; i < count; ++i) {
    const Index r = num_rows();
    added_.emplace_back();
    diagonal_.push_back(-1);
    diagonal_[r] = find_or_add(r, r);
  }
}

Index BlockSparseMatrix::find_or_add(Index row, Index column) {
  const Index found = slot(row, column);
  if (found >= 0) return found;
  const Index k = num_blocks();
  added_columns_.push_back(column);
  resize_values();
  added_[row].push_back(k);
  index_added(key(row, column), k);
  const Index transposed = row == column ? k : slot(column, row);
  transposed_.push_back(transposed);
  if (transposed >= 0) transposed_[static_cast<std::size_t>(transposed)] = k;
  return k;
}

namespace {
// Fibonacci hashing of a (row, column) key into a table of 2^bits entries.
std::size_t hash_position(std::uint64_t key, std::size_t mask) { return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 32) & mask; }
}  // namespace

Index BlockSparseMatrix::added_slot(std::uint64_t k) const {
  if (added_keys_.empty()) return -1;
  const std::size_t mask = added_keys_.size() - 1;
  for (std::size_t i = hash_position(k, mask);; i = (i + 1) & mask) {
    if (added_keys_[i] == k) return added_key_slots_[i];
    if (added_keys_[i] == kNoKey) return -1;
  }
}

void BlockSparseMatrix::place_added(std::uint64_t k, Index slot) {
  const std::size_t mask = added_keys_.size() - 1;
  std::size_t i = hash_position(k, mask);
  while (added_keys_[i] != kNoKey) i = (i + 1) & mask;
  added_keys_[i] = k;
  added_key_slots_[i] = slot;
}

void BlockSparseMatrix::index_added(std::uint64_t k, Index slot) {
  if (2 * (added_columns_.size() + 1) <= added_keys_.size()) {
    place_added(k, slot);
    return;
  }
  // Grow to keep the table at most half full: every added block again, this one among them.
  const std::size_t capacity = std::max<std::size_t>(64, 4 * added_keys_.size());
  added_keys_.assign(capacity, kNoKey);
  added_key_slots_.assign(capacity, -1);
  const auto built = static_cast<Index>(columns_.size());
  for (Index r = 0; r < num_rows(); ++r) {
    for (const Index a : added_[r]) place_added(key(r, added_columns_[static_cast<std::size_t>(a - built)]), a);
  }
}

Index BlockSparseMatrix::slot(Index row, Index column) const {
  if (row < built_rows()) {
    const auto begin = columns_.begin() + row_start_[row], end = columns_.begin() + row_start_[row + 1];
    const auto it = std::lower_bound(begin, end, column);
    if (it != end && *it == column) return static_cast<Index>(it - columns_.begin());
  }
  return added_slot(key(row, column));
}

void BlockSparseMatrix::set_zero() {
  std::fill(values_.begin(), values_.end(), 0.0);
  std::fill(added_values_.begin(), added_values_.end(), 0.0);
  std::fill(single_values_.begin(), single_values_.end(), 0.0f);
  std::fill(single_added_values_.begin(), single_added_values_.end(), 0.0f);
}

void BlockSparseMatrix::add_scaled(const BlockSparseMatrix& other, double weight) {
  const auto scaled = [weight](auto& to, const auto& from) {
    using Value = typename std::decay_t<decltype(to)>::value_type;
    // Blocks added to this one since the copy (surface contact) are beyond the other's: zeros there.
    for (std::size_t k = 0; k < std::min(to.size(), from.size()); ++k) to[k] = static_cast<Value>(to[k] + weight * from[k]);
  };
  scaled(values_, other.values_);
  scaled(added_values_, other.added_values_);
  scaled(single_values_, other.single_values_);
  scaled(single_added_values_, other.single_added_values_);
}

double BlockSparseMatrix::multiply_rows(Index begin, Index end, const double* x, double* y, const std::uint8_t* free) const {
  return single_ ? multiply_rows_stored(begin, end, x, y, free, single_values_.data(), single_added_values_.data())
                 : multiply_rows_stored(begin, end, x, y, free, values_.data(), added_values_.data());
}

template <typename Value>
double BlockSparseMatrix::multiply_rows_stored(Index begin, Index end, const double* x, double* y, const std::uint8_t* free,
                                               const Value* built_values, const Value* added_values) const {
  const auto add = [&](const Value* b, const double* in, double* sums) {
    sums[0] += b[0] * in[0] + b[1] * in[1] + b[2] * in[2];
    sums[1] += b[3] * in[0] + b[4] * in[1] + b[5] * in[2];
    sums[2] += b[6] * in[0] + b[7] * in[1] + b[8] * in[2];
  };
  const Index built = built_rows();
  double dot = 0;
  for (Index r = begin; r < end; ++r) {
    double* out = y + 3 * static_cast<std::size_t>(r);
    if (!free[r]) {
      out[0] = out[1] = out[2] = 0;
      continue;
    }
    double sums[3] = {0, 0, 0};
    if (r < built) {
      for (Index k = row_start_[r]; k < row_start_[r + 1]; ++k) {
        add(built_values + 9 * static_cast<std::size_t>(k), x + 3 * static_cast<std::size_t>(columns_[k]), sums);
      }
    }
    for (const Index k : added_[r]) {
      const std::size_t a = static_cast<std::size_t>(k - static_cast<Index>(columns_.size()));
      add(added_values + 9 * a, x + 3 * static_cast<std::size_t>(added_columns_[a]), sums);
    }
    out[0] = sums[0];
    out[1] = sums[1];
    out[2] = sums[2];
    const double* own = x + 3 * static_cast<std::size_t>(r);
    dot += own[0] * sums[0] + own[1] * sums[1] + own[2] * sums[2];
  }
  return dot;
}

void BlockSparseMatrix::multiply(const double* x, double* y, const std::uint8_t* free) const {
  for_chunks(num_rows(), kNodeChunk, [&](Index begin, Index end, Index) { multiply_rows(begin, end, x, y, free); });
}

namespace {

// The inverse of a symmetric positive definite 3 x 3 block (row-major), or of its diagonal when
// it is not invertible (a node with no stiffness and no mass, which a valid mesh does not have).
std::array<double, 9> inverse_block(const double* b) {
  const double c00 = b[4] * b[8] - b[5] * b[7], c01 = b[5] * b[6] - b[3] * b[8], c02 = b[3] * b[7] - b[4] * b[6];
  const double det = b[0] * c00 + b[1] * c01 + b[2] * c02;
  std::array<double, 9> inv{};
  if (det > 0 && std::isfinite(det)) {
    const double s = 1 / det;
    inv = {c00 * s, (b[2] * b[7] - b[1] * b[8]) * s, (b[1] * b[5] - b[2] * b[4]) * s,
           c01 * s, (b[0] * b[8] - b[2] * b[6]) * s, (b[2] * b[3] - b[0] * b[5]) * s,
           c02 * s, (b[1] * b[6] - b[0] * b[7]) * s, (b[0] * b[4] - b[1] * b[3]) * s};
    return inv;
  }
  for (int i = 0; i < 3; ++i) inv[4 * i] = b[4 * i] > 0 ? 1 / b[4 * i] : 1.0;
  return inv;
}

}  // namespace

ConjugateGradientReport conjugate_gradients(const BlockSparseMatrix& a, std::span<const double> b, std::span<double> d,
                                            std::span<const std::uint8_t> free, std::span<const double> weight,
                                            const ConjugateGradientOptions& options, ConjugateGradientWorkspace* w) {
  const Index n = a.num_rows();
  const std::size_t size = 3 * static_cast<std::size_t>(n);
  w->r.resize(size);
  w->z.resize(size);
  w->p.resize(size);
  w->q.resize(size);
  w->inverse_diagonal.resize(static_cast<std::size_t>(n));
  const std::uint8_t* is_free = free.data();
  // Preconditioner, and r = b - A d with the start's residual measures.
  for_chunks(n, kNodeChunk, [&](Index begin, Index end, Index) {
    double block[9];
    for (Index v = begin; v < end; ++v) {
      a.read(a.diagonal_slot(v), block);
      w->inverse_diagonal[v] = inverse_block(block);
    }
  });
  a.multiply(d.data(), w->q.data(), is_free);
  struct Sums {
    double rz = 0, rw = 0;
  };
  // Sets d += step p and r -= step q (at the start: r = b - q), z = P r, and returns r.z and
  // r^T W r; the chunks' sums go into partial[2c], partial[2c + 1] and are added in chunk order.
  const Index chunks = std::max<Index>(1, (n + kNodeChunk - 1) / kNodeChunk);
  w->partial.assign(2 * static_cast<std::size_t>(chunks), 0.0);
  const auto update = [&](bool start, double step) {
    for_chunks(n, kNodeChunk, [&](Index begin, Index end, Index c) {
      double rz = 0, rw = 0;
      for (Index v = begin; v < end; ++v) {
        double* r = w->r.data() + 3 * static_cast<std::size_t>(v);
        double* z = w->z.data() + 3 * static_cast<std::size_t>(v);
        const double* q = w->q.data() + 3 * static_cast<std::size_t>(v);
        if (!is_free[v]) {
          r[0] = r[1] = r[2] = z[0] = z[1] = z[2] = 0;
          continue;
        }
        if (start) {
          for (int k = 0; k < 3; ++k) r[k] = b[3 * v + k] - q[k];
        } else {
          const double* p = w->p.data() + 3 * static_cast<std::size_t>(v);
          for (int k = 0; k < 3; ++k) {
            d[3 * v + k] += step * p[k];
            r[k] -= step * q[k];
          }
        }
        const std::array<double, 9>& m = w->inverse_diagonal[v];
        z[0] = m[0] * r[0] + m[1] * r[1] + m[2] * r[2];
        z[1] = m[3] * r[0] + m[4] * r[1] + m[5] * r[2];
        z[2] = m[6] * r[0] + m[7] * r[1] + m[8] * r[2];
        rz += r[0] * z[0] + r[1] * z[1] + r[2] * z[2];
        rw += weight[v] * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
      }
      w->partial[2 * c] = rz;
      w->partial[2 * c + 1] = rw;
    });
    Sums s;
    for (Index c = 0; c < chunks; ++c) {
      s.rz += w->partial[2 * c];
      s.rw += w->partial[2 * c + 1];
    }
    return s;
  };
  Sums s = update(true, 0);
  ConjugateGradientReport report;
  report.weighted_residual = s.rw;
  const double target = std::max(options.absolute_target, options.relative_target * options.relative_target * s.rw);
  if (s.rw <= target) {
    report.reached_target = true;
    return report;
  }
  const int max_iterations = options.max_iterations > 0 ? options.max_iterations : static_cast<int>(std::min<std::size_t>(10 * size + 10, 1 << 30));
  std::copy(w->z.begin(), w->z.end(), w->p.begin());
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    double pq = 0;
    for_chunks(n, kNodeChunk, [&](Index begin, Index end, Index c) { w->partial[2 * c] = a.multiply_rows(begin, end, w->p.data(), w->q.data(), is_free); });
    for (Index c = 0; c < chunks; ++c) pq += w->partial[2 * c];
    if (!(pq > 0) || !std::isfinite(pq)) break;  // no descent left (rounding) or not positive definite
    const Sums next = update(false, s.rz / pq);
    report.iterations = iteration + 1;
    report.weighted_residual = next.rw;
    if (next.rw <= target) {
      report.reached_target = true;
      break;
    }
    const double beta = next.rz / s.rz;
    s = next;
    for_chunks(n, kNodeChunk, [&](Index begin, Index end, Index) {
      for (std::size_t k = 3 * static_cast<std::size_t>(begin); k < 3 * static_cast<std::size_t>(end); ++k) w->p[k] = w->z[k] + beta * w->p[k];
    });
  }
  return report;
}

struct DirectSolver::Factor {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  // What the analysis was made for: the free nodes and the pattern's size.
  std::vector<std::uint8_t> free;
  Index blocks = -1, rows = -1;
  std::vector<Eigen::Triplet<double>> triplets;
};

DirectSolver::DirectSolver() : factor_(std::make_unique<Factor>()) {}
DirectSolver::~DirectSolver() = default;

bool DirectSolver::solve(const BlockSparseMatrix& a, std::span<const std::uint8_t> free, std::span<const double> b,
                         std::span<double> d) {
  Factor& f = *factor_;
  const Index n = a.num_rows();
  std::vector<Index> dof(static_cast<std::size_t>(n), -1);
  Index count = 0;
  for (Index v = 0; v < n; ++v) {
    if (free[v]) dof[v] = count++;
  }
  // Every block of the pattern goes in, zero or not, so that the sparse pattern depends on the
  // block pattern and the free nodes only.
  f.triplets.clear();
  for (Index row = 0; row < n; ++row) {
    if (dof[row] < 0) continue;
    a.for_each_block(row, [&](Index k, Index column) {
      if (dof[column] < 0) return;
      double block[9];
      a.read(k, block);
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) f.triplets.emplace_back(3 * dof[row] + i, 3 * dof[column] + j, block[3 * i + j]);
      }
    });
  }
  Eigen::SparseMatrix<double> matrix(3 * count, 3 * count);
  matrix.setFromTriplets(f.triplets.begin(), f.triplets.end());
  const bool same = f.rows == n && f.blocks == a.num_blocks() && std::equal(free.begin(), free.end(), f.free.begin(), f.free.end());
  if (!same) {
    f.ldlt.analyzePattern(matrix);
    f.rows = n;
    f.blocks = a.num_blocks();
    f.free.assign(free.begin(), free.end());
  }
  f.ldlt.factorize(matrix);
  if (f.ldlt.info() != Eigen::Success) {
    f.rows = -1;  // analyse afresh next time
    return false;
  }
  Eigen::VectorXd rhs(3 * count);
  for (Index v = 0; v < n; ++v) {
    if (dof[v] >= 0) {
      for (int k = 0; k < 3; ++k) rhs[3 * dof[v] + k] = b[3 * v + k];
    }
  }
  const Eigen::VectorXd x = f.ldlt.solve(rhs);
  if (f.ldlt.info() != Eigen::Success) return false;
  for (Index v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) d[3 * v + k] = dof[v] >= 0 ? x[3 * dof[v] + k] : 0.0;
  }
  return true;
}

bool DirectSolver::positive_definite() const {
  return factor_->rows >= 0 && (factor_->ldlt.vectorD().size() == 0 || factor_->ldlt.vectorD().minCoeff() > 0);
}

bool solve_direct(const BlockSparseMatrix& a, std::span<const std::uint8_t> free, std::span<const double> b, std::span<double> d) {
  DirectSolver solver;
  return solver.solve(a, free, b, d);
}

}  // namespace tetcut::sim::detail
