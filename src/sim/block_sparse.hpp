#pragma once
// The Newton system of the simulator: a symmetric matrix of 3 x 3 blocks over the mesh nodes,
// stored in block compressed rows with both triangles (each row multiplies on its own, so rows
// split over threads without races), and conjugate gradients on it.
//
// Constrained (pinned or kinematic) nodes stay in the pattern; the solver works on the free ones
// only: it reads and writes vectors there and treats the others as zero, which is the matrix
// restricted to the free unknowns. So pinning or releasing a node changes nothing here.
//
// Results never depend on the number of threads: a row's product is computed by one thread in
// column order, and every sum over nodes is taken in fixed chunks added in chunk order.

#include <tetcut/types.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace tetcut::sim::detail {

/// Node-range chunks for deterministic parallel loops: chunk c covers nodes [c * kChunk, ...).
inline constexpr Index kNodeChunk = 512;

/// Incidence of nodes in groups (tets, spring pairs, triangles) as compressed rows: the groups
/// around node n are group[start[n] .. start[n + 1]), ascending (a node a group holds twice is
/// listed twice). O(nodes + groups).
template <std::size_t N>
void incidence(Index num_nodes, std::span<const std::array<Index, N>> groups, std::vector<Index>* start, std::vector<Index>* group) {
  start->assign(static_cast<std::size_t>(num_nodes) + 1, 0);
  for (const auto& g : groups) {
    for (const Index n : g) ++(*start)[static_cast<std::size_t>(n) + 1];
  }
  for (Index n = 0; n < num_nodes; ++n) (*start)[static_cast<std::size_t>(n) + 1] += (*start)[static_cast<std::size_t>(n)];
  group->resize(static_cast<std::size_t>(start->back()));
  std::vector<Index> next(start->begin(), start->end() - 1);
  for (Index i = 0; i < static_cast<Index>(groups.size()); ++i) {
    for (const Index n : groups[static_cast<std::size_t>(i)]) (*group)[static_cast<std::size_t>(next[static_cast<std::size_t>(n)]++)] = i;
  }
}

/// Calls body(begin, end, chunk) over fixed chunks of [0, count), in parallel when there are
/// several. The chunking is independent of the number of threads.
template <typename Body>
void for_chunks(Index count, Index chunk, const Body& body) {
  const Index chunks = (count + chunk - 1) / chunk;
  if (chunks <= 1) {
    if (count > 0) body(Index{0}, count, Index{0});
    return;
  }
  tbb::parallel_for(
      tbb::blocked_range<Index>(0, chunks, 1),
      [&](const tbb::blocked_range<Index>& range) {
        for (Index c = range.begin(); c != range.end(); ++c) body(c * chunk, std::min(count, (c + 1) * chunk), c);
      },
      tbb::simple_partitioner());
}

/// The sum of f(begin, end) over the fixed chunks of [0, count), added in chunk order (the same
/// bits on any number of threads). `partial` is scratch.
template <typename Sum>
double sum_chunks(Index count, Index chunk, std::vector<double>* partial, const Sum& sum) {
  const Index chunks = (count + chunk - 1) / chunk;
  partial->assign(static_cast<std::size_t>(std::max<Index>(chunks, 1)), 0.0);
  for_chunks(count, chunk, [&](Index begin, Index end, Index c) { (*partial)[c] = sum(begin, end); });
  double total = 0;
  for (const double s : *partial) total += s;
  return total;
}

/// The least of least(begin, end) over the fixed chunks of [0, count) and `bound` (the answer
/// when count is 0). Exact on any number of threads. `partial` is scratch.
template <typename Least>
double min_chunks(Index count, Index chunk, double bound, std::vector<double>* partial, const Least& least) {
  partial->assign(static_cast<std::size_t>((count + chunk - 1) / chunk), bound);
  for_chunks(count, chunk, [&](Index begin, Index end, Index c) { (*partial)[c] = least(begin, end); });
  double result = bound;
  for (const double value : *partial) result = std::min(result, value);
  return result;
}

/// Calls body(begin, end, out) over the fixed chunks of [0, count), in parallel, each chunk
/// appending its findings to a vector `out` of its own, and appends those to *into in chunk
/// order: the result does not depend on the number of threads. The chunks' vectors are `parts`,
/// cleared first, so that a caller that keeps them reuses their memory.
template <typename T, typename Body>
void append_chunks(Index count, Index chunk, std::vector<T>* into, std::vector<std::vector<T>>* parts, const Body& body) {
  parts->resize(static_cast<std::size_t>((count + chunk - 1) / chunk));
  for_chunks(count, chunk, [&](Index begin, Index end, Index c) {
    std::vector<T>* out = &(*parts)[static_cast<std::size_t>(c)];
    out->clear();
    body(begin, end, out);
  });
  for (const std::vector<T>& part : *parts) into->insert(into->end(), part.begin(), part.end());
}

/// The same with vectors of its own for the chunks.
template <typename T, typename Body>
void append_chunks(Index count, Index chunk, std::vector<T>* into, const Body& body) {
  std::vector<std::vector<T>> parts;
  append_chunks(count, chunk, into, &parts, body);
}

