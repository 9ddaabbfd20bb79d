#pragma once
// Finite elements on (cut) tet meshes: hyperelastic energies per tet and an implicit integrator.
//
//   tetcut::sim::Simulator sim(result.mesh.mesh, material, fractions);  // fractions: per tet copy
//   sim.pin(node);
//   for (...) sim.step(options);                                        // backward Euler
//   sim.remesh(cutter, cutter.cut(blade));                              // after each cut batch
//
// Each tet copy of a cut mesh is a whole tet holding part of its material: its mass and elastic
// energy are scaled by its material volume fraction, floored at kMinVolumeFraction so that a copy
// holding a sliver of material keeps some stiffness and mass and the system stays well
// conditioned.

#include <tetcut/cutter.hpp>
#include <tetcut/tet_mesh.hpp>

#include <memory>
#include <span>
#include <vector>

namespace tetcut::sim {

using Mat3 = Eigen::Matrix3d;
/// d vec(P) / d vec(F), with vec stacking columns (Eigen's default).
using Mat9 = Eigen::Matrix<double, 9, 9>;

enum class Model {
  kCorotated,         ///< fixed corotated (Stomakhin et al. 2012): mu |F - R|^2 + lambda/2 (J - 1)^2
  kStableNeoHookean,  ///< Smith, de Goes, Kim 2018, with the log(I_C + 1) term; rest stable, shifted to Psi(I) = 0
};

/// Lamé parameters.
struct Lame {
  double mu = 0, lambda = 0;
};
/// Whether `nu` is a Poisson's ratio of a stable isotropic material: strictly between -1 (where the
/// shear modulus E / (2 (1 + nu)) is unbounded) and 1/2 (incompressible: lambda is unbounded). The
/// one check of the range, for the tet material (lame_parameters), the cloth's and scene files.
constexpr bool valid_poissons_ratio(double nu) { return nu > -1 && nu < 0.5; }

/// From Young's modulus E > 0 and Poisson's ratio -1 < nu < 0.5; Error(kInvalidArgument) otherwise.
Lame lame_parameters(double youngs_modulus, double poissons_ratio);
/// The parameters a model's energy uses so that its small-strain behaviour is that of linear
/// elasticity with `lame` (Stable Neo-Hookean: mu' = 4/3 mu, lambda' = lambda + 5/6 mu).
Lame model_parameters(Model model, const Lame& lame);

/// Strain energy density Psi(F), its first Piola-Kirchhoff stress P = dPsi/dF, and dP/dF, for a
/// model with parameters as returned by model_parameters.
double energy_density(Model model, const Lame& p, const Mat3& F);
Mat3 first_piola(Model model, const Lame& p, const Mat3& F);
Mat9 stress_derivative(Model model, const Lame& p, const Mat3& F);
/// dP/dF with negative eigenvalues clamped to zero (symmetric positive semi-definite), for Newton.
Mat9 projected_stress_derivative(Model model, const Lame& p, const Mat3& F);

struct Material {
  Model model = Model::kStableNeoHookean;
  double youngs_modulus = 1e5;  ///< Pa
  double poissons_ratio = 0.3;
  double density = 1000;        ///< kg / m^3
  /// Rayleigh damping: force -(mass_damping M + stiffness_damping K) v, K the stiffness at the
  /// start of the step.
  double mass_damping = 0, stiffness_damping = 0;
};

/// Copies holding less material than this fraction of their tet count as holding this much.
inline constexpr double kMinVolumeFraction = 0.01;

enum class LinearSolver {
  /// Conjugate gradients preconditioned by the inverses of the 3 x 3 diagonal blocks, solved as
  /// accurately as the Newton tolerance needs (see StepOptions): the default. Cheap to set up
  /// after a cut and O(nonzeros) per iteration on both cores.
  kConjugateGradient,
  /// Sparse LDL^T (Eigen's simplicial factorisation): exact, but its fill makes it slow beyond a
  /// few thousand tets; for small or badly conditioned static problems.
  kCholesky,
};

/// Where Newton's method starts a dynamic step, and so where its first matrix and gradient are
/// taken. Both end at the same step once converged; with a fixed budget of one iteration they
/// differ (see StepOptions::first_guess).
enum class FirstGuess {
  /// The positions the velocities predict, x + dt v (kinematic nodes at their targets): a body in
  /// free flight or turning is met where it is going, so one iteration follows a turn closely.
  kPrediction,
  /// The positions the step starts from (kinematic nodes at their targets): the linearly
  /// implicit step of Baraff and Witkin (1998). Nothing is extrapolated, so nothing overshoots.
  kStart,
};

struct StepOptions {
  double dt = 1.0 / 120;
  Vec3 gravity = Vec3(0, 0, -9.81);
  int max_newton_iterations = 30;
  /// Newton stops when half the Newton decrement (the energy the step still expects to gain) is
  /// below tolerance^2 times the kinetic energy scale M (L / dt)^2, L the mesh's size: a step
  /// whose positions are settled to about tolerance * L in the mass-weighted mean (a single node
  /// may be a few times further). For a dynamic step the test is also
  /// passed, with no further solve, when an upper bound of the decrement from the gradient
  /// (dt^2 g^T M^-1 g, as the Hessian is at least M / dt^2) is below it.
  double tolerance = 1e-7;
  LinearSolver solver = LinearSolver::kConjugateGradient;
  /// Conjugate gradient iterations per Newton iteration at most; 0: as many as it takes to solve
  /// the Newton system to the accuracy the tolerance asks for.
  int max_cg_iterations = 0;
  /// A Newton matrix serves the first iteration of at most this many consecutive dynamic steps
  /// (1: a fresh one every iteration). Only the direction changes: energies, gradients and the
  /// convergence test are always those of the current positions, contact and spring terms are
  /// replaced, and a cut's changes are taken out and put in. The deformation changes little in
  /// one step, so the direction is about as good and the step costs no element Hessians: 2
  /// measured 20 to 30% faster steps here, with the same result (see the README).
  int reuse_hessian = 2;
  /// Store the Newton matrix in single precision once it outgrows the cache (more than about
  /// 8 MB, some 30k tets): half the memory its products stream (a real-time step at 114k tets
  /// about a fifth faster), at float rounding (about 6e-8) of its entries; a smaller one stays in
  /// double, where the conversions cost more than they save. The energies, gradients and
  /// convergence test stay in double, but the direction no longer keeps momentum exactly (a body
  /// in free fall gains about 1e-7 of it a step): for the real-time mode, whose budget leaves
  /// larger residuals, not for converged steps.
  bool single_precision_matrix = false;
  /// The budget's safety valve: while a step would end with a residual (StepReport::residual)
  /// above this, it takes further Newton iterations, at most `rescue_iterations` of them. A
  /// residual of 1 leaves a correction as large as the object in one step: far beyond what a
  /// budget ever leaves in steady motion (0.001 to 0.25 measured on the embedded femur of
  /// examples/live-femur.json), and where, left alone, the error grew tenfold a step until the
  /// positions overflowed (a hook let go of stretched material). 0: no valve.
  double rescue_residual = 0;
  int rescue_iterations = 0;
  /// Where Newton starts a dynamic step. Converged steps end at the same positions either way (to
  /// the tolerance), and the prediction is the better guess for them: a body in free flight is
  /// there already, so its momentum comes out exact. With one iteration a step (the real-time
  /// mode) the two trade accuracy in smooth motion against robustness where motion changes
  /// abruptly, measured (see the README, "Where Newton starts"):
  /// - kStart does not overshoot. On the live femur (tetcut_bench_live, 213 steps) the prediction
  ///   of a cut piece falling onto the floor lies deep in it, and of a hook's release past where
  ///   the material snaps back; from there one iteration left residuals up to 0.99 and needed the
  ///   safety valve on 37 of 60 falling steps and 8 of 77 hook steps (p99 of the falling steps
  ///   37-49 ms, with the Newton matrix made every step; kept 4 steps, 29 and 28); from the start
  ///   on none, with the matrix kept for 4 steps (p99 6-8 ms). Surface contact costs less: there
  ///   is no first guess to shorten by continuous collision detection, and one move a step for the
  ///   candidate lists to cover.
  /// - kPrediction follows smooth motion more closely, since one iteration only corrects it: the
  ///   hanging block's sag after 30 real-time steps is 9e-6 off the converged one against 9e-4
  ///   from the start, and the block turning at 1 rad/s (E = 1e5) keeps 64% of its kinetic energy
  ///   after 2 s against 34% (converged steps keep 88%: tetcut_bench_sim).
  /// So the real-time mode keeps the prediction, and scenes of cutting and contact
  /// (examples/live-femur.json, the contact benchmarks) choose the start.
  FirstGuess first_guess = FirstGuess::kPrediction;

