#pragma once
// What a Simulator holds, shared by its parts: the mesh's elements and nodes (simulator.cpp), the
// element loops that evaluate and assemble them (assembly.cpp), and the Newton integrator
// (integrator.cpp).

#include "sim/block_sparse.hpp"
#include "sim/elasticity.hpp"
#include "sim/element_batch.hpp"
#include "sim/surface_contact.hpp"

#include <tetcut/sim.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace tetcut::sim {

struct SimulatorState {
  // Obstacle friction's smoothing: slips below this share of the mean edge length per step are
  // static (a thousandth: as surface contact's hundredth of its thickness, a tenth of an edge).
  static constexpr double kStaticSlipShare = 1e-3;

  struct Element {
    std::array<Index, 4> nodes;
    detail::ShapeWeights weights;  // dF/dx: F = sum_a x_a w_a^T
    double volume;                 // rest volume times the material fraction
  };
  struct Spring {
    EmbeddedPoint p, q;
    double stiffness;
  };

  Material material;
  Lame parameters;
  std::vector<Element> elements;  // by tet id
  std::vector<EmbeddedPoint> contact_points;
  std::vector<Obstacle> obstacles;
  // Friction against obstacles over the current step, lagged as surface contact's: per contact
  // point pressed into an obstacle with friction at the step's start, the obstacle's normal
  // there, the penalty's normal force, the point's position then and the coefficient.
  struct ObstacleFriction {
    std::array<Index, 4> nodes;
    Eigen::Vector4d weights;
    Vec3 normal, start;
    double normal_force, mu;
  };
  std::vector<ObstacleFriction> obstacle_friction;
  double contact_stiffness = 0;
  double mean_edge = 0;  // of the mesh the simulator was made with: the length friction's smoothing follows
  bool contact_stiffness_given = false;
  std::vector<Spring> springs;
  std::vector<Simulator::Anchor> anchors;
  // Contact of the material surface with itself (set_contact_surface): mutable, as its candidate
  // list is a cache of the positions it was last asked about. `contact_changed`: per copy,
  // whether a cut changed it since the surface was last set.
  mutable detail::SurfaceContact surface_contact;
  // for_each_constraint's scratch: the contact points inside an obstacle (point, obstacle, the
  // signed distance and the outward normal there).
  struct Penetration {
    Index point;
    int obstacle;
    double distance;
    Vec3 normal;
  };
  mutable std::vector<Penetration> penetrations;
  std::vector<std::uint8_t> contact_changed;
  Points x, v;
  Eigen::VectorXd mass;
  double size = 1;
  /// Per node: -1 free, 0 pinned, 1 moved to target.
  std::vector<std::int8_t> constraint;
  Points target;

  // The elements in a spatial order (Morton order of their rest centroids; a cut's new copies
  // are appended), cut into clusters of kCluster: cluster k is positions k kCluster ... The
  // clusters are coloured: no two of a colour share a node, so a colour's clusters scatter into
  // node vectors and the matrix on all threads at once, every entry receives its terms in a
  // fixed order whatever the threads, and a cluster's writes stay close in memory.
  static constexpr Index kCluster = 128;
  std::vector<Index> element_order;     // position -> tet id
  std::vector<Index> element_position;  // tet id -> position
  Index appended_since_order = 0;       // copies appended since the last spatial sort
  std::vector<Index> cluster_color;
  std::vector<std::uint64_t> node_colors;  // per node: the colours (below 64) of its clusters
  bool colors_past_64 = false;             // then node_colors is incomplete: colour from scratch
  std::vector<Index> color_start, color_clusters;
  // What the element loops read and write, stored by position so that they stream through memory
  // (random access to per-element data was half the cost of assembly at 100k tets): the element,
  // its 16 slots in the pattern, and its V from its last SVD (the next SVD starts there; the
  // deformation changes little between Newton iterations and steps, so Jacobi needs fewer sweeps).
  struct OrderedElement {
    Element element;
    std::array<Index, 16> slots;
  };
  std::vector<OrderedElement> ordered;
  std::vector<Mat3> ordered_v;
  // The Newton system's block pattern of elements and springs. Built from scratch when due;
  // otherwise brought up to date at the next step: blocks of the elements a cut changed or added
  // (pattern_pending, positions) and of springs added since.
  detail::BlockSparseMatrix hessian;
  bool pattern_rebuild = true;
  std::vector<Index> pattern_pending;
  bool springs_pending = false;
  Index blocks_at_build = 0;
  Points rest;  // per node

