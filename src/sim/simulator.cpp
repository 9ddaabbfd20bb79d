// Backward Euler as energy minimisation (the incremental potential), by Newton's method on the
// free degrees of freedom with element Hessians projected to positive semi-definite, a sparse
// solve, and a backtracking line search on the potential.

#include <tetcut/error.hpp>
#include <tetcut/sim.hpp>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <limits>
#include <map>
#include <stdexcept>
#include <cmath>
#include <string>

namespace tetcut::sim {
namespace {

using Mat12 = Eigen::Matrix<double, 12, 12>;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Sparse = Eigen::SparseMatrix<double>;

// B = d vec(F) / d x for F = sum_a x_a w_a^T: column 3a + i, row 3l + i holds w_a(l).
Eigen::Matrix<double, 9, 12> strain_matrix(const Eigen::Matrix<double, 4, 3>& w) {
  Eigen::Matrix<double, 9, 12> b = Eigen::Matrix<double, 9, 12>::Zero();
  for (int a = 0; a < 4; ++a) {
    for (int i = 0; i < 3; ++i) {
      for (int l = 0; l < 3; ++l) b(3 * l + i, 3 * a + i) = w(a, l);
    }
  }
  return b;
}

}  // namespace

Simulator::Simulator(const TetMesh& mesh, const Material& material, std::span<const double> volume_fraction)
    : material_(material),
      parameters_(model_parameters(material.model, lame_parameters(material.youngs_modulus, material.poissons_ratio))),
      x_(mesh.current()),
      v_(Points::Zero(mesh.num_nodes(), 3)),
      mass_(Eigen::VectorXd::Zero(mesh.num_nodes())),
      constraint_(static_cast<std::size_t>(mesh.num_nodes()), -1),
      target_(Points::Zero(mesh.num_nodes(), 3)) {
  if (!(material.density > 0) || !std::isfinite(material.density)) {
    throw Error(ErrorKind::kInvalidArgument, "density must be a positive number");
  }
  if (!(material.mass_damping >= 0) || !(material.stiffness_damping >= 0)) {
    throw Error(ErrorKind::kInvalidArgument, "damping coefficients must not be negative");
  }
  build(mesh, volume_fraction);
}

void Simulator::build(const TetMesh& mesh, std::span<const double> volume_fraction) {
  if (!volume_fraction.empty() && static_cast<Index>(volume_fraction.size()) != mesh.num_tets()) {
    throw Error(ErrorKind::kInvalidArgument, "volume fractions: " + std::to_string(volume_fraction.size()) +
                                                 " values for " + std::to_string(mesh.num_tets()) + " tets");
  }
  const Points& rest = mesh.rest();
  mass_ = Eigen::VectorXd::Zero(mesh.num_nodes());
  elements_.clear();
  elements_.resize(static_cast<std::size_t>(mesh.num_tets()));
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    Element& e = elements_[t];
    for (int k = 0; k < 4; ++k) e.nodes[k] = mesh.tets()(t, k);
    Mat3 dm;
    for (int k = 0; k < 3; ++k) dm.col(k) = (rest.row(e.nodes[k + 1]) - rest.row(e.nodes[0])).transpose();
    const Mat3 inverse = dm.inverse();
    e.weights.bottomRows<3>() = inverse;
    e.weights.row(0) = -inverse.colwise().sum();
    double fraction = volume_fraction.empty() ? 1.0 : volume_fraction[t];
    if (!(fraction >= 0 && fraction <= 1 + 1e-9)) {
      throw Error(ErrorKind::kInvalidArgument, "volume fraction of tet " + std::to_string(t) + " is not in [0, 1]");
    }
    fraction = std::clamp(fraction, kMinVolumeFraction, 1.0);
    e.volume = dm.determinant() / 6 * fraction;
    for (const Index n : e.nodes) mass_[n] += material_.density * e.volume / 4;
  }
  const Vec3 extent = rest.colwise().maxCoeff() - rest.colwise().minCoeff();
  size_ = std::max(extent.norm(), 1e-300);
  double edges = 0;
  for (const Element& e : elements_) {
    for (const auto& edge : kTetEdges) edges += (rest.row(e.nodes[edge[0]]) - rest.row(e.nodes[edge[1]])).norm();
  }
  if (contact_stiffness_given_) return;
  contact_stiffness_ = elements_.empty() ? 0 : 10 * material_.youngs_modulus * edges / (6.0 * static_cast<double>(elements_.size()));
}

