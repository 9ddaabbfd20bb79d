// Backward Euler as energy minimisation (the incremental potential), by Newton's method over the
// free nodes: projected element Hessians assembled into the block pattern, conjugate gradients
// (or a sparse LDL^T), and a backtracking line search on the potential.
//
// Each Newton iteration costs one Hessian assembly, one linear solve and, usually, one trial
// evaluation (energy and gradient at the full step), all O(tets) or O(nonzeros) on all cores. The
// gradient at the accepted point serves both the next iteration and the convergence test: for a
// dynamic step the Hessian is at least M / dt^2, so g^T H^-1 g <= dt^2 g^T M^-1 g bounds the
// Newton decrement without a solve, and a step that passes it ends after its first solve.

#include <tetcut/error.hpp>
#include <tetcut/sim.hpp>

#include "sim/line_search.hpp"
#include "sim/simulator_state.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "util/stopwatch.hpp"

namespace tetcut::sim {
namespace {

using detail::kArmijo;
using detail::kEnergyRounding;
// Halvings of the step before the line search gives up (t = 2^-40: the limit of precision).
constexpr int kMaxHalvings = 40;
// The linear solve aims to leave a residual worth this share of the convergence threshold, so
// that the next gradient passes the test with room for the nonlinear terms of the step.
constexpr double kSolveShare = 0.1;
// After a step the line search had to shorten (strongly nonlinear), an accurate solve is wasted:
// the next solve stops at this residual relative to its start (inexact Newton).
constexpr double kInexactNewton = 0.1;

// Blocks (72 bytes each in double) past which the matrix stops fitting in this machine's caches
// and its products become bound by memory (8 MB; a 114k-tet matrix has 19 MB): measured, single
// precision is a fifth faster at 114k tets and 40% slower at 11.5k.
constexpr Index kSinglePrecisionBlocks = 8 * 1024 * 1024 / 72;

// The potential's terms other than elasticity, at positions `at`, for the free nodes' gradient
// (and Hessian). A Newton step's pieces, gathered so that energy, gradient and Hessian are written
// once.
struct Potential {
  SimulatorState& s;
  bool inertia;
  double h;
  Vec3 gravity;
  double inertia_weight, damping_weight;
  bool stiffness_damping;

  // Inertia, mass damping and gravity per node; the Hessian's diagonal when `hessian`.
  double nodal(const Points& at, std::vector<double>* g, bool hessian) const {
    const Index n = s.num_nodes();
    return detail::sum_chunks(n, detail::kNodeChunk, &s.partial, [&](Index begin, Index end) {
      double energy = 0;
      for (Index v = begin; v < end; ++v) {
        const double m = s.mass[v];
        const Vec3 p = at.row(v).transpose();
        Vec3 grad = -m * gravity;
        energy -= m * gravity.dot(p);
        if (inertia) {
          const Vec3 from_prediction = p - s.prediction.row(v).transpose(), from_start = p - s.start.row(v).transpose();
          energy += 0.5 * m / (h * h) * from_prediction.squaredNorm() + 0.5 * m * s.material.mass_damping / h * from_start.squaredNorm();
          grad += m / (h * h) * from_prediction + m * s.material.mass_damping / h * from_start;
        }
        for (int k = 0; k < 3; ++k) (*g)[3 * v + k] += grad[k];
        if (hessian && inertia) {
          s.hessian.add_to_diagonal(v, m * inertia_weight);
          s.ledger_nodal[v] = m * inertia_weight;
        }
      }
      return energy;
    });
  }

