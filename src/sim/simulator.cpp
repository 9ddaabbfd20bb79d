// The simulator's mesh state: elements and lumped masses from the rest shape, nodes and their
// constraints, soft constraints (contact points, springs), and carrying the state over a cut.
// The step itself is in integrator.cpp, the element loops in assembly.cpp.

#include <tetcut/error.hpp>
#include <tetcut/sim.hpp>

#include "collision/twins.hpp"
#include "sim/simulator_state.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

namespace tetcut::sim {
namespace {

// A volume fraction may exceed 1 by rounding (material volume and tet volume are computed
// differently); beyond this it is an error in the caller's data.
constexpr double kFractionRounding = 1e-9;

}  // namespace

void SimulatorState::set_element(Index t, const std::array<Index, 4>& nodes, const std::array<Vec3, 4>& corners, double fraction) {
  Element& e = elements[t];
  e.nodes = nodes;
  Mat3 dm;
  for (int k = 0; k < 3; ++k) dm.col(k) = corners[k + 1] - corners[0];
  const Mat3 inverse = dm.inverse();
  e.weights.bottomRows<3>() = inverse;
  e.weights.row(0) = -inverse.colwise().sum();
  if (!(fraction >= 0 && fraction <= 1 + kFractionRounding)) {
    throw Error(ErrorKind::kInvalidArgument, "volume fraction of tet " + std::to_string(t) + " is not in [0, 1]");
  }
  e.volume = dm.determinant() / 6 * std::clamp(fraction, kMinVolumeFraction, 1.0);
}

void SimulatorState::build(const TetMesh& mesh, std::span<const double> volume_fraction) {
  if (!volume_fraction.empty() && static_cast<Index>(volume_fraction.size()) != mesh.num_tets()) {
    throw Error(ErrorKind::kInvalidArgument, "volume fractions: " + std::to_string(volume_fraction.size()) +
                                                 " values for " + std::to_string(mesh.num_tets()) + " tets");
  }
  const Points& rest_positions = mesh.rest();
  elements.resize(static_cast<std::size_t>(mesh.num_tets()));
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    std::array<Index, 4> nodes;
    std::array<Vec3, 4> corners;
    for (int k = 0; k < 4; ++k) {
      nodes[k] = mesh.tets()(t, k);
      corners[k] = rest_positions.row(nodes[k]).transpose();
    }
    set_element(t, nodes, corners, volume_fraction.empty() ? 1.0 : volume_fraction[t]);
  }
  const Vec3 extent = rest_positions.colwise().maxCoeff() - rest_positions.colwise().minCoeff();
  size = std::max(extent.norm(), std::numeric_limits<double>::min());
  rest = rest_positions;
  compute_masses();
  order_from_scratch(rest);
}

Simulator::Simulator(const TetMesh& mesh, const Material& material, std::span<const double> volume_fraction)
    : state_(std::make_unique<SimulatorState>()) {
  if (!(material.density > 0) || !std::isfinite(material.density)) {
    throw Error(ErrorKind::kInvalidArgument, "density must be a positive number");
  }
  if (!(material.mass_damping >= 0) || !(material.stiffness_damping >= 0)) {
    throw Error(ErrorKind::kInvalidArgument, "damping coefficients must not be negative");
  }
  SimulatorState& s = *state_;
  s.material = material;
  s.parameters = model_parameters(material.model, lame_parameters(material.youngs_modulus, material.poissons_ratio));
  s.x = mesh.current();
  s.v = Points::Zero(mesh.num_nodes(), 3);
  s.constraint.assign(static_cast<std::size_t>(mesh.num_nodes()), -1);
  s.target = Points::Zero(mesh.num_nodes(), 3);
  s.build(mesh, volume_fraction);
  // The default contact stiffness follows the mesh the simulator was made with; cuts, which only
  // copy its tets, keep it.
  double edges = 0;
  for (const SimulatorState::Element& e : s.elements) {
    for (const auto& edge : kTetEdges) edges += (mesh.rest().row(e.nodes[edge[0]]) - mesh.rest().row(e.nodes[edge[1]])).norm();
  }
  s.mean_edge = s.elements.empty() ? 0 : edges / (6.0 * static_cast<double>(s.elements.size()));
  s.contact_stiffness = 10 * material.youngs_modulus * s.mean_edge;
}

Simulator::Simulator(const Simulator& other) : state_(std::make_unique<SimulatorState>(*other.state_)) {}
Simulator& Simulator::operator=(const Simulator& other) {
  if (this != &other) state_ = std::make_unique<SimulatorState>(*other.state_);
  return *this;
}
Simulator::Simulator(Simulator&&) noexcept = default;
Simulator& Simulator::operator=(Simulator&&) noexcept = default;
Simulator::~Simulator() = default;