  // Reusing the Newton matrix (StepOptions::reuse_hessian): its elastic part was assembled at
  // `assembled_at`; the other terms in it are recorded (per node, the mass term added to the
  // diagonal; the contact and spring terms), so that a later step takes them out and puts its
  // own in. A cut since then leaves element contributions to take out (the old element, its
  // slots and warm start) and to put in (positions), both at assembled_at.
  struct ConstraintTerm {
    ConstraintTerm() {}  // written in place (a resize() for a parallel fill zeroes nothing)
    ConstraintTerm(const std::array<Index, 16>& n, const std::array<double, 16>& c, int k, const Mat3& h)
        : nodes(n), coefficients(c), count(k), d2E(h) {}
    std::array<Index, 16> nodes;
    std::array<double, 16> coefficients;
    int count;
    Mat3 d2E;
  };
  bool reusable = false;
  int reusable_age = 0;  // steps the matrix has served
  Points assembled_at;
  std::vector<double> ledger_nodal;
  std::vector<ConstraintTerm> ledger_constraints;
  // Seconds add_recorded_terms took, summed (a step reports its share: StepReport).
  double constraint_matrix_seconds = 0;
  std::vector<std::pair<OrderedElement, Mat3>> reuse_take_out;
  std::vector<Index> reuse_put_in;
  // Scratch of the constraint terms' scatter: per term its first block, per block its slot; the
  // (term, row corner) entries bucketed by chunk of rows, in the terms' order.
  std::vector<Index> term_block_start, term_slots, term_row_start, term_row_fill;
  std::vector<std::array<Index, 2>> term_rows;
  // Scratch of the surface contact terms' gradient: per group of terms after the first, its own
  // gradient (3 per node), added in the groups' order.
  std::vector<std::vector<double>> term_group_gradient;

  // Scratch reused from step to step, so that a step allocates nothing once sizes settle (and
  // why a Simulator, even through const calls, is for one thread at a time).
  detail::ConjugateGradientWorkspace cg;
  mutable std::vector<double> partial;
  detail::BlockSparseMatrix damping;  // the stiffness at the start of a step, for Rayleigh damping
  std::vector<double> current_gradient, trial_gradient, direction, rhs, weight, product;
  std::vector<std::uint8_t> free, all;
  Points start, prediction, trial, displacement;

  Index num_nodes() const { return static_cast<Index>(x.rows()); }
  Mat3 deformation_gradient(const Element& e, const Points& at) const {
    return detail::deformation_gradient(e.weights, at.row(e.nodes[0]).transpose(), at.row(e.nodes[1]).transpose(),
                                        at.row(e.nodes[2]).transpose(), at.row(e.nodes[3]).transpose());
  }

  /// Rebuilds elements, masses, order and colours from a mesh (constructor and remesh). O(T log T).
  void build(const TetMesh& mesh, std::span<const double> volume_fraction);
  /// Element t from its nodes, their rest positions and its material fraction (checked, floored
  /// at kMinVolumeFraction).
  void set_element(Index t, const std::array<Index, 4>& nodes, const std::array<Vec3, 4>& rest, double fraction);
  void compute_masses();
  /// Nodes split by a cut start as their sources (position, velocity, constraint, rest position);
  /// springs, anchors and contact points are dropped.
  void carry_new_nodes(Index first_new_node, std::span<const Index> new_node_source);