double Obstacle::distance(const Vec3& x, Vec3* direction) const {
  switch (kind) {
    case Kind::kPlane:
      *direction = normal;
      return (x - point).dot(normal);
    case Kind::kSphere: {
      const Vec3 r = x - point;
      const double length = r.norm();
      *direction = length > 0 ? Vec3(r / length) : Vec3(0, 0, 1);
      return length - radius;
    }
    case Kind::kBox: {
      // Outside: distance to the box (positive); inside: minus the distance to the nearest face.
      const Vec3 below = point - x, above = x - normal;
      const Vec3 outside = below.cwiseMax(above).cwiseMax(0.0);
      if (outside.squaredNorm() > 0) {
        const Vec3 nearest = x.cwiseMax(point).cwiseMin(normal);
        *direction = (x - nearest).normalized();
        return outside.norm();
      }
      double depth = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 3; ++k) {
        for (const int side : {-1, 1}) {
          const double d = side < 0 ? x[k] - point[k] : normal[k] - x[k];
          if (d < depth) {
            depth = d;
            *direction = Vec3::Zero();
            (*direction)[k] = side;
          }
        }
      }
      return -depth;
    }
  }
  return 0;
}

void Simulator::add_spring(const EmbeddedPoint& p, const EmbeddedPoint& q, double stiffness) {
  for (const EmbeddedPoint* e : {&p, &q}) {
    if (e->tet < 0 || e->tet >= static_cast<Index>(elements_.size())) throw Error(ErrorKind::kInvalidArgument, "spring: no such tet");
  }
  if (!(stiffness >= 0)) throw Error(ErrorKind::kInvalidArgument, "spring: stiffness must not be negative");
  springs_.push_back({p, q, stiffness});
}

Vec3 Simulator::position(const EmbeddedPoint& p) const {
  Vec3 y = Vec3::Zero();
  for (int k = 0; k < 4; ++k) y += p.weights[k] * x_.row(elements_[p.tet].nodes[k]).transpose();
  return y;
}

template <typename Visit>
void Simulator::for_each_constraint(const Points& x, Visit&& visit) const {
  std::array<Index, 8> nodes;
  std::array<double, 8> coefficients;
  for (const EmbeddedPoint& point : contact_points_) {
    Vec3 y = Vec3::Zero();
    for (int k = 0; k < 4; ++k) {
      nodes[k] = elements_[point.tet].nodes[k];
      coefficients[k] = point.weights[k];
      y += coefficients[k] * x.row(nodes[k]).transpose();
    }
    for (const Obstacle& obstacle : obstacles_) {
      Vec3 n;
      const double d = obstacle.distance(y, &n);
      if (d >= 0) continue;
      // (k / 2) d^2; the Hessian keeps the normal part only (positive semi-definite).
      visit(nodes, coefficients, 4, 0.5 * contact_stiffness_ * d * d, Vec3(contact_stiffness_ * d * n),
            Mat3(contact_stiffness_ * n * n.transpose()));
    }
  }
  for (const Spring& spring : springs_) {
    Vec3 y = Vec3::Zero();
    for (int k = 0; k < 4; ++k) {
      nodes[k] = elements_[spring.p.tet].nodes[k];
      nodes[k + 4] = elements_[spring.q.tet].nodes[k];
      coefficients[k] = spring.p.weights[k];
      coefficients[k + 4] = -spring.q.weights[k];
    }
    for (int k = 0; k < 8; ++k) y += coefficients[k] * x.row(nodes[k]).transpose();
    visit(nodes, coefficients, 8, 0.5 * spring.stiffness * y.squaredNorm(), Vec3(spring.stiffness * y),
          Mat3(spring.stiffness * Mat3::Identity()));
  }
}