  // The recorded constraint terms (c c^T times d2E each) added into the matrix with `sign`; a
  // surface contact pair couples nodes no element does, whose blocks are added to the pattern
  // here. The blocks are looked up first, in parallel (a search of the row, then of the added
  // blocks' table: 173k blocks an assembly on the sliced hand), those missing added on one
  // thread, then the terms are added in parallel over fixed chunks of rows, each chunk taking
  // its rows' blocks in the terms' order: every block sums its terms in that order, so the sums
  // do not depend on the number of threads (added on one thread, they were 2.2 ms of a 20 ms
  // step there). O(sum of count^2).
  void add_recorded_terms(double sign) const {
    const std::vector<SimulatorState::ConstraintTerm>& terms = s.ledger_constraints;
    const auto count = static_cast<Index>(terms.size());
    if (count == 0) return;
    const Clock::time_point start = Clock::now();
    s.term_block_start.resize(terms.size() + 1);
    s.term_block_start[0] = 0;
    for (std::size_t k = 0; k < terms.size(); ++k) s.term_block_start[k + 1] = s.term_block_start[k] + terms[k].count * terms[k].count;
    s.term_slots.resize(static_cast<std::size_t>(s.term_block_start.back()));
    constexpr Index kTermChunk = 256;
    detail::for_chunks(count, kTermChunk, [&](Index begin, Index end, Index) {
      for (Index k = begin; k < end; ++k) {
        const SimulatorState::ConstraintTerm& t = terms[static_cast<std::size_t>(k)];
        Index* slot = &s.term_slots[static_cast<std::size_t>(s.term_block_start[static_cast<std::size_t>(k)])];
        // Terms come in the order of their pairs, pairs of one pair of copies together: about half
        // couple the very nodes the term before did, whose blocks are the same.
        const SimulatorState::ConstraintTerm* before = k > begin ? &terms[static_cast<std::size_t>(k) - 1] : nullptr;
        if (before && before->count == t.count && std::equal(t.nodes.begin(), t.nodes.begin() + t.count, before->nodes.begin())) {
          std::copy_n(slot - t.count * t.count, t.count * t.count, slot);
          continue;
        }
        // The diagonal's blocks are known, and a block's transpose is found from it: half the
        // other blocks are looked up.
        for (int a = 0; a < t.count; ++a) {
          slot[a * t.count + a] = s.hessian.diagonal_slot(t.nodes[a]);
          for (int b = a + 1; b < t.count; ++b) {
            const Index found = s.hessian.slot(t.nodes[a], t.nodes[b]);
            slot[a * t.count + b] = found;
            slot[b * t.count + a] = found >= 0 ? s.hessian.transposed_slot(found) : s.hessian.slot(t.nodes[b], t.nodes[a]);
          }
        }
      }
    });
    for (std::size_t k = 0; k < terms.size(); ++k) {
      const SimulatorState::ConstraintTerm& t = terms[k];
      Index* slot = &s.term_slots[static_cast<std::size_t>(s.term_block_start[k])];
      for (int a = 0; a < t.count; ++a) {
        for (int b = 0; b < t.count; ++b, ++slot) {
          if (*slot < 0) *slot = s.hessian.find_or_add(t.nodes[a], t.nodes[b]);
        }
      }
    }
    // Each (term, corner) by the chunk of its corner's row (a counting sort: the terms' order kept).
    constexpr Index kRowChunks = 64;
    const Index rows_per_chunk = (s.num_nodes() + kRowChunks - 1) / kRowChunks;
    s.term_row_start.assign(kRowChunks + 1, 0);
    for (const SimulatorState::ConstraintTerm& t : terms) {
      for (int a = 0; a < t.count; ++a) ++s.term_row_start[static_cast<std::size_t>(t.nodes[a] / rows_per_chunk) + 1];
    }
    for (Index c = 0; c < kRowChunks; ++c) s.term_row_start[c + 1] += s.term_row_start[c];
    s.term_rows.resize(static_cast<std::size_t>(s.term_row_start.back()));
    s.term_row_fill.assign(s.term_row_start.begin(), s.term_row_start.end() - 1);
    for (Index k = 0; k < count; ++k) {
      const SimulatorState::ConstraintTerm& t = terms[static_cast<std::size_t>(k)];
      for (int a = 0; a < t.count; ++a) s.term_rows[static_cast<std::size_t>(s.term_row_fill[static_cast<std::size_t>(t.nodes[a] / rows_per_chunk)]++)] = {k, a};
    }
    detail::for_chunks(kRowChunks, 1, [&](Index chunk, Index, Index) {
      for (Index e = s.term_row_start[chunk]; e < s.term_row_start[chunk + 1]; ++e) {
        const auto [k, a] = s.term_rows[static_cast<std::size_t>(e)];
        const SimulatorState::ConstraintTerm& t = terms[static_cast<std::size_t>(k)];
        double m[9];
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) m[3 * i + j] = t.d2E(i, j);
        }
        const Index* slot = &s.term_slots[static_cast<std::size_t>(s.term_block_start[static_cast<std::size_t>(k)] + a * t.count)];
        for (int b = 0; b < t.count; ++b) s.hessian.add(slot[b], m, sign * t.coefficients[a] * t.coefficients[b]);
      }
    });
    s.constraint_matrix_seconds += seconds_since(start);
  }