Index Simulator::num_nodes() const { return state_->num_nodes(); }
Index Simulator::num_tets() const { return static_cast<Index>(state_->elements.size()); }
const Points& Simulator::positions() const { return state_->x; }
const Points& Simulator::velocities() const { return state_->v; }
const Eigen::VectorXd& Simulator::masses() const { return state_->mass; }

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

void Simulator::set_contact_points(std::vector<EmbeddedPoint> points) {
  for (const EmbeddedPoint& p : points) {
    if (p.tet < 0 || p.tet >= num_tets()) throw Error(ErrorKind::kInvalidArgument, "contact point: no such tet");
  }
  state_->contact_points = std::move(points);
}
void Simulator::add_obstacle(const Obstacle& obstacle) {
  if (!(obstacle.friction >= 0) || !std::isfinite(obstacle.friction)) {
    throw Error(ErrorKind::kInvalidArgument, "obstacle: the friction coefficient must be a number, not negative");
  }
  state_->obstacles.push_back(obstacle);
}

// Every surface vertex is a contact point (43k on the sliced hand): found in parallel over fixed
// chunks, in the points' and obstacles' order, as one pass found them.
void SimulatorState::lag_obstacle_friction() {
  obstacle_friction.clear();
  if (std::none_of(obstacles.begin(), obstacles.end(), [](const Obstacle& o) { return o.friction > 0; })) return;
  detail::append_chunks(static_cast<Index>(contact_points.size()), detail::kNodeChunk, &obstacle_friction,
                        [&](Index begin, Index end, std::vector<ObstacleFriction>* out) {
                          for (Index p = begin; p < end; ++p) {
                            const EmbeddedPoint& point = contact_points[static_cast<std::size_t>(p)];
                            ObstacleFriction f;
                            f.nodes = elements[static_cast<std::size_t>(point.tet)].nodes;
                            f.weights = point.weights;
                            f.start = Vec3::Zero();
                            for (int k = 0; k < 4; ++k) f.start += f.weights[k] * start.row(f.nodes[k]).transpose();
                            for (const Obstacle& obstacle : obstacles) {
                              if (!(obstacle.friction > 0)) continue;
                              const double d = obstacle.distance(f.start, &f.normal);
                              if (d >= 0) continue;
                              f.normal_force = -contact_stiffness * d;
                              f.mu = obstacle.friction;
                              out->push_back(f);
                            }
                          }
                        });
}
void Simulator::set_contact_stiffness(double stiffness) {
  if (!(stiffness >= 0) || !std::isfinite(stiffness)) throw Error(ErrorKind::kInvalidArgument, "contact stiffness must not be negative");
  state_->contact_stiffness = stiffness;
  state_->contact_stiffness_given = true;
}
double Simulator::contact_stiffness() const { return state_->contact_stiffness; }

void Simulator::set_contact_surface(const MaterialSurface& surface, const SurfaceContactOptions& options) {
  SimulatorState& s = *state_;
  const TriangleSurface& t = surface.surface;
  const Index V = t.num_vertices(), F = t.num_triangles();
  if (static_cast<Index>(surface.vertex_tet.size()) != V || surface.vertex_weights.rows() != V ||
      static_cast<Index>(surface.triangle_tet.size()) != F) {
    throw Error(ErrorKind::kInvalidArgument, "contact surface: per-vertex or per-triangle data of the wrong size");
  }
  for (const Index copy : surface.vertex_tet) {
    if (copy < 0 || copy >= num_tets()) throw Error(ErrorKind::kInvalidArgument, "contact surface: a vertex names tet " + std::to_string(copy) + " of " + std::to_string(num_tets()));
  }
  for (const Index copy : surface.triangle_tet) {
    if (copy < 0 || copy >= num_tets()) throw Error(ErrorKind::kInvalidArgument, "contact surface: a triangle names tet " + std::to_string(copy) + " of " + std::to_string(num_tets()));
  }
  for (Index f = 0; f < F; ++f) {
    for (int k = 0; k < 3; ++k) {
      if (t.triangles(f, k) < 0 || t.triangles(f, k) >= V) throw Error(ErrorKind::kInvalidArgument, "contact surface: triangle " + std::to_string(f) + " names a vertex that does not exist");
    }
  }
  if (!surface.vertex_weights.allFinite() || !t.vertices.allFinite()) throw Error(ErrorKind::kInvalidArgument, "contact surface: not finite");
  for (const double value : {options.thickness, options.stiffness, options.friction, options.cushion}) {
    if (!(value >= 0) || !std::isfinite(value)) {
      throw Error(ErrorKind::kInvalidArgument, "contact surface: thickness, stiffness, friction and cushion must not be negative");
    }
  }
  std::vector<std::array<Index, 4>> copy_nodes(s.elements.size());
  for (std::size_t e = 0; e < s.elements.size(); ++e) copy_nodes[e] = s.elements[e].nodes;
  if (s.contact_changed.size() != s.elements.size()) s.contact_changed.assign(s.elements.size(), 1);
  s.surface_contact.set_surface(surface, copy_nodes, s.rest, s.x, s.contact_changed, options, s.material.youngs_modulus);
  std::fill(s.contact_changed.begin(), s.contact_changed.end(), 0);
}