class BlockSparseMatrix {
 public:
  /// The pattern in which every two nodes of a tet, every two of the `extra` groups (eight
  /// nodes, the two tets a spring joins) and the two of each of `couplings` (blocks wanted in
  /// both orders: surface contact's), are coupled; the diagonal is always present. Fills
  /// `tet_slots` with the 16 slots of each tet: slot of (row node a, column node b) is
  /// tet_slots[t][4 a + b]. Stored compactly (no room left in rows: at 100k tets a matrix a
  /// third larger fell out of the cache and made each product three times slower). O(sum over
  /// nodes of the tets around it), parallel over rows.
  void build(Index num_nodes, std::span<const std::array<Index, 4>> tets, std::span<const std::array<Index, 8>> extra,
             std::vector<std::array<Index, 16>>* tet_slots, std::span<const std::array<Index, 2>> couplings = {});

  /// Appends rows (new nodes) holding their diagonal block. No slot moves.
  void add_rows(Index count);
  /// The slot of block (row, column), added (zero) when missing: blocks added after a build go to
  /// a small area of their own, so no slot moves. O(log row length) (see slot).
  Index find_or_add(Index row, Index column);

  Index num_rows() const { return static_cast<Index>(diagonal_.size()); }
  /// Blocks in the pattern (a coupling a cut removed stays, as zeros, until the next build).
  Index num_blocks() const { return static_cast<Index>(columns_.size() + added_columns_.size()); }
  Index num_added_blocks() const { return static_cast<Index>(added_columns_.size()); }
  /// The slot of block (row, column), or -1 when it is not in the pattern: a binary search of the
  /// build's row, then a hash of the added blocks (surface contact adds a block per pair of nodes
  /// its terms couple, up to 256 per term and a million an assembly on a pile, so a scan of the
  /// row, which contact makes long, took a quarter of a piled step). O(log row length).
  Index slot(Index row, Index column) const;
  Index diagonal_slot(Index row) const { return diagonal_[row]; }
  /// The slot of the transposed block: (column, row) for the block (row, column) in `slot`, or
  /// -1 while that one is not in the pattern. O(1) (kept through builds and added blocks), so
  /// that a symmetric scatter looks up half its blocks.
  Index transposed_slot(Index slot) const { return transposed_[static_cast<std::size_t>(slot)]; }
  /// Calls visit(slot, column) for each block of `row`: those of the build by ascending column,
  /// then those added since.
  template <typename Visit>
  void for_each_block(Index row, Visit&& visit) const {
    if (row < built_rows()) {
      for (Index k = row_start_[row]; k < row_start_[row + 1]; ++k) visit(k, columns_[k]);
    }
    for (const Index k : added_[row]) visit(k, added_columns_[k - static_cast<Index>(columns_.size())]);
  }
  /// How the blocks are stored: in double, or in single precision (half the memory the products
  /// stream; for the real-time mode, whose budget leaves residuals far above float rounding).
  /// Changing it zeroes the values.
  void set_single_precision(bool single);
  bool single_precision() const { return single_; }

  /// Block `slot` += scale * m (9 values, row-major), or its transpose.
  void add(Index slot, const double* m, double scale = 1) {
    if (single_) {
      add_to(f_values(slot), m, scale);
    } else {
      add_to(d_values(slot), m, scale);
    }
  }
  void add_transposed(Index slot, const double* m) {
    const double t[9] = {m[0], m[3], m[6], m[1], m[4], m[7], m[2], m[5], m[8]};
    add(slot, t);
  }
  /// Adds `value` to the three diagonal entries of row `row`'s diagonal block.
  void add_to_diagonal(Index row, double value) {
    const double m[9] = {value, 0, 0, 0, value, 0, 0, 0, value};
    add(diagonal_slot(row), m);
  }
  /// Block `slot` into `out` (9 values, row-major).
  void read(Index slot, double* out) const {
    if (single_) {
      const float* v = const_cast<BlockSparseMatrix*>(this)->f_values(slot);
      for (int k = 0; k < 9; ++k) out[k] = v[k];
    } else {
      const double* v = const_cast<BlockSparseMatrix*>(this)->d_values(slot);
      for (int k = 0; k < 9; ++k) out[k] = v[k];
    }
  }
  /// Where block `slot` is (for prefetching).
  const void* address(Index slot) const {
    auto* self = const_cast<BlockSparseMatrix*>(this);
    return single_ ? static_cast<const void*>(self->f_values(slot)) : static_cast<const void*>(self->d_values(slot));
  }
  void set_zero();
  /// this += weight * other, for a matrix with the same pattern and precision (a copy of this
  /// one, to which blocks may have been added since: the other holds zeros there).
  void add_scaled(const BlockSparseMatrix& other, double weight);