  // Contact and springs: their energies and gradients; into the matrix (and recorded, for a later
  // step that reuses it) through add_recorded_terms. The surface contact's terms in parallel
  // (surface_terms), the few others on one thread.
  double constraints(const Points& at, std::vector<double>* g, bool hessian) const {
    double energy = 0;
    if (hessian) s.ledger_constraints.clear();
    s.for_each_constraint(
        at,
        [&](const std::array<Index, 16>& nodes, const std::array<double, 16>& c, int count, double e, const Vec3& dE, const Mat3& d2E) {
          energy += e;
          for (int a = 0; a < count; ++a) {
            for (int i = 0; i < 3; ++i) (*g)[3 * nodes[a] + i] += c[a] * dE[i];
          }
          if (hessian) s.ledger_constraints.emplace_back(nodes, c, count, d2E);
        },
        false);
    energy += surface_terms(at, g, hessian);
    if (hessian) add_recorded_terms(1);
    return energy;
  }

  // The surface contact's active terms (7.4k at most on the sliced hand, where taking them on one
  // thread, each term's gradient and its copy into the ledger, took 1.1 to 1.35 ms an evaluation,
  // 0.14 ms now): their energy, their gradient added into g, and, with `hessian`, their copies
  // appended to the ledger. In parallel over groups of the terms' fixed chunks, each group
  // summing into its own gradient (the first into g), the groups then added in order: the number
  // of groups follows the terms and nodes, not the threads, so neither do the sums.
  // O(terms x nodes each + groups x nodes).
  double surface_terms(const Points& at, std::vector<double>* g, bool hessian) const {
    if (!s.surface_contact.enabled()) return 0;
    const std::vector<std::vector<detail::ActiveTerm>>& chunks = s.surface_contact.active_chunks(at);
    const auto chunk_count = static_cast<Index>(chunks.size());
    std::size_t total = 0;
    for (const std::vector<detail::ActiveTerm>& chunk : chunks) total += chunk.size();
    if (total == 0) return 0;
    // A group is worth its own gradient once its terms touch about as many entries as it has.
    constexpr std::size_t kMaxGroups = 4, kEntriesPerTerm = 3 * 16;
    const std::size_t size = g->size();
    const auto groups = static_cast<Index>(std::clamp<std::size_t>(total * kEntriesPerTerm / std::max<std::size_t>(size, 1), 1, kMaxGroups));
    const std::size_t ledger_start = s.ledger_constraints.size();
    if (hessian) s.ledger_constraints.resize(ledger_start + total);
    s.term_group_gradient.resize(static_cast<std::size_t>(groups));
    double group_energy[kMaxGroups] = {};
    detail::for_chunks(groups, 1, [&](Index group, Index, Index) {
      std::vector<double>* into = g;
      if (group > 0) {
        into = &s.term_group_gradient[static_cast<std::size_t>(group)];
        into->assign(size, 0.0);
      }
      const Index first = chunk_count * group / groups, last = chunk_count * (group + 1) / groups;
      std::size_t at_ledger = ledger_start;
      for (Index c = 0; c < first; ++c) at_ledger += chunks[static_cast<std::size_t>(c)].size();
      double energy = 0;
      for (Index c = first; c < last; ++c) {
        for (const detail::ActiveTerm& a : chunks[static_cast<std::size_t>(c)]) {
          const detail::ContactTerm& t = a.term;
          energy += a.energy;
          for (int k = 0; k < t.count; ++k) {
            for (int i = 0; i < 3; ++i) (*into)[3 * t.nodes[k] + i] += t.coefficients[k] * a.gradient[i];
          }
          if (hessian) {
            SimulatorState::ConstraintTerm& recorded = s.ledger_constraints[at_ledger++];
            recorded.nodes = t.nodes;
            recorded.coefficients = t.coefficients;
            recorded.count = t.count;
            recorded.d2E = a.hessian;
          }
        }
      }
      group_energy[group] = energy;
    });
    double energy = group_energy[0];
    for (Index group = 1; group < groups; ++group) {
      const std::vector<double>& from = s.term_group_gradient[static_cast<std::size_t>(group)];
      for (std::size_t k = 0; k < size; ++k) (*g)[k] += from[k];
      energy += group_energy[group];
    }
    return energy;
  }

