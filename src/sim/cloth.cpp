// The cloth simulator: backward Euler as minimisation of the incremental potential, by Newton's
// method on the free nodes with the simulator's block matrix and conjugate gradients.
//
// Cost per Newton iteration: O(triangles + hinges) element work (a 6 x 6 eigen-projection per
// membrane) and a sparse LDL^T of the free nodes' system (for a sheet, O(n^1.5) with the
// fill-reducing order). Serial: the cloth meshes this serves have hundreds to a few thousand
// triangles.

#include <tetcut/cloth.hpp>
#include <tetcut/error.hpp>
#include <tetcut/sim.hpp>

#include <algorithm>
#include <cmath>
#include <map>

#include "sim/block_sparse.hpp"
#include "sim/cloth_energy.hpp"
#include "sim/line_search.hpp"
#include "util/stopwatch.hpp"

namespace tetcut::sim {

namespace {
using detail::kArmijo;
using detail::kEnergyRounding;
// Halvings of the step before the line search gives up.
constexpr int kMaxClothHalvings = 30;

// sum over free nodes of |g|^2 dt^2 / m: what a mass-only step would move, squared.
double gradient_measure(const std::vector<double>& g, const std::vector<double>& weight) {
  double sum = 0;
  for (std::size_t i = 0; i < weight.size(); ++i) {
    sum += weight[i] * (g[3 * i] * g[3 * i] + g[3 * i + 1] * g[3 * i + 1] + g[3 * i + 2] * g[3 * i + 2]);
  }
  return sum;
}
}  // namespace

struct ClothSimulator::State {
  ClothMaterial material;
  double mu = 0, lambda = 0;
  PlanarCutMesh mesh;
  std::vector<detail::MembraneElement> membranes;
  std::vector<detail::Hinge> hinges;
  Points x, v;
  Eigen::VectorXd mass;
  std::vector<std::uint8_t> free;  // 1 free, 0 pinned
  double edge_length = 1;
  // The Newton system: triangles (padded with their last node) then hinges, as 4-node groups.
  detail::BlockSparseMatrix hessian;
  std::vector<std::array<Index, 4>> groups;
  std::vector<std::array<Index, 16>> slots;
  detail::DirectSolver solver;
  std::vector<double> gradient, direction, rhs;

