// The live session: the cutter, the simulator and the material surface of one scene, advanced a
// step at a time. After a cut the simulator follows the cutter's batch (Simulator::remesh from
// the cutter: only what the batch touched); the surface is rebuilt when contact, springs, hooks
// or a caller need it, and the whole result (pieces) only when asked for.

#include <tetcut/error.hpp>
#include <tetcut/session.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "util/stopwatch.hpp"

namespace tetcut {
namespace {

// Times are sums of steps, so a move meant to start at a step's time may be reached a rounding
// early or late (seconds; far below any step): it starts at that step, not one later.
constexpr double kTimeRounding = 1e-12;

bool in_box(const Box& box, const Vec3& x) { return (x.array() >= box.min.array()).all() && (x.array() <= box.max.array()).all(); }

// Closest point to p on triangle (a, b, c), as barycentric weights (Ericson, Real-Time Collision
// Detection, 5.1.5): geometry for picking a point to hook, not topology.
Eigen::Vector3d closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denominator = va + vb + vc;
  if (!(denominator > 0)) return {1, 0, 0};  // a degenerate triangle: its first corner
  const double v = vb / denominator, w = vc / denominator;
  return {1 - v - w, v, w};
}

void check_finite(const Vec3& p, const char* what) {
  if (!p.allFinite()) throw Error(ErrorKind::kInvalidArgument, std::string(what) + ": not finite");
}

}  // namespace

struct Session::State {
  explicit State(const Scene& s)
      : scene(s),
        cutter(s.embed_surface ? embed(s.mesh, *s.embed_surface, s.embed_options) : Cutter(s.mesh)),
        sim(start_simulator()),
        cut_ids(s.cuts.size(), {-1, -1}),
        scalpel_rest(s.scalpels.size()) {
    if (s.contact_stiffness > 0) sim.set_contact_stiffness(s.contact_stiffness);
    for (const sim::Obstacle& o : s.obstacles) sim.add_obstacle(o);
    pinned.assign(static_cast<std::size_t>(sim.num_nodes()), 0);
    for (Index n = 0; n < sim.num_nodes(); ++n) {
      for (const Box& box : s.pins) {
        if (in_box(box, rest_of(n))) {
          pinned[n] = 1;
          sim.pin(n);
        }
      }
    }
    refresh_constraints();
  }

  sim::Simulator start_simulator() {
    const CutResult& r = whole_result();
    std::vector<double> fractions = r.mesh.material_fractions();
    for (double& f : fractions) f = std::min(f, 1.0);  // a rounding above 1 is not material
    return sim::Simulator(r.mesh.mesh, scene.material, fractions);
  }

  Vec3 rest_of(Index node) const { return cutter.input().rest().row(cutter.node_parent()[node]).transpose(); }
  double dt() const { return scene.step.dt; }
  double now() const { return steps * dt(); }
  // Records a live event of `kind` at the time now; the caller fills in the rest.
  SessionEvent& record(SessionEvent::Kind kind) {
    SessionEvent& e = recording.emplace_back();
    e.kind = kind;
    e.time = now();
    return e;
  }
  // Pins (on) or lets go of the nodes within `radius` of `point`, and records it.
  void set_pinned(const Vec3& p, double radius, bool on, const char* what) {
    check_finite(p, what);
    if (!(radius > 0) || !std::isfinite(radius)) throw Error(ErrorKind::kInvalidArgument, std::string(what) + ": the radius must be positive");
    for (Index n = 0; n < sim.num_nodes(); ++n) {
      if ((on || pinned[n]) && (sim.positions().row(n).transpose() - p).norm() <= radius) {
        pinned[n] = on;
        if (on) {
          sim.pin(n);
        } else {
          sim.release(n);
        }
      }
    }
    SessionEvent& e = record(on ? SessionEvent::Kind::kPin : SessionEvent::Kind::kUnpin);
    e.point = p;
    e.radius = radius;
  }

  CutResult& whole_result() {
    if (!result) {
      result = cutter.result();
      surface = result->surface;
      surface_current = true;
    }
    return *result;
  }
  const MaterialSurface& current_surface() {
    if (!surface_current) {
      const auto start = Clock::now();
      surface = cutter.surface();
      surface_current = true;
      pending.surface += seconds_since(start);
    }
    return surface;
  }

