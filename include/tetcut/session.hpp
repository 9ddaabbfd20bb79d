#pragma once
// A live session: a cut object simulated one time step at a time while it takes events.
//
//   tetcut::Session session(tetcut::load_scene("scene.json"));
//   session.blade({a, b});              // a scalpel's pose (world space): the strip it swept is cut
//   const int hook = session.grab(p);   // a hook on the surface point nearest p
//   session.move_hook(hook, target);    // a spring pulls it there
//   session.advance();                  // the scene's own events due now, then one step
//   tetcut::write_recording("take.json", scene, session);  // replays with tetcut sim
//
// It owns the cutter, the simulator and the material surface. `tetcut sim` runs every scene
// through one (its timed cuts, scalpels, transforms and springs are applied in advance()), so a
// live session and a script share one loop. Events a caller applies are recorded with the
// simulated time; a recording is the scene plus those events, and replaying it applies each
// where it was applied live (before the scene's own events of that step), so the replay gives
// the same pieces and positions, bit for bit on the same number of threads.
//
// A bad event (a non-finite pose or point, a hook that does not exist or was released, a point
// with no surface near it) throws Error(kInvalidArgument) and changes nothing.

#include <tetcut/scene.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace tetcut {

/// What one step of a session did.
struct SessionStep {
  sim::StepReport report;
  /// This step's stages in seconds (the events before it included): cut, surface, remesh, step.
  SceneStageSeconds seconds;
  /// A cut changed the mesh since the last step: the surface and pieces are new.
  bool topology_changed = false;
};

class Session {
 public:
  /// The scene's set-up: its mesh (or the surface embedded in a lattice), material, gravity and
  /// solver, pins, moves, obstacles, contact stiffness. Its timed events are applied by advance().
  /// The session reads `scene` as it runs: it must outlive the session.
  explicit Session(const Scene& scene);
  ~Session();
  Session(Session&&) noexcept;
  Session& operator=(Session&&) noexcept;

  /// The scene's events due by the middle of the next step, then that step. O(the step).
  SessionStep advance();
  /// Simulated seconds so far (steps times dt), and steps so far.
  double time() const;
  int steps() const;

  // Live events, applied now (before the next step) and recorded.
  /// The blade is at `pose` (world space): the strip between its last pose in this stroke and
  /// this one is cut, both mapped to rest space through the current motion (so consecutive
  /// strips meet in the material). The first pose of a stroke cuts nothing.
  void blade(const BladePose& pose);
  /// The blade leaves the material: its next pose starts a new stroke.
  void lift_blade();
  /// Hooks the material surface at its point nearest `point` (world space) with a spring of
  /// `stiffness` (0: 100 times the contact stiffness) to a target, at first the point itself.
  /// Returns the hook's number (0, 1, ... in order).
  int grab(const Vec3& point, double stiffness = 0);
  void move_hook(int hook, const Vec3& target);
  void release(int hook);
  /// Holds where they are the nodes within `radius` of `point` (world space), or lets them go.
  void pin(const Vec3& point, double radius);
  void unpin(const Vec3& point, double radius);
  /// Any of the above, as a recording lists it (its time is not checked).
  void apply(const SessionEvent& event);

  /// The events applied through the calls above, with their times.
  const std::vector<SessionEvent>& recording() const;

  // State.
  const sim::Simulator& simulator() const;
  const Cutter& cutter() const;
  /// The material surface (rest positions) and where its vertices are now (|V| x 3).
  const MaterialSurface& surface();
  Points surface_positions();
  /// The whole result: pieces, the mesh with its fields. Rebuilt after cuts when asked for.
  CutResult& result();
  /// Cut batches applied (a scene's cuts, scalpel strips, blade strips), and those of them that
  /// changed the mesh (a strip beside the object changes nothing).
  int cuts_applied() const;
  int topology_changes() const;
  /// Springs across incisions now, the widest gap between the two ends of one, and the widest
  /// when they were attached (how far the incision had opened).
  Index num_incision_springs() const;
  double widest_incision_spring() const;
  double incision_gap_when_attached() const;
  /// Hooks held now (released ones excluded).
  int num_hooks() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Writes a session's recording: the scene's JSON with its file paths made absolute, the
/// session's events, and a duration of the session's time, so that `tetcut sim` replays it.
void write_recording(const std::filesystem::path& path, const Scene& scene, const Session& session);
/// The recording's text (JSON), as write_recording writes it.
std::string recording_json(const Scene& scene, const Session& session);

}  // namespace tetcut