  void build();
  /// The incremental potential at y (inertia about `prediction`, damping about x), its gradient
  /// into `g` when not null, and the projected Hessian into `hessian` when asked.
  double potential(const Points& y, const Points& prediction, double h, const Vec3& gravity, std::vector<double>* g,
                   bool assemble, bool project = false);
  double elastic(const Points& y) const;
};

void ClothSimulator::State::build() {
  const PlanarMesh& m = mesh.mesh;
  const Index n = m.num_nodes(), t = m.num_triangles();
  const std::vector<double> fractions = mesh.material_fractions();
  membranes.resize(t);
  mass = Eigen::VectorXd::Zero(n);
  double length_sum = 0;
  for (Index c = 0; c < t; ++c) {
    const Eigen::Vector2d a = m.rest.row(m.triangles(c, 0)), b = m.rest.row(m.triangles(c, 1)), d = m.rest.row(m.triangles(c, 2));
    membranes[c] = detail::make_membrane(a, b, d, fractions[c]);
    for (int k = 0; k < 3; ++k) mass[m.triangles(c, k)] += material.density * membranes[c].area / 3;
    length_sum += (b - a).norm() + (d - b).norm() + (a - d).norm();
  }
  edge_length = t > 0 ? length_sum / (3.0 * t) : 1.0;

  // Hinges: every two copies of different triangles that share an edge's two nodes.
  struct Wing {
    Index copy, opposite, from, to;
  };
  std::map<std::array<Index, 2>, std::vector<Wing>> by_edge;
  for (Index c = 0; c < t; ++c) {
    for (int k = 0; k < 3; ++k) {
      const Index u = m.triangles(c, k), w = m.triangles(c, (k + 1) % 3), o = m.triangles(c, (k + 2) % 3);
      by_edge[{std::min(u, w), std::max(u, w)}].push_back({c, o, u, w});
    }
  }
  hinges.clear();
  for (const auto& [edge, wings] : by_edge) {
    for (std::size_t i = 0; i < wings.size(); ++i) {
      for (std::size_t j = i + 1; j < wings.size(); ++j) {
        if (mesh.triangle_parent[wings[i].copy] == mesh.triangle_parent[wings[j].copy]) continue;
        const std::array<Index, 4> nodes = {wings[i].from, wings[i].to, wings[i].opposite, wings[j].opposite};
        std::array<Eigen::Vector2d, 4> rest;
        for (int q = 0; q < 4; ++q) rest[q] = m.rest.row(nodes[q]).transpose();
        const double share = 0.5 * (fractions[wings[i].copy] + fractions[wings[j].copy]);
        hinges.push_back(detail::make_hinge(nodes, rest, material.bending_stiffness * share));
      }
    }
  }

  groups.clear();
  for (Index c = 0; c < t; ++c) groups.push_back({m.triangles(c, 0), m.triangles(c, 1), m.triangles(c, 2), m.triangles(c, 2)});
  for (const detail::Hinge& h : hinges) groups.push_back(h.nodes);
  hessian.build(n, groups, {}, &slots);
}

double ClothSimulator::State::elastic(const Points& y) const {
  const PlanarMesh& m = mesh.mesh;
  double energy = 0;
  for (Index c = 0; c < m.num_triangles(); ++c) {
    const std::array<Vec3, 3> corners = {y.row(m.triangles(c, 0)).transpose(), y.row(m.triangles(c, 1)).transpose(),
                                         y.row(m.triangles(c, 2)).transpose()};
    energy += detail::membrane_energy(membranes[c], mu, lambda, corners, nullptr, nullptr, false);
  }
  for (const detail::Hinge& h : hinges) {
    const std::array<Vec3, 4> corners = {y.row(h.nodes[0]).transpose(), y.row(h.nodes[1]).transpose(), y.row(h.nodes[2]).transpose(),
                                         y.row(h.nodes[3]).transpose()};
    energy += detail::hinge_energy(h, corners, nullptr);
  }
  return energy;
}

double ClothSimulator::State::potential(const Points& y, const Points& prediction, double h, const Vec3& gravity,
                                        std::vector<double>* g, bool assemble, bool project) {
  const PlanarMesh& m = mesh.mesh;
  const Index n = m.num_nodes();
  if (g != nullptr) g->assign(3 * static_cast<std::size_t>(n), 0.0);
  if (assemble) hessian.set_zero();
  double energy = 0;
  const double inertia = 1 / (h * h), damping = material.mass_damping / h;
  for (Index i = 0; i < n; ++i) {
    const Vec3 p = y.row(i).transpose(), from_prediction = p - prediction.row(i).transpose(), from_start = p - x.row(i).transpose();
    energy += mass[i] * (0.5 * inertia * from_prediction.squaredNorm() + 0.5 * damping * from_start.squaredNorm() - gravity.dot(p));
    if (g != nullptr) {
      const Vec3 grad = mass[i] * (inertia * from_prediction + damping * from_start - gravity);
      for (int k = 0; k < 3; ++k) (*g)[3 * i + k] += grad[k];
    }
    if (assemble) hessian.add_to_diagonal(i, mass[i] * (inertia + damping));
  }
  for (Index c = 0; c < m.num_triangles(); ++c) {
    const std::array<Index, 3> nodes = {m.triangles(c, 0), m.triangles(c, 1), m.triangles(c, 2)};
    const std::array<Vec3, 3> corners = {y.row(nodes[0]).transpose(), y.row(nodes[1]).transpose(), y.row(nodes[2]).transpose()};
    detail::Vec9 grad = detail::Vec9::Zero();
    detail::Mat9 hess = detail::Mat9::Zero();
    energy += detail::membrane_energy(membranes[c], mu, lambda, corners, g != nullptr ? &grad : nullptr, assemble ? &hess : nullptr, project);
    if (g != nullptr) {
      for (int a = 0; a < 3; ++a) {
        for (int k = 0; k < 3; ++k) (*g)[3 * nodes[a] + k] += grad[3 * a + k];
      }
    }
    if (assemble) {
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> block = hess.block<3, 3>(3 * a, 3 * b);
          hessian.add(slots[c][4 * a + b], block.data());
        }
      }
    }
  }
  for (std::size_t i = 0; i < hinges.size(); ++i) {
    const detail::Hinge& hinge = hinges[i];
    const std::array<Vec3, 4> corners = {y.row(hinge.nodes[0]).transpose(), y.row(hinge.nodes[1]).transpose(),
                                         y.row(hinge.nodes[2]).transpose(), y.row(hinge.nodes[3]).transpose()};
    Eigen::Matrix<double, 12, 1> grad = Eigen::Matrix<double, 12, 1>::Zero();
    energy += detail::hinge_energy(hinge, corners, g != nullptr ? &grad : nullptr);
    if (g != nullptr) {
      for (int a = 0; a < 4; ++a) {
        for (int k = 0; k < 3; ++k) (*g)[3 * hinge.nodes[a] + k] += grad[3 * a + k];
      }
    }
    if (assemble) {
      const std::size_t group = static_cast<std::size_t>(m.num_triangles()) + i;
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) {
          const double value = 2 * hinge.weight * hinge.k[a] * hinge.k[b];
          const double block[9] = {value, 0, 0, 0, value, 0, 0, 0, value};
          hessian.add(slots[group][4 * a + b], block);
        }
      }
    }
  }
  return energy;
}