  // World-space events between two steps see the mesh where the simulator has it; new nodes of
  // a batch start at their sources, so once between steps is enough.
  void set_current_once() {
    if (current_set) return;
    cutter.set_current(sim.positions());
    current_set = true;
  }
  BladePose to_material(const BladePose& pose) {
    set_current_once();
    Points world(2, 3);
    world.row(0) = pose.a.transpose();
    world.row(1) = pose.b.transpose();
    const Points rest = cutter.to_rest(world);
    return {rest.row(0).transpose(), rest.row(1).transpose()};
  }

  void after_batch(const CutBatchReport& batch) {
    ++cuts_applied;
    // A batch that missed the material (a blade pose beside the object) changed no tet, so no
    // copy, node or surface patch: nothing to remesh, and the pages' topology still holds.
    if (batch.tets_touched == 0) return;
    const auto start = Clock::now();
    sim.remesh(cutter, batch);
    pinned.resize(static_cast<std::size_t>(sim.num_nodes()), 0);
    for (Index i = 0; i < static_cast<Index>(batch.new_node_source.size()); ++i) {
      pinned[batch.first_new_node + i] = pinned[batch.new_node_source[i]];
    }
    result.reset();
    surface_current = false;
    constraints_stale = true;
    topology_changed = true;
    ++topology_changes;
    pending.remesh += seconds_since(start);
  }

  // The strip between two rest-space poses, cut (nothing when the blade stood still).
  void cut_strip(const BladePose& from, const BladePose& to) {
    const std::array<BladePose, 2> strip{from, to};
    const auto start = Clock::now();
    const TriangleSurface triangles = swept_blade(strip);
    if (triangles.num_triangles() == 0) return;
    const CutBatchReport batch = cutter.cut(triangles);
    pending.cut += seconds_since(start);
    after_batch(batch);
  }

  void apply_transforms(double due) {
    while (next_transform < scene.transforms.size() && scene.transforms[next_transform].time <= due) {
      const SceneTransform& tr = scene.transforms[next_transform++];
      Points x = sim.positions(), v = sim.velocities();
      for (Index n = 0; n < sim.num_nodes(); ++n) {
        x.row(n) = (tr.rotation * (x.row(n).transpose() - tr.centre) + tr.centre + tr.translation).transpose();
        v.row(n) = (tr.rotation * v.row(n).transpose()).transpose();
      }
      sim.set_positions(x);
      sim.set_velocities(v);
      for (Index n = 0; n < sim.num_nodes(); ++n) {
        if (pinned[n]) sim.pin(n);
      }
      for (Hook& h : hooks) h.target = tr.rotation * (h.target - tr.centre) + tr.centre + tr.translation;
      constraints_stale = true;
    }
  }

  void apply_cuts(double due) {
    while (next_cut < scene.cuts.size() && scene.cuts[next_cut].time <= due) {
      const SceneCut& cut = scene.cuts[next_cut];
      const auto start = Clock::now();
      const std::int64_t first_id = cutter.num_cut_triangles();
      CutBatchReport batch;
      if (cut.world_space) {
        set_current_once();
        batch = cutter.cut_deformed(cut.triangles);
      } else {
        batch = cutter.cut(cut.triangles);
      }
      cut_ids[next_cut++] = {first_id, cutter.num_cut_triangles()};
      pending.cut += seconds_since(start);
      after_batch(batch);
    }
  }

  // Each scalpel active during the coming step cuts the strip it sweeps then, between its
  // rest-space poses at the start and the end of the step.
  void apply_scalpels(double t0, double t1) {
    for (std::size_t i = 0; i < scene.scalpels.size(); ++i) {
      const SceneScalpel& blade = scene.scalpels[i];
      if (t1 <= blade.from || t0 >= blade.until) continue;
      const auto start = Clock::now();
      const auto place = [&](const BladePose& pose) { return blade.world_space ? to_material(pose) : pose; };
      if (!scalpel_rest[i]) scalpel_rest[i] = place(blade.at(std::max(t0, blade.from)));
      const BladePose end = place(blade.at(std::min(t1, blade.until)));
      pending.cut += seconds_since(start);
      cut_strip(*scalpel_rest[i], end);
      scalpel_rest[i] = end;
    }
  }