void Simulator::remesh(const TetMesh& mesh, std::span<const double> volume_fraction, Index first_new_node,
                       std::span<const Index> new_node_source) {
  if (first_new_node != num_nodes() || mesh.num_nodes() != first_new_node + static_cast<Index>(new_node_source.size())) {
    throw Error(ErrorKind::kInvalidArgument, "remesh: the node counts do not match the cut report");
  }
  const Index old = num_nodes();
  x_.conservativeResize(mesh.num_nodes(), 3);
  v_.conservativeResize(mesh.num_nodes(), 3);
  target_.conservativeResize(mesh.num_nodes(), 3);
  for (Index i = 0; i < static_cast<Index>(new_node_source.size()); ++i) {
    const Index source = new_node_source[i];
    if (source < 0 || source >= old + i) throw Error(ErrorKind::kInvalidArgument, "remesh: a node's source does not exist");
    x_.row(old + i) = x_.row(source);
    v_.row(old + i) = v_.row(source);
    target_.row(old + i) = target_.row(source);
    constraint_.push_back(constraint_[source]);
  }
  contact_points_.clear();
  springs_.clear();
  build(mesh, volume_fraction);
}

void Simulator::set_positions(const Points& x) {
  if (x.rows() != num_nodes() || !x.allFinite()) throw Error(ErrorKind::kInvalidArgument, "positions: wrong size or not finite");
  x_ = x;
}

void Simulator::set_velocities(const Points& v) {
  if (v.rows() != num_nodes() || !v.allFinite()) throw Error(ErrorKind::kInvalidArgument, "velocities: wrong size or not finite");
  v_ = v;
}

void Simulator::pin(Index node) {
  constraint_.at(node) = 0;
  target_.row(node) = x_.row(node);
}

void Simulator::move_to(Index node, const Vec3& target) {
  constraint_.at(node) = 1;
  target_.row(node) = target.transpose();
}

void Simulator::release(Index node) { constraint_.at(node) = -1; }

Mat3 Simulator::deformation_gradient(const Element& e, const Points& x) const {
  Mat3 F = Mat3::Zero();
  for (int a = 0; a < 4; ++a) F += x.row(e.nodes[a]).transpose() * e.weights.row(a);
  return F;
}

double Simulator::elastic_energy() const {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, elements_.size(), 1024), 0.0,
      [&](const auto& range, double sum) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          sum += elements_[i].volume * energy_density(material_.model, parameters_, deformation_gradient(elements_[i], x_));
        }
        return sum;
      },
      std::plus<>());
}

Points Simulator::elastic_gradient() const {
  Points g = Points::Zero(num_nodes(), 3);
  for (const Element& e : elements_) {
    const Mat3 P = first_piola(material_.model, parameters_, deformation_gradient(e, x_));
    for (int a = 0; a < 4; ++a) g.row(e.nodes[a]) += e.volume * (P * e.weights.row(a).transpose()).transpose();
  }
  return g;
}

Vec3 Simulator::momentum() const { return (mass_.asDiagonal() * v_).colwise().sum().transpose(); }

StepReport Simulator::step(const StepOptions& options) { return minimise(options, true); }

StepReport Simulator::solve_static(const StepOptions& options) {
  StepReport report = minimise(options, false);
  v_.setZero();
  return report;
}