ClothSimulator::ClothSimulator(const PlanarCutMesh& mesh, const Points& world, const ClothMaterial& material)
    : state_(std::make_unique<State>()) {
  State& s = *state_;
  if (!(material.density > 0) || !(material.stretch_stiffness > 0) || !(material.bending_stiffness >= 0) ||
      !valid_poissons_ratio(material.poisson_ratio) || !(material.mass_damping >= 0)) {
    throw Error(ErrorKind::kInvalidArgument,
                "cloth material: density and stretch stiffness must be positive, bending stiffness and damping not "
                "negative, and Poisson's ratio in (-1, 0.5)");
  }
  if (world.rows() != mesh.mesh.num_nodes() || !world.allFinite()) {
    throw Error(ErrorKind::kInvalidArgument, "cloth: " + std::to_string(world.rows()) + " positions for " +
                                                 std::to_string(mesh.mesh.num_nodes()) + " nodes, or a non-finite one");
  }
  s.material = material;
  const double e = material.stretch_stiffness, nu = material.poisson_ratio;
  s.mu = e / (2 * (1 + nu));
  s.lambda = e * nu / (1 - nu * nu);  // plane stress
  s.mesh = mesh;
  s.x = world;
  s.v = Points::Zero(world.rows(), 3);
  s.free.assign(static_cast<std::size_t>(world.rows()), 1);
  s.build();
}

ClothSimulator::~ClothSimulator() = default;
ClothSimulator::ClothSimulator(ClothSimulator&&) noexcept = default;
ClothSimulator& ClothSimulator::operator=(ClothSimulator&&) noexcept = default;

void ClothSimulator::remesh(const PlanarCutMesh& mesh, const PlanarCutReport& report) {
  State& s = *state_;
  const Index n = mesh.mesh.num_nodes();
  if (report.first_new_node != s.x.rows() || n != report.first_new_node + static_cast<Index>(report.new_node_source.size())) {
    throw Error(ErrorKind::kInvalidArgument, "cloth remesh: the report does not continue this simulator's mesh");
  }
  Points x(n, 3), v(n, 3);
  x.topRows(s.x.rows()) = s.x;
  v.topRows(s.v.rows()) = s.v;
  s.free.resize(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < report.new_node_source.size(); ++i) {
    const Index node = report.first_new_node + static_cast<Index>(i), from = report.new_node_source[i];
    x.row(node) = x.row(from);
    v.row(node) = v.row(from);
    s.free[node] = s.free[from];
  }
  s.x = std::move(x);
  s.v = std::move(v);
  s.mesh = mesh;
  s.build();
}

void ClothSimulator::pin(Index node) { state_->free.at(node) = 0; }
void ClothSimulator::release(Index node) { state_->free.at(node) = 1; }
bool ClothSimulator::pinned(Index node) const { return state_->free.at(node) == 0; }