  /// The real-time mode: a fixed budget of work per step (one Newton iteration of at most
  /// `cg_iterations` conjugate gradient iterations by default, with a fresh Newton matrix every
  /// `reuse` steps, stored in single precision), whatever the residual up to 1 (beyond it the
  /// step goes on, up to 8 more iterations: see rescue_residual); the report's `residual` says
  /// what the budget left. See the README for what it costs in accuracy. Where things collide or
  /// snap, first_guess = kStart is the steadier.
  static StepOptions real_time(double dt, int newton_iterations = 1, int cg_iterations = 30, int reuse = 4) {
    StepOptions o;
    o.dt = dt;
    o.max_newton_iterations = newton_iterations;
    o.max_cg_iterations = cg_iterations;
    o.reuse_hessian = reuse;
    o.single_precision_matrix = true;
    o.rescue_residual = 1;
    o.rescue_iterations = 8;
    return o;
  }
};

struct StepReport {
  int newton_iterations = 0;  ///< Newton systems assembled and solved
  int cg_iterations = 0;      ///< conjugate gradient iterations, over all Newton iterations
  int rescue_iterations = 0;  ///< Newton iterations beyond the budget (StepOptions::rescue_residual)
  bool converged = false;
  double energy = 0;  ///< the incremental potential at the end of the step
  /// How far from converged the step ended, in the units of StepOptions::tolerance (a converged
  /// step's is at most the tolerance): sqrt(d / (M (L / dt)^2)) for the best measure d known of
  /// half the Newton decrement at the end positions: the decrement itself when Newton stopped
  /// there without moving, otherwise (dynamic steps) the bound from the gradient, or (static
  /// solves) the last decrement measured.
  double residual = 0;
  /// Wall time of the step's stages in seconds: element energies, stresses and Hessians with
  /// their assembly; the linear solves; the line search (energies and gradients of trial points).
  double assemble_seconds = 0, solve_seconds = 0, line_search_seconds = 0;
  /// Of assemble_seconds: adding the contact and spring terms' blocks into the Newton matrix
  /// (their number grows with the surface pairs in contact and the guards pressed).
  double constraint_matrix_seconds = 0;
  /// Surface contact (Simulator::set_contact_surface): pairs of primitives closer than the
  /// contact thickness at the end of the step; Newton steps that continuous collision detection
  /// shortened (moves it stopped before two parts of the surface met); seconds it took, with the
  /// joins' update.
  Index contact_pairs = 0;
  int contact_limited_steps = 0;
  double contact_seconds = 0;
};

/// A point that moves with one tet: sum of weights[k] times node k of tet `tet` (weights sum to 1),
/// e.g. a vertex of the material surface (MaterialSurface::vertex_tet and vertex_weights).
struct EmbeddedPoint {
  Index tet = -1;
  Eigen::Vector4d weights = Eigen::Vector4d::Constant(0.25);
};

/// A solid obstacle the contact points are kept out of: half-space below a plane (`point`, outward
/// `normal`), a ball, or an axis-aligned box. With `friction` (a Coulomb coefficient) a point
/// pressed into it is also held against sliding: smoothed and lagged as surface contact's friction
/// (SurfaceContactOptions::friction), the normal force that of the penalty at the step's start,
/// and slips below a thousandth of the mesh's mean edge length per step resisted as by a stiff
/// spring (static friction).
struct Obstacle {
  enum class Kind { kPlane, kSphere, kBox } kind = Kind::kPlane;
  Vec3 point = Vec3::Zero();            ///< plane: a point on it; sphere: the centre; box: min corner
  Vec3 normal = Vec3(0, 0, 1);          ///< plane: outward normal; box: max corner
  double radius = 0;                    ///< sphere
  double friction = 0;                  ///< Coulomb coefficient (0: frictionless)
  static Obstacle plane(const Vec3& point, const Vec3& normal) { return {Kind::kPlane, point, normal.normalized(), 0, 0}; }
  static Obstacle sphere(const Vec3& centre, double radius) { return {Kind::kSphere, centre, Vec3::Zero(), radius, 0}; }
  static Obstacle box(const Vec3& min, const Vec3& max) { return {Kind::kBox, min, max, 0, 0}; }
  /// The same obstacle with friction coefficient `mu`.
  Obstacle with_friction(double mu) const {
    Obstacle o = *this;
    o.friction = mu;
    return o;
  }
  /// Signed distance of x from the obstacle's surface (negative inside) and the outward direction
  /// there.
  double distance(const Vec3& x, Vec3* direction) const;
};

/// Pairs of points facing each other across an incision: vertices of the material surface lying
/// on cut triangles first_cut .. end_cut - 1 (MaterialSurface::triangle_source) that have the same
/// rest position but belong to different tet copies. Springs between them close the incision.
std::vector<std::pair<EmbeddedPoint, EmbeddedPoint>> incision_pairs(const MaterialSurface& surface, std::int64_t first_cut,
                                                                    std::int64_t end_cut);

/// Contact of the material surface with itself and between pieces (see set_contact_surface).
struct SurfaceContactOptions {
  /// The distance (m) below which two parts of the surface repel, and the gap they keep under
  /// light load. 0: a tenth of the surface's mean edge length.
  double thickness = 0;
  /// kappa (N/m) scaling the barrier. 0: Young's modulus times the surface's mean edge length
  /// (a pair about as stiff as a cube of the material an edge wide).
  double stiffness = 0;
  /// Coulomb friction coefficient between parts of the surface (0: none), smoothed and lagged
  /// as in IPC: each step takes the normals and normal forces of the pairs in contact at its
  /// start, and slips below a hundredth of the thickness are resisted as by a stiff spring
  /// (static friction). Against obstacles: Obstacle::friction.
  double friction = 0;
  /// How far apart (in thicknesses) the guards push the two sides of a cut, which coincide when
  /// it is made (0: not at all; the sides stay pressed within the guards' allowance). With 1 a
  /// cut opens by up to a thickness over the 30 steps after it is made, and a side resting on
  /// its cut then slides along it as on any surface; without, it slides only about a tet before
  /// the barrier of the other side's rims, a gap of about 0 away, holds it (docs/contact.md).
  /// Costs more where cut sides press together: each guard is active up to the cushion, and
  /// guards reach joined pairs out to the thickness plus the cushion. At 0.5 a block's half
  /// slides at 0.83 of g sin on a frictionless incline (a ball's cap slides off its cut with
  /// either value). Not safe everywhere yet: 81 sticks piling cross in no pair with 1, Figure
  /// 4's 289 sticks, 144 sticks and the femur incision in none with 0.5; Figure 8's colliding
  /// slinky, with 0.5, crossed in up to 6 pairs in 16 of 76 frames while guards pressed past
  /// their wall crept deeper at each lag, and since they no longer do with a cushion in none
  /// over its whole 3 s.
  double cushion = 0;
};

struct SimulatorState;

/// Backward Euler on a (cut) tet mesh. Cost per Newton iteration: O(tets) element work (analytic
/// eigensystems, no numerical eigen-decomposition) and O(nonzeros) per conjugate gradient
/// iteration, both on all cores; results do not depend on the number of threads. After a cut,
/// `remesh` is O(tets) and needs no factorisation.
class Simulator {
 public:
  /// The mesh's rest positions define the material; its current positions are the start state
  /// (velocities zero). `volume_fraction` per tet (empty: all 1) scales mass and energy, floored
  /// at kMinVolumeFraction. Error(kInvalidArgument) on a bad material or fraction count.
  Simulator(const TetMesh& mesh, const Material& material, std::span<const double> volume_fraction = {});
  Simulator(const Simulator& other);
  Simulator& operator=(const Simulator& other);
  Simulator(Simulator&&) noexcept;
  Simulator& operator=(Simulator&&) noexcept;
  ~Simulator();