  bool apply_springs(double due) {
    bool added = false;
    while (next_springs < scene.springs.size() && scene.springs[next_springs].time <= due) {
      active_springs.push_back(&scene.springs[next_springs++]);
      added = true;
    }
    if (added) constraints_stale = true;
    return added;
  }

  // Contact points (the surface's vertices), springs across incisions and hooks name tets: set
  // again after every cut.
  void refresh_constraints() {
    const auto start = Clock::now();
    if (!scene.obstacles.empty()) {
      const MaterialSurface& s = current_surface();
      std::vector<sim::EmbeddedPoint> points;
      points.reserve(static_cast<std::size_t>(s.surface.num_vertices()));
      for (Index v = 0; v < s.surface.num_vertices(); ++v) points.push_back({s.vertex_tet[v], s.vertex_weights.row(v).transpose()});
      sim.set_contact_points(std::move(points));
    }
    if (scene.self_collision) sim.set_contact_surface(current_surface(), scene.self_contact);
    sim.clear_springs();
    spring_ends.clear();
    for (const SceneSprings* springs : active_springs) {
      const double k = springs->stiffness > 0 ? springs->stiffness : 100 * sim.contact_stiffness();
      for (int c = springs->first_cut; c <= springs->last_cut; ++c) {
        if (cut_ids[c].first < 0) continue;  // not applied yet
        for (const auto& [p, q] : sim::incision_pairs(current_surface(), cut_ids[c].first, cut_ids[c].second)) {
          sim.add_spring(p, q, k);
          spring_ends.emplace_back(p, q);
        }
      }
    }
    set_anchors();
    constraints_stale = false;
    pending.remesh += seconds_since(start);
  }

  void set_anchors() {
    std::vector<sim::Simulator::Anchor> anchors;
    for (const Hook& h : hooks) {
      if (h.held) anchors.push_back({h.point, h.target, h.stiffness});
    }
    sim.set_anchors(std::move(anchors));
  }

  double widest_spring() const {
    double gap = 0;
    for (const auto& [p, q] : spring_ends) gap = std::max(gap, (sim.position(p) - sim.position(q)).norm());
    return gap;
  }

  // Kinematic nodes: those in an active move box go with its velocity; others are let go.
  void apply_moves(double t) {
    if (scene.moves.empty()) return;
    for (Index n = 0; n < sim.num_nodes(); ++n) {
      if (pinned[n]) continue;
      bool moved = false;
      for (const SceneMove& m : scene.moves) {
        if (t + kTimeRounding >= m.from && t < m.until && in_box(m.box, rest_of(n))) {
          sim.move_to(n, sim.positions().row(n).transpose() + dt() * m.velocity);
          moved = true;
          break;
        }
      }
      if (!moved) sim.release(n);
    }
  }

  struct Hook {
    sim::EmbeddedPoint point;
    Vec3 target;
    double stiffness;
    bool held;
  };

  // The hook `hook` names, which must be held; `what` names the event in the error.
  Hook& held_hook(int hook, const char* what) {
    if (hook < 0 || hook >= static_cast<int>(hooks.size()) || !hooks[hook].held) {
      throw Error(ErrorKind::kInvalidArgument, std::string(what) + ": no hook " + std::to_string(hook) + " is held");
    }
    return hooks[hook];
  }