  // Reusing the matrix at `at`: the recorded mass and constraint terms out, the current ones in.
  void replace_recorded_terms(const Points& at) const {
    const Index n = s.num_nodes();
    s.ledger_nodal.resize(static_cast<std::size_t>(n), 0.0);  // new nodes: nothing recorded
    for (Index v = 0; v < n; ++v) {
      const double now = s.mass[v] * inertia_weight;
      s.hessian.add_to_diagonal(v, now - s.ledger_nodal[v]);
      s.ledger_nodal[v] = now;
    }
    add_recorded_terms(-1);
    s.ledger_constraints.clear();
    s.for_each_constraint(at, [&](const std::array<Index, 16>& nodes, const std::array<double, 16>& c, int count, double, const Vec3&,
                                  const Mat3& d2E) { s.ledger_constraints.emplace_back(nodes, c, count, d2E); });
    add_recorded_terms(1);
  }

  // Rayleigh stiffness damping: (damping_weight / 2) u^T K u with u = at - start and K the
  // stiffness at the start of the step (s.damping, a copy of the pattern).
  double damping(const Points& at, std::vector<double>* g, bool hessian) const {
    if (!stiffness_damping) return 0;
    const Index n = s.num_nodes();
    s.displacement = at - s.start;
    s.product.resize(3 * static_cast<std::size_t>(n));
    s.all.assign(static_cast<std::size_t>(n), 1);
    const double uKu = detail::sum_chunks(n, detail::kNodeChunk, &s.partial, [&](Index begin, Index end) {
      return s.damping.multiply_rows(begin, end, s.displacement.data(), s.product.data(), s.all.data());
    });
    for (std::size_t k = 0; k < s.product.size(); ++k) (*g)[k] += damping_weight * s.product[k];
    if (hessian) s.hessian.add_scaled(s.damping, damping_weight);
    return 0.5 * damping_weight * uKu;
  }

  // The potential at `at` and its gradient (3 per node, written over `g`).
  double evaluate(const Points& at, std::vector<double>* g) const {
    std::fill(g->begin(), g->end(), 0.0);
    double energy = s.elastic_gradient(at, g);
    energy += nodal(at, g, false) + constraints(at, g, false) + damping(at, g, false);
    return energy;
  }
  // The same, and the Hessian into s.hessian.
  double evaluate_with_hessian(const Points& at, std::vector<double>* g) const {
    std::fill(g->begin(), g->end(), 0.0);
    s.ledger_nodal.assign(static_cast<std::size_t>(s.num_nodes()), 0.0);
    double energy = s.assemble_hessian(at, g);
    energy += nodal(at, g, true) + constraints(at, g, true) + damping(at, g, true);
    // A later step may reuse it (not with stiffness damping, whose term changes every step).
    s.reusable = inertia && !stiffness_damping;
    s.reusable_age = 0;
    s.assembled_at = at;
    s.reuse_take_out.clear();
    s.reuse_put_in.clear();
    return energy;
  }
};