  /// After a cut: the new mesh (same material) whose nodes from `first_new_node` on were split
  /// from `new_node_source` (CutBatchReport). Old nodes keep their state; new ones start with
  /// their source's position, velocity and constraint. Masses and elements are rebuilt with the
  /// new volume fractions; springs and contact points, which name tets, are dropped (set them
  /// again).
  void remesh(const TetMesh& mesh, std::span<const double> volume_fraction, Index first_new_node,
              std::span<const Index> new_node_source);
  /// The same straight from the cutter after a batch (its report), for a simulator whose mesh is
  /// the cutter's before that batch: only the copies of the tets the batch touched are rebuilt
  /// (with Cutter::material_fraction), the rest is linear passes, and no CutResult is needed.
  /// What a live session calls after every blade step.
  void remesh(const Cutter& cutter, const CutBatchReport& batch);

  Index num_nodes() const;
  Index num_tets() const;
  const Points& positions() const;
  const Points& velocities() const;
  void set_positions(const Points& x);
  void set_velocities(const Points& v);
  /// Per node lumped mass.
  const Eigen::VectorXd& masses() const;

  /// Holds a node where it is.
  void pin(Index node);
  /// Moves a node to `target` over the next step, whatever the forces (a kinematic node).
  void move_to(Index node, const Vec3& target);
  /// Frees a pinned or kinematic node.
  void release(Index node);

