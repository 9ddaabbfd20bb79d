#pragma once
// Cloth: the planar cutter's mesh (PlanarCutMesh) simulated in 3D by backward Euler.
//
//   tetcut::sim::ClothSimulator cloth(cut.mesh, world_positions, material);
//   cloth.pin(node);
//   cloth.step(options);                       // one time step
//   cutter.cut(more); cloth.remesh(cutter.result().mesh, report);   // cut while it hangs
//
// Energies: a St. Venant-Kirchhoff membrane per triangle copy and a quadratic bending hinge per
// edge two copies share (src/sim/cloth_energy.hpp), both scaled by the copies' material
// fractions; gravity; pins. Each step minimises the incremental potential by Newton's method: the
// Hessian assembled in the simulator's block matrix, solved by a sparse LDL^T, the membranes'
// Hessians projected to positive semi-definite where the whole system is not positive definite,
// and a backtracking line search.

#include <tetcut/planar_cutter.hpp>
#include <tetcut/types.hpp>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace tetcut::sim {

struct ClothMaterial {
  double density = 0.2;             ///< kg per square metre of rest area
  double stretch_stiffness = 500;   ///< Young's modulus times thickness (N/m)
  double poisson_ratio = 0.3;
  double bending_stiffness = 1e-4;  ///< k_b (N m): energy of bending
  double mass_damping = 0;          ///< 1/s: a drag proportional to mass and velocity
};

struct ClothStepOptions {
  double dt = 1.0 / 60;
  Vec3 gravity = Vec3(0, 0, -9.81);
  int max_newton_iterations = 30;
  /// Converged when the largest free node's Newton correction estimate, |g| dt^2 / m, is below
  /// this times the mean rest edge length.
  double tolerance = 1e-5;
};

struct ClothStepReport {
  int newton_iterations = 0;
  /// Iterations whose true Hessian was indefinite, so that the projected one was used.
  int projected_iterations = 0;
  double residual = 0;  ///< the convergence measure at the end, relative to the mean edge length
  bool converged = false;
  double seconds = 0;
};

class ClothSimulator {
 public:
  /// `world`: the nodes' initial positions (|nodes| x 3); velocities start at zero.
  /// Error(kInvalidArgument) on a bad material or size.
  ClothSimulator(const PlanarCutMesh& mesh, const Points& world, const ClothMaterial& material);
  ~ClothSimulator();
  ClothSimulator(ClothSimulator&&) noexcept;
  ClothSimulator& operator=(ClothSimulator&&) noexcept;

  /// After a cut batch: the new mesh, whose nodes from report.first_new_node on were split from
  /// report.new_node_source. Old nodes keep their state and pins; new ones take their source's.
  void remesh(const PlanarCutMesh& mesh, const PlanarCutReport& report);

  void pin(Index node);
  void release(Index node);
  bool pinned(Index node) const;

  ClothStepReport step(const ClothStepOptions& options);

  Index num_nodes() const;
  Index num_triangles() const;
  Index num_hinges() const;
  const Points& positions() const;
  const Points& velocities() const;
  void set_positions(const Points& x);
  const Eigen::VectorXd& masses() const;
  /// Membrane plus bending energy at the current positions.
  double elastic_energy() const;
  double kinetic_energy() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tetcut::sim