// The options a step needs, checked before anything changes.
void check_step_options(const StepOptions& options, bool inertia) {
  if (inertia && !(options.dt > 0 && std::isfinite(options.dt))) throw Error(ErrorKind::kInvalidArgument, "the time step must be positive");
  if (!(options.tolerance > 0) || !std::isfinite(options.tolerance)) throw Error(ErrorKind::kInvalidArgument, "the tolerance must be positive");
  if (options.max_newton_iterations < 1) throw Error(ErrorKind::kInvalidArgument, "at least one Newton iteration is needed");
  if (options.max_cg_iterations < 0) throw Error(ErrorKind::kInvalidArgument, "the conjugate gradient budget must not be negative");
  if (!options.gravity.allFinite()) throw Error(ErrorKind::kInvalidArgument, "gravity must be finite");
  if (options.reuse_hessian < 1) throw Error(ErrorKind::kInvalidArgument, "reuse_hessian must be at least 1");
}

// The matrix's pattern brought up to date with the mesh, in single precision when it is large
// enough to be bound by memory.
void prepare_matrix(SimulatorState& s, const StepOptions& options) {
  s.refresh_structure();
  const bool single = options.single_precision_matrix && s.hessian.num_blocks() > kSinglePrecisionBlocks;
  if (s.hessian.single_precision() != single) {
    s.hessian.set_single_precision(single);
    s.reusable = false;  // the values are gone
  }
}

// The step's start: which nodes are free, the start and predicted positions, and the first guess
// (the prediction or the start, as the options say, with constrained nodes at their targets).
void start_step(SimulatorState& s, bool inertia, double h, FirstGuess first_guess) {
  const Index n = s.num_nodes();
  // Free nodes: not constrained, and holding mass (a node in no tet has no energy at all).
  s.free.resize(static_cast<std::size_t>(n));
  for (Index v = 0; v < n; ++v) s.free[v] = s.constraint[v] < 0 && s.mass[v] > 0;
  s.start = s.x;
  s.prediction = inertia ? Points(s.x + h * s.v) : s.x;
  Points& x = s.x;
  if (first_guess == FirstGuess::kPrediction) x = s.prediction;  // else x is the start already
  for (Index v = 0; v < n; ++v) {
    if (s.constraint[v] >= 0) x.row(v) = s.target.row(v);
  }
}

// Friction (against obstacles, and of surface contact) acts over the step with the contacts of
// its start (lagged). With surface contact the start is where no two parts of the surface touch;
// the first guess may not go beyond where two would meet (the kinematic nodes then go only part
// of the way this step).
void lag_contact(SimulatorState& s, bool inertia, StepReport* report) {
  if (inertia) {
    s.lag_obstacle_friction();
  } else {
    s.obstacle_friction.clear();
  }
  if (!s.surface_contact.enabled()) return;
  const Clock::time_point contact_start = Clock::now();
  Points& x = s.x;
  // The two sides of fresh cuts are guarded against passing through each other over the step
  // (first: the last step's joins measured what the guards need, at these positions).
  s.surface_contact.lag_guards(s.start);
  // Friction acts over this step with the normals and forces of its start (lagged).
  // (A static solve has no step to slip over: none.)
  if (inertia) {
    s.surface_contact.lag_friction(s.start);
  } else {
    s.surface_contact.drop_friction();
  }
  s.displacement = x - s.start;
  // A first guess that moves nothing (the start, FirstGuess::kStart, with nothing kinematic
  // moving; or a prediction at rest): nothing to shorten, and no candidate list to cover a move.
  const double t = s.displacement.isZero(0) ? 1.0 : s.surface_contact.max_step(s.start, s.displacement.data());
  if (t < 1) {
    x = s.start + t * s.displacement;
    ++report->contact_limited_steps;
  }
  report->contact_seconds += seconds_since(contact_start);
}