  /// y = A x restricted to the nodes with free[n] != 0 (y is 0 at the others, and x is read as 0
  /// there). x and y hold 3 values per node.
  void multiply(const double* x, double* y, const std::uint8_t* free) const;
  /// Same for one chunk of rows, returning sum over those rows of x . (A x) (for CG's step).
  double multiply_rows(Index begin, Index end, const double* x, double* y, const std::uint8_t* free) const;

 private:
  template <typename Value>
  static void add_to(Value* v, const double* m, double scale) {
    for (int k = 0; k < 9; ++k) v[k] = static_cast<Value>(v[k] + scale * m[k]);
  }
  template <typename Value>
  double multiply_rows_stored(Index begin, Index end, const double* x, double* y, const std::uint8_t* free, const Value* built,
                              const Value* added) const;
  double* d_values(Index slot) {
    const auto built = static_cast<Index>(columns_.size());
    return slot < built ? values_.data() + 9 * static_cast<std::size_t>(slot) : added_values_.data() + 9 * static_cast<std::size_t>(slot - built);
  }
  float* f_values(Index slot) {
    const auto built = static_cast<Index>(columns_.size());
    return slot < built ? single_values_.data() + 9 * static_cast<std::size_t>(slot)
                        : single_added_values_.data() + 9 * static_cast<std::size_t>(slot - built);
  }
  // 9 values per slot, of the build and of the blocks added since; only the arrays of the
  // precision in use are allocated.
  void resize_values();
  bool single_ = false;
  Index built_rows() const { return static_cast<Index>(row_start_.size()) - 1; }
  // The build: compressed rows.
  std::vector<Index> row_start_{0};
  std::vector<Index> columns_;
  std::vector<double> values_;
  std::vector<float> single_values_;
  // Blocks added since, by row; their slots follow the build's.
  std::vector<std::vector<Index>> added_;
  std::vector<Index> added_columns_;
  std::vector<double> added_values_;
  std::vector<float> single_added_values_;
  // The added blocks' slots by (row, column): open addressing, linear probing, at most half full.
  static constexpr std::uint64_t kNoKey = ~std::uint64_t{0};
  static std::uint64_t key(Index row, Index column) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(row)) << 32) | static_cast<std::uint32_t>(column);
  }
  Index added_slot(std::uint64_t key) const;
  // Indexes a block just added (already in added_ and added_columns_), growing the table first
  // where it would be more than half full.
  void index_added(std::uint64_t key, Index slot);
  void place_added(std::uint64_t key, Index slot);  // into a free entry; the table has room
  std::vector<std::uint64_t> added_keys_;
  std::vector<Index> added_key_slots_;
  std::vector<Index> diagonal_;
  std::vector<Index> transposed_;  // per slot, the slot of the transposed block (or -1)
};

struct ConjugateGradientOptions {
  int max_iterations = 0;  ///< 0: no limit but 10 times the unknowns (a safeguard)
  /// Stop once r^T W r <= absolute_target or <= relative_target^2 times its starting value, with
  /// W = diag(weight) per node (the solver's measure of the residual; the simulator passes dt^2 /
  /// mass, so that it bounds the energy the remaining error is worth).
  double absolute_target = 0;
  double relative_target = 0;
};

struct ConjugateGradientReport {
  int iterations = 0;
  double weighted_residual = 0;  ///< r^T W r at the end
  bool reached_target = false;
};

/// Solves A d = b over the free nodes by conjugate gradients preconditioned with the inverses of
/// A's 3 x 3 diagonal blocks, starting from d (a warm start; zero it for none). O(nnz) per
/// iteration, no allocation once `workspace` has grown to size.
struct ConjugateGradientWorkspace {
  std::vector<double> r, z, p, q;
  std::vector<std::array<double, 9>> inverse_diagonal;
  std::vector<double> partial;
};
ConjugateGradientReport conjugate_gradients(const BlockSparseMatrix& a, std::span<const double> b, std::span<double> d,
                                            std::span<const std::uint8_t> free, std::span<const double> weight,
                                            const ConjugateGradientOptions& options, ConjugateGradientWorkspace* workspace);

/// Solves A d = b over the free nodes directly: their part of the matrix as an Eigen sparse
/// matrix, factorised by LDL^T (d is 0 at the others). For small or badly conditioned systems,
/// where conjugate gradients would need many iterations. The fill-reducing order and symbolic
/// factorisation are kept while the pattern and the free nodes stay the same, so a Newton loop
/// pays them once.
class DirectSolver {
 public:
  DirectSolver();
  ~DirectSolver();
  /// False when the factorisation fails.
  bool solve(const BlockSparseMatrix& a, std::span<const std::uint8_t> free, std::span<const double> b, std::span<double> d);
  /// Whether the last matrix solved was positive definite (every pivot of D positive), so that
  /// its solution is a descent direction.
  bool positive_definite() const;

 private:
  struct Factor;
  std::unique_ptr<Factor> factor_;
};

/// A one-off DirectSolver::solve.
bool solve_direct(const BlockSparseMatrix& a, std::span<const std::uint8_t> free, std::span<const double> b, std::span<double> d);

}  // namespace tetcut::sim::detail