  const Scene& scene;
  Cutter cutter;
  std::optional<CutResult> result;
  MaterialSurface surface;
  bool surface_current = false;
  sim::Simulator sim;
  std::vector<std::uint8_t> pinned;
  std::vector<std::pair<std::int64_t, std::int64_t>> cut_ids;  // cut id ranges of applied cut events, for springs
  std::vector<std::optional<BladePose>> scalpel_rest;           // each scalpel's last pose, in rest space
  std::vector<const SceneSprings*> active_springs;
  std::vector<std::pair<sim::EmbeddedPoint, sim::EmbeddedPoint>> spring_ends;
  double gap_when_attached = 0;
  std::optional<BladePose> blade_rest;  // the live blade's last pose in this stroke, in rest space
  std::vector<Hook> hooks;
  std::vector<SessionEvent> recording;
  std::size_t next_cut = 0, next_transform = 0, next_springs = 0, next_event = 0;
  bool current_set = false, constraints_stale = false, topology_changed = false;
  int steps = 0, cuts_applied = 0, topology_changes = 0;
  SceneStageSeconds pending;  // stages since the last step
};

namespace {
// The live session runs tet scenes; a cloth scene is refused before anything is built.
const Scene& tet_scene(const Scene& scene) {
  if (scene.cloth) {
    throw Error(ErrorKind::kInvalidInput, "a cloth scene runs in tetcut sim; the live session takes tet meshes",
                scene.source.string());
  }
  return scene;
}
}  // namespace

Session::Session(const Scene& scene) : state_(std::make_unique<State>(tet_scene(scene))) {}
Session::~Session() = default;
Session::Session(Session&&) noexcept = default;
Session& Session::operator=(Session&&) noexcept = default;

double Session::time() const { return state_->now(); }
int Session::steps() const { return state_->steps; }
const std::vector<SessionEvent>& Session::recording() const { return state_->recording; }
const sim::Simulator& Session::simulator() const { return state_->sim; }
const Cutter& Session::cutter() const { return state_->cutter; }
const MaterialSurface& Session::surface() { return state_->current_surface(); }
CutResult& Session::result() { return state_->whole_result(); }
int Session::cuts_applied() const { return state_->cuts_applied; }
int Session::topology_changes() const { return state_->topology_changes; }
Index Session::num_incision_springs() const { return static_cast<Index>(state_->spring_ends.size()); }
double Session::widest_incision_spring() const { return state_->widest_spring(); }
double Session::incision_gap_when_attached() const { return state_->gap_when_attached; }
int Session::num_hooks() const {
  return static_cast<int>(std::count_if(state_->hooks.begin(), state_->hooks.end(), [](const State::Hook& h) { return h.held; }));
}

Points Session::surface_positions() { return surface().positions(state_->cutter.tet_nodes(), state_->sim.positions()); }

SessionStep Session::advance() {
  State& s = *state_;
  const double t = s.now(), dt = s.dt();
  const double due = t + dt / 2;  // events due by the middle of this step happen before it
  // A recording's events first: live, they came between the last step and this one.
  while (s.next_event < s.scene.events.size() && s.scene.events[s.next_event].time <= due) apply(s.scene.events[s.next_event++]);
  s.apply_transforms(due);
  s.apply_cuts(due);
  s.apply_scalpels(t, t + dt);
  const bool springs_added = s.apply_springs(due);
  if (s.constraints_stale) s.refresh_constraints();
  if (springs_added) s.gap_when_attached = std::max(s.gap_when_attached, s.widest_spring());
  s.apply_moves(t);
  const auto step_start = Clock::now();
  SessionStep out;
  out.report = s.sim.step(s.scene.step);
  s.pending.step += seconds_since(step_start);
  out.seconds = s.pending;
  out.topology_changed = s.topology_changed;
  s.pending = {};
  s.topology_changed = false;
  s.current_set = false;
  ++s.steps;
  return out;
}

void Session::blade(const BladePose& pose) {
  State& s = *state_;
  check_finite(pose.a, "blade");
  check_finite(pose.b, "blade");
  if (!((pose.b - pose.a).norm() > 0)) throw Error(ErrorKind::kInvalidArgument, "blade: its two ends coincide");
  const auto start = Clock::now();
  const BladePose rest = s.to_material(pose);
  s.pending.cut += seconds_since(start);
  if (s.blade_rest) s.cut_strip(*s.blade_rest, rest);
  s.blade_rest = rest;
  s.record(SessionEvent::Kind::kBlade).pose = pose;
}

void Session::lift_blade() {
  State& s = *state_;
  s.blade_rest.reset();
  s.record(SessionEvent::Kind::kLiftBlade);
}