StepReport Simulator::minimise(const StepOptions& options, bool inertia) {
  if (!(options.dt > 0) && inertia) throw Error(ErrorKind::kInvalidArgument, "the time step must be positive");
  const double h = options.dt;
  const Index n = num_nodes();
  const Points start = x_;
  // Degrees of freedom: the coordinates of free nodes.
  std::vector<Index> dof(static_cast<std::size_t>(3 * n), -1);
  Index free = 0;
  for (Index v = 0; v < n; ++v) {
    if (constraint_[v] >= 0) continue;
    for (int k = 0; k < 3; ++k) dof[3 * v + k] = free++;
  }
  // Start from the inertial prediction; constrained nodes go where they are told.
  const Points prediction = inertia ? Points(start + h * v_) : start;
  Points x = prediction;
  for (Index v = 0; v < n; ++v) {
    if (constraint_[v] >= 0) x.row(v) = target_.row(v);
  }
  const double inertia_weight = inertia ? 1 / (h * h) + material_.mass_damping / h : 0;

  // Rayleigh stiffness damping uses the stiffness at the start of the step.
  const bool stiffness_damping = inertia && material_.stiffness_damping > 0;
  std::vector<Mat12> start_hessians;
  const auto element_hessian = [&](const Element& e, const Points& at) {
    const Mat9 d = projected_stress_derivative(material_.model, parameters_, deformation_gradient(e, at));
    const Eigen::Matrix<double, 9, 12> b = strain_matrix(e.weights);
    return Mat12(e.volume * b.transpose() * d * b);
  };
  if (stiffness_damping) {
    start_hessians.resize(elements_.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, elements_.size(), 512), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) start_hessians[i] = element_hessian(elements_[i], start);
    });
  }
  const double damping_weight = stiffness_damping ? material_.stiffness_damping / h : 0;

  const auto element_values = [&](const Element& e, const Points& at, std::size_t i) {
    Vec12 u;
    for (int a = 0; a < 4; ++a) u.segment<3>(3 * a) = (at.row(e.nodes[a]) - start.row(e.nodes[a])).transpose();
    double energy = e.volume * energy_density(material_.model, parameters_, deformation_gradient(e, at));
    if (stiffness_damping) energy += 0.5 * damping_weight * u.dot(start_hessians[i] * u);
    return energy;
  };
  // The potential: inertia (and mass damping), elastic energy, stiffness damping, gravity.
  const auto potential = [&](const Points& at) {
    double total = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, elements_.size(), 1024), 0.0,
        [&](const auto& range, double sum) {
          for (std::size_t i = range.begin(); i != range.end(); ++i) sum += element_values(elements_[i], at, i);
          return sum;
        },
        std::plus<>());
    for (Index v = 0; v < n; ++v) {
      const Vec3 p = at.row(v).transpose();
      if (inertia) {
        total += 0.5 * mass_[v] / (h * h) * (p - prediction.row(v).transpose()).squaredNorm();
        total += 0.5 * mass_[v] * material_.mass_damping / h * (p - start.row(v).transpose()).squaredNorm();
      }
      total -= mass_[v] * options.gravity.dot(p);
    }
    for_each_constraint(at, [&](const auto&, const auto&, int, double energy, const Vec3&, const Mat3&) { total += energy; });
    return total;
  };

  // Sparsity over free degrees of freedom, and where each element's entries go.
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(elements_.size() * 144 + static_cast<std::size_t>(free));
  for (Index d = 0; d < free; ++d) triplets.emplace_back(d, d, 0.0);
  for (const Element& e : elements_) {
    for (int r = 0; r < 12; ++r) {
      const Index row = dof[3 * e.nodes[r / 3] + r % 3];
      if (row < 0) continue;
      for (int c = 0; c < 12; ++c) {
        const Index col = dof[3 * e.nodes[c / 3] + c % 3];
        if (col >= 0) triplets.emplace_back(row, col, 0.0);
      }
    }
  }
  for (const Spring& spring : springs_) {
    for (int r = 0; r < 24; ++r) {
      const Index row = dof[3 * elements_[r < 12 ? spring.p.tet : spring.q.tet].nodes[(r % 12) / 3] + r % 3];
      if (row < 0) continue;
      for (int c = 0; c < 24; ++c) {
        const Index col = dof[3 * elements_[c < 12 ? spring.p.tet : spring.q.tet].nodes[(c % 12) / 3] + c % 3];
        if (col >= 0) triplets.emplace_back(row, col, 0.0);
      }
    }
  }
  Sparse hessian(free, free);
  hessian.setFromTriplets(triplets.begin(), triplets.end());
  triplets = {};
  const auto slot = [&](Index row, Index col) {
    const auto* begin = hessian.innerIndexPtr() + hessian.outerIndexPtr()[col];
    const auto* end = hessian.innerIndexPtr() + hessian.outerIndexPtr()[col + 1];
    const auto* found = std::lower_bound(begin, end, row);
    if (found == end || *found != row) throw std::logic_error("simulator: an entry outside the Hessian's pattern");
    return static_cast<Index>(found - hessian.innerIndexPtr());
  };
  std::vector<Index> diagonal(static_cast<std::size_t>(free));
  for (Index d = 0; d < free; ++d) diagonal[d] = slot(d, d);

  Eigen::SimplicialLDLT<Sparse> cholesky;
  Eigen::ConjugateGradient<Sparse, Eigen::Lower | Eigen::Upper, Eigen::IncompleteCholesky<double>> cg;
  if (options.solver == LinearSolver::kCholesky) cholesky.analyzePattern(hessian);
  cg.setTolerance(1e-10);

  double total_mass = mass_.sum();
  double volume = 0;
  for (const Element& e : elements_) volume += e.volume;
  const double scale = inertia ? total_mass * size_ * size_ / (h * h) : parameters_.mu * volume;
  const double threshold = options.tolerance * options.tolerance * scale;

  StepReport report;
  std::vector<Mat12> hessians(elements_.size());
  std::vector<Vec12> gradients(elements_.size());
  Eigen::VectorXd gradient(free), step(free);
  double energy = potential(x);
  for (int iteration = 0; iteration < options.max_newton_iterations; ++iteration) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, elements_.size(), 256), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        const Element& e = elements_[i];
        const Mat3 F = deformation_gradient(e, x);
        const Eigen::Matrix<double, 9, 12> b = strain_matrix(e.weights);
        const Mat3 P = first_piola(material_.model, parameters_, F);
        gradients[i] = e.volume * b.transpose() * Eigen::Map<const Eigen::Matrix<double, 9, 1>>(P.data());
        hessians[i] = e.volume * b.transpose() * projected_stress_derivative(material_.model, parameters_, F) * b;
        if (stiffness_damping) {
          Vec12 u;
          for (int a = 0; a < 4; ++a) u.segment<3>(3 * a) = (x.row(e.nodes[a]) - start.row(e.nodes[a])).transpose();
          gradients[i] += damping_weight * start_hessians[i] * u;
          hessians[i] += damping_weight * start_hessians[i];
        }
      }
    });
    std::fill(hessian.valuePtr(), hessian.valuePtr() + hessian.nonZeros(), 0.0);
    gradient.setZero();
    for (std::size_t i = 0; i < elements_.size(); ++i) {
      const Element& e = elements_[i];
      for (int r = 0; r < 12; ++r) {
        const Index row = dof[3 * e.nodes[r / 3] + r % 3];
        if (row < 0) continue;
        gradient[row] += gradients[i][r];
        for (int c = 0; c < 12; ++c) {
          const Index col = dof[3 * e.nodes[c / 3] + c % 3];
          if (col >= 0) hessian.valuePtr()[slot(row, col)] += hessians[i](r, c);
        }
      }
    }
    for (Index v = 0; v < n; ++v) {
      for (int k = 0; k < 3; ++k) {
        const Index d = dof[3 * v + k];
        if (d < 0) continue;
        double g = -mass_[v] * options.gravity[k];
        if (inertia) {
          g += mass_[v] / (h * h) * (x(v, k) - prediction(v, k)) + mass_[v] * material_.mass_damping / h * (x(v, k) - start(v, k));
        }
        gradient[d] += g;
        hessian.valuePtr()[diagonal[d]] += mass_[v] * inertia_weight;
      }
    }
    for_each_constraint(x, [&](const std::array<Index, 8>& nodes, const std::array<double, 8>& c, int count, double,
                               const Vec3& dE, const Mat3& d2E) {
      for (int a = 0; a < count; ++a) {
        for (int i = 0; i < 3; ++i) {
          const Index row = dof[3 * nodes[a] + i];
          if (row < 0) continue;
          gradient[row] += c[a] * dE[i];
          for (int b = 0; b < count; ++b) {
            for (int j = 0; j < 3; ++j) {
              const Index col = dof[3 * nodes[b] + j];
              if (col >= 0 && d2E(i, j) != 0) hessian.valuePtr()[slot(row, col)] += c[a] * c[b] * d2E(i, j);
            }
          }
        }
      }
    });
    if (options.solver == LinearSolver::kCholesky) {
      cholesky.factorize(hessian);
      step = cholesky.solve(-gradient);
      if (cholesky.info() != Eigen::Success) throw Error(ErrorKind::kInvalidInput, "the Newton system could not be factorised");
    } else {
      cg.compute(hessian);
      if (cg.info() != Eigen::Success) throw Error(ErrorKind::kInvalidInput, "the Newton system could not be preconditioned");
      step = cg.solve(-gradient);
    }
    const double decrement = -gradient.dot(step);
    report.newton_iterations = iteration + 1;
    if (!(decrement >= 0) || !std::isfinite(decrement)) break;  // not a descent direction: give up
    if (decrement / 2 <= threshold) {
      report.converged = true;
      break;
    }
    // Backtracking (Armijo) on the potential.
    double t = 1;
    Points trial = x;
    bool accepted = false;
    for (int halving = 0; halving < 40; ++halving) {
      for (Index v = 0; v < n; ++v) {
        for (int k = 0; k < 3; ++k) {
          const Index d = dof[3 * v + k];
          if (d >= 0) trial(v, k) = x(v, k) + t * step[d];
        }
      }
      const double trial_energy = potential(trial);
      if (trial_energy <= energy - 1e-4 * t * decrement) {
        x.swap(trial);
        energy = trial_energy;
        accepted = true;
        break;
      }
      t /= 2;
    }
    if (!accepted) break;  // at the limit of precision
  }
  report.energy = energy;
  if (inertia) v_ = (x - start) / h;
  x_ = std::move(x);
  return report;
}