  Index num_clusters() const { return (static_cast<Index>(ordered.size()) + kCluster - 1) / kCluster; }
  std::span<const OrderedElement> cluster(Index k) const;
  /// The spatial order, the ordered copy and colours from scratch; warm starts follow their
  /// elements by id; the pattern is due for a build. O(T log T).
  void order_from_scratch(const Points& rest_positions);
  /// Greedy colouring of the clusters. O(tets) while 64 colours suffice, O(sum over nodes of
  /// their clusters squared) beyond (a node in very many copies).
  void color_from_scratch();
  /// The clusters grouped by colour, from cluster_color.
  void group_colors();
  /// After a cut whose elements are already in `elements`: elements old_count .. are new copies
  /// of new_source[i]; `renoded` existed and changed nodes; `rebuilt` are all existing elements
  /// whose data changed. Appends the new ones, recolours the clusters that changed, and leaves
  /// the pattern's update for the next step. O(what changed) + O(clusters); from scratch once
  /// copies appended since the last sort reach a quarter of the mesh.
  void update_after_cut(Index old_count, std::span<const Index> new_source, std::span<const Index> renoded,
                        std::span<const Index> rebuilt);
  /// The pattern from scratch, with every element's slots (a reusable matrix is lost).
  void build_pattern();
  /// Adds sign times an element's projected Hessian at positions `at` into its slots (the
  /// scalar kernel; for the few elements a cut changed). `v` is its warm start, updated.
  void add_element_hessian(const Element& e, const std::array<Index, 16>& slots, Mat3* v, const Points& at, double sign);
  /// The element contributions a cut left to take out and put in (see above).
  void apply_cut_to_reused_matrix();
  /// Brings the pattern up to date before a step (see the members). O(pending elements and
  /// springs), or a build.
  void refresh_structure();

  /// The material as the lane kernel takes it.
  detail::LaneMaterial lane_parameters() const;
  /// Elements at positions first .. first + count - 1 into a lane batch, at positions `at`.
  void pack(const Points& at, Index first, int count, detail::LaneBatch* batch) const;
  /// Psi and, when `stress` is set, P of the element at position `pos` for deformation F.
  double energy_at(Index pos, const Mat3& F, Mat3* stress) const;
  /// Elastic energy at `at` (sum of volume * Psi), deterministic. O(tets), parallel.
  double elastic_energy(const Points& at) const;
  /// Elastic energy at `at`, adding its gradient into `gradient` (3 per node). O(tets), parallel
  /// by colour.
  double elastic_gradient(const Points& at, std::vector<double>* gradient) const;
  /// The same, and the projected Hessian into the pattern's values (which it zeroes first);
  /// updates the elements' SVD warm starts. Needs a fresh structure (refresh_structure).
  double assemble_hessian(const Points& at, std::vector<double>* gradient);

  /// An embedded point's position at node positions `at`: sum_k w_k at(n_k) over its tet's nodes.
  Vec3 point_position(const EmbeddedPoint& p, const Points& at) const {
    Vec3 y = Vec3::Zero();
    for (int k = 0; k < 4; ++k) y += p.weights[k] * at.row(elements[p.tet].nodes[k]).transpose();
    return y;
  }

  /// Lags obstacle friction for the step starting at `start` (see obstacle_friction). O(points x
  /// obstacles).
  void lag_obstacle_friction();

  /// The soft constraints as energies of one point y = sum_i c_i x_{n_i} (up to 16 nodes: a
  /// surface contact pair's y is the vector between its closest points); calls
  /// visit(nodes, coefficients, count, energy, dE/dy, d2E/dy2) for each active one at `at`; the
  /// surface contact's pairs and guards last, unless `surface_pairs` is false (the integrator
  /// takes those in parallel: SurfaceContact::active_chunks).
  template <typename Visit>
  void for_each_constraint(const Points& at, Visit&& visit, bool surface_pairs = true) const;
};