// The potential of this step, its buffers sized and zeroed, and Rayleigh stiffness damping (which
// uses the projected stiffness at the start of the step) set up.
Potential step_potential(SimulatorState& s, const StepOptions& options, bool inertia, double h) {
  const std::size_t size = 3 * static_cast<std::size_t>(s.num_nodes());
  Potential potential{s, inertia, h, options.gravity, inertia ? 1 / (h * h) + s.material.mass_damping / h : 0.0, 0.0, false};
  s.current_gradient.assign(size, 0.0);
  s.trial_gradient.assign(size, 0.0);
  s.direction.assign(size, 0.0);
  s.rhs.assign(size, 0.0);
  s.weight.assign(static_cast<std::size_t>(s.num_nodes()), 0.0);
  if (inertia && s.material.stiffness_damping > 0) {
    s.assemble_hessian(s.start, &s.current_gradient);
    s.damping = s.hessian;
    potential.stiffness_damping = true;
    potential.damping_weight = s.material.stiffness_damping / h;
  }
  return potential;
}

// The energy the tolerance is relative to: the kinetic energy scale M (size / h)^2 of a dynamic
// step, the elastic scale mu V of a static solve.
double energy_scale(const SimulatorState& s, bool inertia, double h) {
  double total_mass = s.mass.sum(), volume = 0;
  for (const SimulatorState::Element& e : s.elements) volume += e.volume;
  return inertia ? total_mass * s.size * s.size / (h * h) : s.parameters.mu * volume;
}

// The Newton iterations of one step: what their pieces share, and the pieces (the direction, the
// line search, the measures of the gradient).
struct Newton {
  SimulatorState& s;
  const StepOptions& options;
  const Potential& potential;
  StepReport& report;
  bool inertia;
  Index n;
  std::size_t size;
  double threshold;  // half the Newton decrement at which the step has converged

  // Sets the bound of half the Newton decrement from a gradient, (1/2) sum |g_v|^2 / (w m_v):
  // its weights 1 / (w m_v) over the free nodes of a dynamic step (none for a static solve).
  void set_decrement_weights() const {
    for (Index v = 0; v < n; ++v) s.weight[v] = inertia && s.free[v] ? 1 / (potential.inertia_weight * s.mass[v]) : 0.0;
  }

  double decrement_bound(const std::vector<double>& g) const {
    double bound = 0;
    for (Index v = 0; v < n; ++v) bound += s.weight[v] * (g[3 * v] * g[3 * v] + g[3 * v + 1] * g[3 * v + 1] + g[3 * v + 2] * g[3 * v + 2]);
    return 0.5 * bound;
  }

  // The gradient's size where energies cannot tell: the bound of the decrement (dynamic steps)
  // or the plain squared norm over the free nodes (static solves).
  double gradient_measure(const std::vector<double>& g) const {
    if (inertia) return decrement_bound(g);
    double sum = 0;
    for (std::size_t k = 0; k < size; ++k) sum += s.free[k / 3] ? g[k] * g[k] : 0.0;
    return sum;
  }