ClothStepReport ClothSimulator::step(const ClothStepOptions& options) {
  const auto start = Clock::now();
  State& s = *state_;
  if (!(options.dt > 0) || !options.gravity.allFinite()) throw Error(ErrorKind::kInvalidArgument, "cloth step: dt must be positive");
  const double h = options.dt;
  const Index n = static_cast<Index>(s.x.rows());
  Points prediction = s.x + h * s.v;
  Points y = prediction;
  for (Index i = 0; i < n; ++i) {
    if (!s.free[i]) y.row(i) = s.x.row(i);
  }
  ClothStepReport report;
  std::vector<double> weight(static_cast<std::size_t>(n));  // dt^2 / m: force to correction
  for (Index i = 0; i < n; ++i) weight[i] = s.free[i] ? h * h / s.mass[i] : 0.0;
  Points trial(n, 3);
  std::vector<double> trial_gradient;
  bool project = false;
  double energy = s.potential(y, prediction, h, options.gravity, &s.gradient, true);
  for (int iteration = 0;; ++iteration) {
    double residual = 0;
    for (Index i = 0; i < n; ++i) {
      if (!s.free[i]) continue;
      const double g = std::sqrt(s.gradient[3 * i] * s.gradient[3 * i] + s.gradient[3 * i + 1] * s.gradient[3 * i + 1] +
                                 s.gradient[3 * i + 2] * s.gradient[3 * i + 2]);
      residual = std::max(residual, g * weight[i] / s.edge_length);
    }
    report.residual = residual;
    if (residual <= options.tolerance) {
      report.converged = true;
      break;
    }
    if (iteration == options.max_newton_iterations) break;
    s.rhs.resize(s.gradient.size());
    for (std::size_t k = 0; k < s.gradient.size(); ++k) s.rhs[k] = -s.gradient[k];
    s.direction.assign(s.gradient.size(), 0.0);
    // A direct solve: cloth systems are small, and copies holding slivers of material make them
    // too badly conditioned for Jacobi-preconditioned CG. The true Hessian first: inertia (M /
    // dt^2) usually keeps the whole system positive definite even where compressed membranes are
    // not, and then Newton converges quadratically (with every membrane projected it converged
    // linearly, a factor of about 0.4 an iteration, on the spiral's ribbon). Where the system is
    // indefinite, the projected one for the rest of the step.
    bool solved = s.solver.solve(s.hessian, s.free, s.rhs, s.direction);
    if (!project && (!solved || !s.solver.positive_definite())) {
      project = true;
      ++report.projected_iterations;
      energy = s.potential(y, prediction, h, options.gravity, &s.gradient, true, true);
      solved = s.solver.solve(s.hessian, s.free, s.rhs, s.direction);
    }
    if (!solved) throw Error(ErrorKind::kInvalidInput, "cloth step: the Newton system could not be factorised");
    ++report.newton_iterations;
    double slope = 0;
    for (std::size_t k = 0; k < s.gradient.size(); ++k) slope += s.gradient[k] * s.direction[k];
    if (!(slope < 0)) break;  // no descent left at this precision
    // Backtracking; near convergence the decrease Armijo asks for is below the rounding of the
    // potential itself, and there the gradient decides (as in the tet simulator's line search).
    const double measure = gradient_measure(s.gradient, weight);
    double t = 1;
    bool accepted = false;
    for (int halving = 0; halving < kMaxClothHalvings && !accepted; ++halving, t *= 0.5) {
      for (Index i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) trial(i, k) = y(i, k) + t * s.direction[3 * i + k];
      }
      const double trial_energy = s.potential(trial, prediction, h, options.gravity, &trial_gradient, false);
      const bool within_rounding = kArmijo * t * -slope <= kEnergyRounding * std::abs(energy);
      accepted = trial_energy <= energy + kArmijo * t * slope ||
                 (within_rounding && gradient_measure(trial_gradient, weight) < measure);
      if (accepted) energy = trial_energy;
    }
    if (!accepted) break;  // at the limit of precision
    y.swap(trial);
    energy = s.potential(y, prediction, h, options.gravity, &s.gradient, true, project);
  }
  s.v = (y - s.x) / h;
  s.x = std::move(y);
  report.seconds = seconds_since(start);
  return report;
}

Index ClothSimulator::num_nodes() const { return static_cast<Index>(state_->x.rows()); }
Index ClothSimulator::num_triangles() const { return state_->mesh.mesh.num_triangles(); }
Index ClothSimulator::num_hinges() const { return static_cast<Index>(state_->hinges.size()); }
const Points& ClothSimulator::positions() const { return state_->x; }
const Points& ClothSimulator::velocities() const { return state_->v; }
void ClothSimulator::set_positions(const Points& x) {
  if (x.rows() != state_->x.rows() || !x.allFinite()) throw Error(ErrorKind::kInvalidArgument, "cloth: bad positions");
  state_->x = x;
}
const Eigen::VectorXd& ClothSimulator::masses() const { return state_->mass; }
double ClothSimulator::elastic_energy() const { return state_->elastic(state_->x); }
double ClothSimulator::kinetic_energy() const {
  double e = 0;
  for (Index i = 0; i < state_->x.rows(); ++i) e += 0.5 * state_->mass[i] * state_->v.row(i).squaredNorm();
  return e;
}

}  // namespace tetcut::sim