template <typename Visit>
void SimulatorState::for_each_constraint(const Points& at, Visit&& visit, bool surface_pairs) const {
  std::array<Index, 16> nodes{};
  std::array<double, 16> coefficients{};
  // The points inside obstacles, found in parallel over fixed chunks (every surface vertex is a
  // contact point: 43k on the sliced hand, whose serial pass took 0.29 ms an evaluation), then
  // visited in the points' and obstacles' order, as one pass did.
  penetrations.clear();
  if (!obstacles.empty()) {
    detail::append_chunks(static_cast<Index>(contact_points.size()), detail::kNodeChunk, &penetrations,
                          [&](Index begin, Index end, std::vector<Penetration>* out) {
                            for (Index p = begin; p < end; ++p) {
                              const Vec3 y = point_position(contact_points[static_cast<std::size_t>(p)], at);
                              for (std::size_t o = 0; o < obstacles.size(); ++o) {
                                Vec3 n;
                                const double d = obstacles[o].distance(y, &n);
                                if (d < 0) out->push_back({p, static_cast<int>(o), d, n});
                              }
                            }
                          });
  }
  for (const Penetration& inside : penetrations) {
    const EmbeddedPoint& point = contact_points[static_cast<std::size_t>(inside.point)];
    for (int k = 0; k < 4; ++k) {
      nodes[k] = elements[point.tet].nodes[k];
      coefficients[k] = point.weights[k];
    }
    const double d = inside.distance;
    const Vec3& n = inside.normal;
    // (k / 2) d^2; the Hessian keeps the normal part only (positive semi-definite).
    visit(nodes, coefficients, 4, 0.5 * contact_stiffness * d * d, Vec3(contact_stiffness * d * n), Mat3(contact_stiffness * n * n.transpose()));
  }
  // Slips below this per step are held as by a stiff spring (see Obstacle::friction).
  const double static_slip = kStaticSlipShare * mean_edge;
  for (const ObstacleFriction& f : obstacle_friction) {
    Vec3 u = -f.start;
    for (int k = 0; k < 4; ++k) {
      nodes[k] = f.nodes[k];
      coefficients[k] = f.weights[k];
      u += coefficients[k] * at.row(nodes[k]).transpose();
    }
    Vec3 g;
    Mat3 matrix;
    const double energy = detail::friction_energy(u, f.normal, f.normal_force, f.mu, static_slip, &g, &matrix);
    visit(nodes, coefficients, 4, energy, g, matrix);
  }
  for (const Simulator::Anchor& anchor : anchors) {
    Vec3 y = Vec3::Zero();
    for (int k = 0; k < 4; ++k) {
      nodes[k] = elements[anchor.point.tet].nodes[k];
      coefficients[k] = anchor.point.weights[k];
      y += coefficients[k] * at.row(nodes[k]).transpose();
    }
    const Vec3 d = y - anchor.target;
    visit(nodes, coefficients, 4, 0.5 * anchor.stiffness * d.squaredNorm(), Vec3(anchor.stiffness * d),
          Mat3(anchor.stiffness * Mat3::Identity()));
  }
  for (const Spring& spring : springs) {
    Vec3 y = Vec3::Zero();
    for (int k = 0; k < 4; ++k) {
      nodes[k] = elements[spring.p.tet].nodes[k];
      nodes[k + 4] = elements[spring.q.tet].nodes[k];
      coefficients[k] = spring.p.weights[k];
      coefficients[k + 4] = -spring.q.weights[k];
    }
    for (int k = 0; k < 8; ++k) y += coefficients[k] * at.row(nodes[k]).transpose();
    visit(nodes, coefficients, 8, 0.5 * spring.stiffness * y.squaredNorm(), Vec3(spring.stiffness * y),
          Mat3(spring.stiffness * Mat3::Identity()));
  }
  if (surface_pairs) {
    surface_contact.for_each_active(at, [&](const detail::ContactTerm& t, double energy, const Vec3& dE, const Mat3& d2E) {
      visit(t.nodes, t.coefficients, t.count, energy, dE, d2E);
    });
  }
  surface_contact.for_each_friction(at, [&](const detail::ContactTerm& t, double energy, const Vec3& dE, const Mat3& d2E) {
    visit(t.nodes, t.coefficients, t.count, energy, dE, d2E);
  });
}

}  // namespace tetcut::sim