  // The Newton direction (into s.direction) from the matrix and the gradient at x; returns the
  // decrement -g . d. After a shortened step (`full_step` false) the solve may be inexact.
  double solve(bool full_step) const {
    const Clock::time_point solve_start = Clock::now();
    for (std::size_t k = 0; k < size; ++k) s.rhs[k] = s.free[k / 3] ? -s.current_gradient[k] : 0.0;
    std::fill(s.direction.begin(), s.direction.end(), 0.0);
    if (options.solver == LinearSolver::kCholesky) {
      if (!detail::solve_direct(s.hessian, s.free, s.rhs, s.direction)) throw Error(ErrorKind::kInvalidInput, "the Newton system could not be factorised");
    } else {
      if (!inertia) {
        // No mass to measure the residual by: the diagonal's, an estimate of H^-1.
        for (Index v = 0; v < n; ++v) {
          double b[9];
          s.hessian.read(s.hessian.diagonal_slot(v), b);
          const double diagonal = (b[0] + b[4] + b[8]) / 3;
          s.weight[v] = s.free[v] && diagonal > 0 ? 1 / diagonal : 0.0;
        }
      }
      detail::ConjugateGradientOptions cg;
      cg.max_iterations = options.max_cg_iterations;
      cg.absolute_target = 2 * kSolveShare * threshold;
      cg.relative_target = full_step ? 0.0 : kInexactNewton;
      const detail::ConjugateGradientReport solved = detail::conjugate_gradients(s.hessian, s.rhs, s.direction, s.free, s.weight, cg, &s.cg);
      report.cg_iterations += solved.iterations;
    }
    report.solve_seconds += seconds_since(solve_start);
    double decrement = 0;
    for (std::size_t k = 0; k < size; ++k) decrement += s.rhs[k] * s.direction[k];
    return decrement;
  }

  // Backtracking (Armijo) on the potential along s.direction, from the longest step that keeps
  // the surface's parts apart. When a step is accepted, x, its gradient and `energy` move there.
  // Returns whether one was, and the last step length tried in `t`.
  bool line_search(double decrement, double* energy, double* t) const {
    Points& x = s.x;
    *t = 1;
    if (s.surface_contact.enabled()) {
      const Clock::time_point contact_start = Clock::now();
      *t = s.surface_contact.max_step(x, s.direction.data());
      if (*t < 1) ++report.contact_limited_steps;
      report.contact_seconds += seconds_since(contact_start);
    }
    const Clock::time_point search_start = Clock::now();
    bool accepted = false;
    for (int halving = 0; halving < kMaxHalvings; ++halving) {
      s.trial = x;
      for (Index v = 0; v < n; ++v) {
        if (!s.free[v]) continue;
        for (int k = 0; k < 3; ++k) s.trial(v, k) += *t * s.direction[3 * v + k];
      }
      const double trial_energy = potential.evaluate(s.trial, &s.trial_gradient);
      // Near convergence the decrease Armijo asks for is below the rounding of the energy
      // itself; there the gradient decides (the bound of the decrement must fall).
      const bool within_rounding = kArmijo * *t * decrement <= kEnergyRounding * std::abs(*energy);
      const bool sufficient = trial_energy <= *energy - kArmijo * *t * decrement ||
                              (within_rounding && gradient_measure(s.trial_gradient) < gradient_measure(s.current_gradient));
      if (sufficient) {
        x.swap(s.trial);
        s.current_gradient.swap(s.trial_gradient);
        *energy = trial_energy;
        accepted = true;
        break;
      }
      *t /= 2;
    }
    report.line_search_seconds += seconds_since(search_start);
    return accepted;
  }
};

// After the last iteration: surface contact's joins for the next step, the active pairs counted,
// and the velocities of a dynamic step.
void finish_step(SimulatorState& s, bool inertia, double h, StepReport* report) {
  const Points& x = s.x;
  if (s.surface_contact.enabled()) {
    const Clock::time_point contact_start = Clock::now();
    s.surface_contact.update_joins(x);
    s.surface_contact.for_each_active(x, [&](const detail::ContactTerm&, double, const Vec3&, const Mat3&) { ++report->contact_pairs; });
    report->contact_seconds += seconds_since(contact_start);
  }
  if (inertia) s.v = (x - s.start) / h;
}

}  // namespace

StepReport Simulator::step(const StepOptions& options) { return minimise(options, true); }

StepReport Simulator::solve_static(const StepOptions& options) {
  StepReport report = minimise(options, false);
  state_->v.setZero();
  return report;
}