void Simulator::clear_contact_surface() { state_->surface_contact.reset(); }

Simulator::SurfaceContactState Simulator::surface_contact() const {
  const detail::SurfaceContact& c = state_->surface_contact;
  SurfaceContactState out;
  out.enabled = c.enabled();
  out.thickness = c.settings().thickness;
  out.stiffness = c.settings().stiffness;
  out.candidates = c.num_candidates();
  out.joined_copy_pairs = c.num_joins();
  out.guards = c.num_guards();
  out.fresh_cut_allowance = c.enabled() ? c.guard_allowance() : 0.0;
  out.guarded_reach = c.enabled() ? c.guarded_reach() : 0.0;
  out.rebuilds = c.num_rebuilds();
  out.copy_pair_rebuilds = c.num_pair_rebuilds();
  const detail::SurfaceContact::PartSeconds& seconds = c.part_seconds();
  out.rebuild_seconds = seconds.rebuild;
  out.ccd_seconds = seconds.ccd;
  out.active_seconds = seconds.active;
  out.guard_seconds = seconds.guards;
  out.join_seconds = seconds.joins;
  return out;
}

double Simulator::surface_contact_energy() const {
  double energy = 0;
  state_->surface_contact.for_each_active(state_->x, [&](const detail::ContactTerm&, double e, const Vec3&, const Mat3&) { energy += e; });
  return energy;
}

void Simulator::add_spring(const EmbeddedPoint& p, const EmbeddedPoint& q, double stiffness) {
  SimulatorState& s = *state_;
  for (const EmbeddedPoint* e : {&p, &q}) {
    if (e->tet < 0 || e->tet >= num_tets()) throw Error(ErrorKind::kInvalidArgument, "spring: no such tet");
  }
  if (!(stiffness >= 0) || !std::isfinite(stiffness)) throw Error(ErrorKind::kInvalidArgument, "spring: stiffness must not be negative");
  s.springs.push_back({p, q, stiffness});
  s.surface_contact.suture(p.tet, q.tet);
  s.springs_pending = true;  // the pattern must hold the blocks between the two tets' nodes
}
void Simulator::clear_springs() {
  state_->springs.clear();
  state_->surface_contact.clear_sutures();
}

void Simulator::set_anchors(std::vector<Anchor> anchors) {
  for (const Anchor& a : anchors) {
    if (a.point.tet < 0 || a.point.tet >= num_tets()) throw Error(ErrorKind::kInvalidArgument, "anchor: no such tet");
    if (!a.target.allFinite() || !a.point.weights.allFinite()) throw Error(ErrorKind::kInvalidArgument, "anchor: not finite");
    if (!(a.stiffness >= 0) || !std::isfinite(a.stiffness)) throw Error(ErrorKind::kInvalidArgument, "anchor: stiffness must not be negative");
  }
  state_->anchors = std::move(anchors);
}
const std::vector<Simulator::Anchor>& Simulator::anchors() const { return state_->anchors; }
Index Simulator::num_springs() const { return static_cast<Index>(state_->springs.size()); }

Vec3 Simulator::position(const EmbeddedPoint& p) const { return state_->point_position(p, state_->x); }