std::vector<std::pair<EmbeddedPoint, EmbeddedPoint>> incision_pairs(const MaterialSurface& surface, std::int64_t first_cut,
                                                                    std::int64_t end_cut) {
  // Vertices on the chosen cut triangles, by rest position; a position held by two copies is a
  // point on both sides of the incision.
  std::map<std::array<double, 3>, std::vector<Index>> by_position;
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(surface.surface.num_vertices()), 0);
  for (Index t = 0; t < surface.surface.num_triangles(); ++t) {
    const std::int64_t source = surface.triangle_source[t];
    if (source < first_cut || source >= end_cut) continue;
    for (int k = 0; k < 3; ++k) {
      const Index v = surface.surface.triangles(t, k);
      if (seen[v]) continue;
      seen[v] = 1;
      const auto row = surface.surface.vertices.row(v);
      by_position[{row[0], row[1], row[2]}].push_back(v);
    }
  }
  std::vector<std::pair<EmbeddedPoint, EmbeddedPoint>> pairs;
  const auto point = [&](Index v) { return EmbeddedPoint{surface.vertex_tet[v], surface.vertex_weights.row(v).transpose()}; };
  for (const auto& [position, vertices] : by_position) {
    for (std::size_t i = 1; i < vertices.size(); ++i) {
      if (surface.vertex_tet[vertices[i]] != surface.vertex_tet[vertices[0]]) pairs.emplace_back(point(vertices[0]), point(vertices[i]));
    }
  }
  return pairs;
}

}  // namespace tetcut::sim