  /// One backward Euler step: minimises the incremental potential by Newton's method with a
  /// backtracking line search, then sets velocities to (x_new - x_old) / dt.
  StepReport step(const StepOptions& options);
  /// Static equilibrium under gravity with the pinned and kinematic nodes held: Newton on the
  /// elastic energy minus gravity's work (no inertia). Velocities are set to zero.
  StepReport solve_static(const StepOptions& options);

  /// Contact: each point is pushed out of every obstacle by a penalty (stiffness / 2) d^2 on its
  /// penetration depth d, a soft constraint that the implicit step treats like any other energy.
  /// Error(kInvalidArgument) when a point names a tet that does not exist.
  void set_contact_points(std::vector<EmbeddedPoint> points);
  /// Error(kInvalidArgument) for a negative or non-finite friction coefficient.
  void add_obstacle(const Obstacle& obstacle);
  /// N/m; by default 10 E h, with h the mean edge length of the mesh the simulator was made with.
  void set_contact_stiffness(double stiffness);
  double contact_stiffness() const;
  /// Contact of the material surface with itself and between pieces: every vertex-triangle and
  /// edge-edge pair of the surface (its vertices follow their copies by their weights) closer
  /// than the thickness adds the barrier kappa b(d), b(d) = -(d - dhat)^2 ln(d / dhat), and every
  /// Newton step is shortened so that no pair reaches distance 0 (continuous collision detection):
  /// parts of the surface never pass through each other. Not counted: pairs of copies that are
  /// neighbours (share a node), unless they face each other across a cut (then those near each
  /// other in the material are guarded as below, the others counted), copies a cut has just separated until their surfaces have moved
  /// apart (their vertices are only guarded against going more than a tenth of the thickness
  /// behind the other side's triangles), and, while springs (add_spring) suture an incision, pairs between the copies they
  /// hold that were within the thickness of each other in the material (the springs pull them
  /// back together) (see src/sim/surface_contact.hpp for the rule, why it should not miss a
  /// collision for long, and what it may still miss). Give the surface again after every cut (remesh drops it, as it drops
  /// the contact points). O(F log F) now; each evaluation O(V + pairs near), parallel.
  /// Error(kInvalidArgument) when the surface names copies or vertices that do not exist.
  void set_contact_surface(const MaterialSurface& surface, const SurfaceContactOptions& options = {});
  /// No surface contact (and no memory of the copies a cut joined).
  void clear_contact_surface();
  /// What surface contact is working with: the thickness and stiffness in use, the candidate
  /// pairs of its broad phase, the pairs of copies still joined across a cut, the guards over
  /// them in the last step, and how often the broad phase was rebuilt (its candidate pairs, and
  /// the pairs of copies whose boxes come close, under them, less often); and how far the two sides
  /// of a fresh cut may press into each other (a tenth of the thickness: what their guards hold
  /// each vertex to; see src/sim/surface_contact.hpp), and how far apart in the material pairs
  /// across a cut may lie that it leaves to those guards (two thicknesses, where the cut runs
  /// between copies that share a node; pressed together, such pairs may go into each other by the
  /// allowance too).
  struct SurfaceContactState {
    bool enabled = false;
    double thickness = 0, stiffness = 0, fresh_cut_allowance = 0, guarded_reach = 0;
    Index candidates = 0, joined_copy_pairs = 0, guards = 0, rebuilds = 0, copy_pair_rebuilds = 0;
    /// Wall seconds spent so far in its parts (tetcut_bench_contact prints them per step):
    /// rebuilding the candidate pairs, and, apart from the rebuilds they set off, shortening the
    /// moves (continuous collision detection), the active terms (measuring the pairs within the
    /// thickness), the guards at a step's start and the joins at its end.
    double rebuild_seconds = 0, ccd_seconds = 0, active_seconds = 0, guard_seconds = 0, join_seconds = 0;
  };
  SurfaceContactState surface_contact() const;
  /// The surface contact energy at the current positions (+inf if two counted parts touch).
  double surface_contact_energy() const;
  /// A zero-rest-length spring (stiffness / 2) |p - q|^2 between two points, e.g. across an
  /// incision to close it.
  void add_spring(const EmbeddedPoint& p, const EmbeddedPoint& q, double stiffness);
  void clear_springs();
  Index num_springs() const;
  /// Anchors: zero-rest-length springs (stiffness / 2) |p - target|^2 from embedded points to
  /// points in space, e.g. a hook pulling the surface toward the cursor. Set as a whole, like the
  /// contact points (remesh drops them); Error(kInvalidArgument) for a tet that does not exist, a
  /// non-finite target or a negative stiffness.
  struct Anchor {
    EmbeddedPoint point;
    Vec3 target = Vec3::Zero();
    double stiffness = 0;
  };
  void set_anchors(std::vector<Anchor> anchors);
  const std::vector<Anchor>& anchors() const;
  /// Where an embedded point is now.
  Vec3 position(const EmbeddedPoint& p) const;

  /// Elastic energy of the current positions.
  double elastic_energy() const;
  /// Gradient of the elastic energy with respect to the positions (|V| x 3): minus the forces.
  Points elastic_gradient() const;
  /// Total momentum sum m v.
  Vec3 momentum() const;
  /// Kinetic energy sum m |v|^2 / 2 (as ClothSimulator::kinetic_energy).
  double kinetic_energy() const;

 private:
  StepReport minimise(const StepOptions& options, bool inertia);
  std::unique_ptr<SimulatorState> state_;
};

}  // namespace tetcut::sim