void SimulatorState::carry_new_nodes(Index first_new_node, std::span<const Index> new_node_source) {
  if (first_new_node != num_nodes()) throw Error(ErrorKind::kInvalidArgument, "remesh: the node counts do not match the cut report");
  for (Index i = 0; i < static_cast<Index>(new_node_source.size()); ++i) {
    const Index source = new_node_source[i];
    if (source < 0 || source >= first_new_node + i) throw Error(ErrorKind::kInvalidArgument, "remesh: a node's source does not exist");
  }
  const Index total = first_new_node + static_cast<Index>(new_node_source.size());
  x.conservativeResize(total, 3);
  v.conservativeResize(total, 3);
  target.conservativeResize(total, 3);
  rest.conservativeResize(total, 3);
  for (Index i = 0; i < static_cast<Index>(new_node_source.size()); ++i) {
    const Index source = new_node_source[i];
    x.row(first_new_node + i) = x.row(source);
    v.row(first_new_node + i) = v.row(source);
    target.row(first_new_node + i) = target.row(source);
    rest.row(first_new_node + i) = rest.row(source);  // a split node is where its source is, in the material
    constraint.push_back(constraint[source]);

  }
  // A reusable matrix was assembled with the sources where they were then.
  if (assembled_at.rows() == first_new_node) {
    assembled_at.conservativeResize(total, 3);
    for (Index i = 0; i < static_cast<Index>(new_node_source.size()); ++i) assembled_at.row(first_new_node + i) = assembled_at.row(new_node_source[i]);
  }
  // Springs, anchors, contact points and the contact surface name tets and barycentric weights
  // that a cut may change (the surface contact keeps its joins of copies: their ids stay).
  contact_points.clear();
  obstacle_friction.clear();
  surface_contact.clear_surface();
  surface_contact.clear_sutures();
  springs.clear();
  anchors.clear();
}

void Simulator::remesh(const TetMesh& mesh, std::span<const double> volume_fraction, Index first_new_node,
                       std::span<const Index> new_node_source) {
  SimulatorState& s = *state_;
  if (mesh.num_nodes() != first_new_node + static_cast<Index>(new_node_source.size())) {
    throw Error(ErrorKind::kInvalidArgument, "remesh: the node counts do not match the cut report");
  }
  if (!volume_fraction.empty() && static_cast<Index>(volume_fraction.size()) != mesh.num_tets()) {
    throw Error(ErrorKind::kInvalidArgument, "remesh: " + std::to_string(volume_fraction.size()) + " volume fractions for " +
                                                 std::to_string(mesh.num_tets()) + " tets");
  }
  s.carry_new_nodes(first_new_node, new_node_source);
  s.build(mesh, volume_fraction);
  s.contact_changed.assign(static_cast<std::size_t>(mesh.num_tets()), 1);
}

void Simulator::remesh(const Cutter& cutter, const CutBatchReport& batch) {
  SimulatorState& s = *state_;
  const Index old_tets = num_tets();
  if (cutter.num_nodes() != batch.first_new_node + static_cast<Index>(batch.new_node_source.size()) ||
      cutter.num_tets() != batch.first_new_tet + static_cast<Index>(batch.new_tet_source.size()) || batch.first_new_tet != old_tets) {
    throw Error(ErrorKind::kInvalidArgument, "remesh: the cutter and its last batch report do not match this simulator's mesh");
  }
  s.carry_new_nodes(batch.first_new_node, batch.new_node_source);
  // Elements to rebuild: every copy of a touched tet (its material fraction may have changed; new
  // copies are among them) and every copy whose nodes changed (a split node can take copies of
  // untouched neighbours along). The others keep their nodes, shape and fraction.
  s.elements.resize(static_cast<std::size_t>(cutter.num_tets()));
  const Points& rest = cutter.input().rest();
  const auto& parent = cutter.node_parent();
  const auto rebuild = [&](Index copy) {
    std::array<Vec3, 4> corners;
    const std::array<Index, 4>& nodes = cutter.tet_nodes()[copy];
    for (int k = 0; k < 4; ++k) corners[k] = rest.row(parent[nodes[k]]).transpose();
    s.set_element(copy, nodes, corners, std::min(cutter.material_fraction(copy), 1.0));
  };
  std::vector<Index> rebuilt;
  for (const Index t : batch.touched) {
    for (const Index copy : cutter.copies_of(t)) {
      rebuild(copy);
      rebuilt.push_back(copy);
    }
  }
  for (const Index copy : batch.changed_tets) {
    rebuild(copy);
    rebuilt.push_back(copy);
  }
  std::sort(rebuilt.begin(), rebuilt.end());
  rebuilt.erase(std::unique(rebuilt.begin(), rebuilt.end()), rebuilt.end());
  s.contact_changed.resize(s.elements.size(), 1);  // new copies
  for (const Index copy : rebuilt) s.contact_changed[static_cast<std::size_t>(copy)] = 1;
  s.compute_masses();
  s.update_after_cut(old_tets, batch.new_tet_source, batch.changed_tets, rebuilt);
}