// Newton's method on the step's potential: the start and first guess, the first matrix (fresh,
// or an earlier step's brought up to date), then iterations of direction, convergence test and
// line search until the decrement, or its bound from the gradient, is below the threshold.
StepReport Simulator::minimise(const StepOptions& options, bool inertia) {
  check_step_options(options, inertia);
  SimulatorState& s = *state_;
  StepReport report;
  const double matrix_seconds_before = s.constraint_matrix_seconds;
  const Clock::time_point assemble_start = Clock::now();
  prepare_matrix(s, options);
  const double h = inertia ? options.dt : 1.0;
  start_step(s, inertia, h, options.first_guess);
  lag_contact(s, inertia, &report);
  const Potential potential = step_potential(s, options, inertia, h);
  const double scale = energy_scale(s, inertia, h);
  Newton newton{s, options, potential, report, inertia, s.num_nodes(), 3 * static_cast<std::size_t>(s.num_nodes()),
                options.tolerance * options.tolerance * scale};
  newton.set_decrement_weights();

  // The first iteration may take the matrix of an earlier step (reuse_hessian), brought up to
  // date: a cut's elements, the mass, contact and spring terms of now.
  Points& x = s.x;
  const bool reused = inertia && s.reusable && s.reusable_age + 1 < options.reuse_hessian && !potential.stiffness_damping;
  double energy;
  if (reused) {
    s.apply_cut_to_reused_matrix();
    energy = potential.evaluate(x, &s.current_gradient);
    potential.replace_recorded_terms(x);
    ++s.reusable_age;
  } else {
    energy = potential.evaluate_with_hessian(x, &s.current_gradient);
  }
  bool hessian_current = true, full_step = true;
  // The best measure known of half the Newton decrement at x: the decrement itself when Newton
  // stopped there without moving, the bound from the gradient after a move (dynamic steps).
  double left = inertia ? newton.decrement_bound(s.current_gradient) : 0.0;
  report.assemble_seconds += seconds_since(assemble_start);

  // The budget, and the iterations the safety valve may add to it (rescue_residual).
  int iterations_allowed = options.max_newton_iterations;
  const double rescue_bound = options.rescue_residual * options.rescue_residual * scale;
  for (int iteration = 0; iteration < iterations_allowed; ++iteration) {
    if (!hessian_current) {
      const Clock::time_point t0 = Clock::now();
      // Where the last move ended at what the guards' planes allow, they are made again here:
      // the potential changes with them, so it is evaluated after.
      if (s.surface_contact.guards_held_back()) s.surface_contact.lag_guards(x);
      energy = potential.evaluate_with_hessian(x, &s.current_gradient);
      report.assemble_seconds += seconds_since(t0);
    }
    hessian_current = false;
    const bool matrix_reused = reused && iteration == 0;
    const double decrement = newton.solve(full_step);
    report.newton_iterations = iteration + 1;
    if (!(decrement >= 0) || !std::isfinite(decrement)) break;  // not a descent direction: give up
    // With a reused matrix the decrement is not this step's Newton decrement: it does not end the
    // step (the gradient bound after the step does).
    if (!matrix_reused) left = decrement / 2;
    if (decrement / 2 <= newton.threshold && !matrix_reused) {
      report.converged = true;
      break;
    }
    double t = 1;
    const bool accepted = newton.line_search(decrement, &energy, &t);
    full_step = t == 1;
    if (!accepted && matrix_reused) continue;  // the old matrix's direction failed: a fresh one next
    if (!accepted) break;                      // at the limit of precision
    if (inertia) {
      left = newton.decrement_bound(s.current_gradient);
      if (left <= newton.threshold) {
        report.converged = true;
        break;
      }
      if (iteration + 1 == iterations_allowed && options.rescue_residual > 0 && left > rescue_bound &&
          iterations_allowed < options.max_newton_iterations + options.rescue_iterations) {
        ++iterations_allowed;
        ++report.rescue_iterations;
      }
    }
  }
  report.energy = energy;
  report.residual = std::sqrt(std::max(left, 0.0) / scale);
  finish_step(s, inertia, h, &report);
  report.constraint_matrix_seconds = s.constraint_matrix_seconds - matrix_seconds_before;
  return report;
}

}  // namespace tetcut::sim