int Session::grab(const Vec3& point, double stiffness) {
  State& s = *state_;
  check_finite(point, "grab");
  if (!(stiffness >= 0) || !std::isfinite(stiffness)) throw Error(ErrorKind::kInvalidArgument, "grab: stiffness must not be negative");
  const MaterialSurface& surface = s.current_surface();
  if (surface.surface.num_triangles() == 0) throw Error(ErrorKind::kInvalidArgument, "grab: there is no surface to hook");
  const Points x = surface_positions();
  // The surface point nearest `point`, and the copy whose material its triangle bounds: the hook
  // holds that side, whichever side of an incision the point is on.
  double best = std::numeric_limits<double>::infinity();
  Index best_triangle = -1;
  Eigen::Vector3d best_weights;
  for (Index t = 0; t < surface.surface.num_triangles(); ++t) {
    const auto corner = [&](int k) { return Vec3(x.row(surface.surface.triangles(t, k)).transpose()); };
    const Eigen::Vector3d w = closest_on_triangle(point, corner(0), corner(1), corner(2));
    const double d = (w[0] * corner(0) + w[1] * corner(1) + w[2] * corner(2) - point).squaredNorm();
    if (d < best) {
      best = d;
      best_triangle = t;
      best_weights = w;
    }
  }
  // Its weights in that copy: from the rest positions (a copy's rest shape is its tet's).
  const Index copy = surface.triangle_tet[best_triangle];
  Vec3 rest = Vec3::Zero();
  for (int k = 0; k < 3; ++k) rest += best_weights[k] * surface.surface.vertices.row(surface.surface.triangles(best_triangle, k)).transpose();
  const auto& nodes = s.cutter.tet_nodes()[copy];
  Eigen::Matrix3d edges;
  for (int k = 0; k < 3; ++k) edges.col(k) = s.rest_of(nodes[k + 1]) - s.rest_of(nodes[0]);
  const Vec3 w = edges.partialPivLu().solve(rest - s.rest_of(nodes[0]));
  State::Hook hook;
  hook.point = {copy, Eigen::Vector4d(1 - w.sum(), w[0], w[1], w[2])};
  hook.target = s.sim.position(hook.point);
  hook.stiffness = stiffness > 0 ? stiffness : 100 * s.sim.contact_stiffness();
  hook.held = true;
  s.hooks.push_back(hook);
  s.set_anchors();
  SessionEvent& e = s.record(SessionEvent::Kind::kGrab);
  e.point = point;
  e.stiffness = stiffness;
  return static_cast<int>(s.hooks.size()) - 1;
}

void Session::move_hook(int hook, const Vec3& target) {
  State& s = *state_;
  State::Hook& held = s.held_hook(hook, "move_hook");
  check_finite(target, "move_hook");
  held.target = target;
  s.set_anchors();
  SessionEvent& e = s.record(SessionEvent::Kind::kMoveHook);
  e.hook = hook;
  e.point = target;
}

void Session::release(int hook) {
  State& s = *state_;
  s.held_hook(hook, "release").held = false;
  s.set_anchors();
  s.record(SessionEvent::Kind::kRelease).hook = hook;
}

void Session::pin(const Vec3& point, double radius) { state_->set_pinned(point, radius, true, "pin"); }

void Session::unpin(const Vec3& point, double radius) { state_->set_pinned(point, radius, false, "unpin"); }

void Session::apply(const SessionEvent& e) {
  switch (e.kind) {
    case SessionEvent::Kind::kBlade:
      blade(e.pose);
      return;
    case SessionEvent::Kind::kLiftBlade:
      lift_blade();
      return;
    case SessionEvent::Kind::kGrab:
      grab(e.point, e.stiffness);
      return;
    case SessionEvent::Kind::kMoveHook:
      move_hook(e.hook, e.point);
      return;
    case SessionEvent::Kind::kRelease:
      release(e.hook);
      return;
    case SessionEvent::Kind::kPin:
      pin(e.point, e.radius);
      return;
    case SessionEvent::Kind::kUnpin:
      unpin(e.point, e.radius);
      return;
  }
}

}  // namespace tetcut