void Simulator::set_positions(const Points& x) {
  if (x.rows() != num_nodes() || !x.allFinite()) throw Error(ErrorKind::kInvalidArgument, "positions: wrong size or not finite");
  state_->x = x;
  state_->reusable = false;  // moved from outside (a rigid transform, say): assemble afresh
}

void Simulator::set_velocities(const Points& v) {
  if (v.rows() != num_nodes() || !v.allFinite()) throw Error(ErrorKind::kInvalidArgument, "velocities: wrong size or not finite");
  state_->v = v;
}

void Simulator::pin(Index node) {
  state_->constraint.at(node) = 0;
  state_->target.row(node) = state_->x.row(node);
}

void Simulator::move_to(Index node, const Vec3& target) {
  if (!target.allFinite()) throw Error(ErrorKind::kInvalidArgument, "move_to: the target is not finite");
  state_->constraint.at(node) = 1;
  state_->target.row(node) = target.transpose();
}

void Simulator::release(Index node) { state_->constraint.at(node) = -1; }

double Simulator::elastic_energy() const { return state_->elastic_energy(state_->x); }

Points Simulator::elastic_gradient() const {
  std::vector<double> g(3 * static_cast<std::size_t>(num_nodes()), 0.0);
  state_->elastic_gradient(state_->x, &g);
  return Eigen::Map<const Points>(g.data(), num_nodes(), 3);
}

Vec3 Simulator::momentum() const { return (state_->mass.asDiagonal() * state_->v).colwise().sum().transpose(); }

double Simulator::kinetic_energy() const {
  double e = 0;
  for (Index n = 0; n < num_nodes(); ++n) e += 0.5 * state_->mass[n] * state_->v.row(n).squaredNorm();
  return e;
}

std::vector<std::pair<EmbeddedPoint, EmbeddedPoint>> incision_pairs(const MaterialSurface& surface, std::int64_t first_cut,
                                                                    std::int64_t end_cut) {
  // Vertices on the chosen cut triangles, grouped by rest position up to its rounding (two
  // copies may round one point differently: collision/twins.hpp); a position held by two copies
  // is a point on both sides of the incision.
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(surface.surface.num_vertices()), 0);
  std::vector<Index> on_cut;
  for (Index t = 0; t < surface.surface.num_triangles(); ++t) {
    const std::int64_t source = surface.triangle_source[t];
    if (source < first_cut || source >= end_cut) continue;
    for (int k = 0; k < 3; ++k) {
      const Index v = surface.surface.triangles(t, k);
      if (seen[v]) continue;
      seen[v] = 1;
      on_cut.push_back(v);
    }
  }
  std::sort(on_cut.begin(), on_cut.end());
  Points rest(static_cast<Index>(on_cut.size()), 3);
  for (std::size_t i = 0; i < on_cut.size(); ++i) rest.row(static_cast<Index>(i)) = surface.surface.vertices.row(on_cut[i]);
  const double scale = rest.size() > 0 ? rest.cwiseAbs().maxCoeff() : 0.0;
  const std::vector<Index> twin = collision::twin_ids(rest, rest, std::max(64 * std::numeric_limits<double>::epsilon() * scale, std::numeric_limits<double>::min()),
                                                      std::numeric_limits<double>::infinity());
  // Per group (by its id, in the order of its smallest member): the first vertex with each other.
  std::map<Index, std::vector<Index>> groups;
  for (std::size_t i = 0; i < on_cut.size(); ++i) groups[twin[i]].push_back(on_cut[i]);
  std::vector<std::pair<EmbeddedPoint, EmbeddedPoint>> pairs;
  const auto point = [&](Index v) { return EmbeddedPoint{surface.vertex_tet[v], surface.vertex_weights.row(v).transpose()}; };
  std::vector<std::vector<Index>> ordered;
  for (auto& [id, vertices] : groups) ordered.push_back(std::move(vertices));
  std::sort(ordered.begin(), ordered.end(), [&](const auto& a, const auto& b) {
    const auto ra = surface.surface.vertices.row(a[0]), rb = surface.surface.vertices.row(b[0]);
    return std::lexicographical_compare(ra.data(), ra.data() + 3, rb.data(), rb.data() + 3);
  });
  for (const std::vector<Index>& vertices : ordered) {
    for (std::size_t i = 1; i < vertices.size(); ++i) {
      if (surface.vertex_tet[vertices[i]] != surface.vertex_tet[vertices[0]]) pairs.emplace_back(point(vertices[0]), point(vertices[i]));
    }
  }
  return pairs;
}

}  // namespace tetcut::sim
