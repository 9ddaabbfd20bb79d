#pragma once
// Scenes: a JSON file describing a simulation with cuts, and a runner that writes its frames.
//
//   tetcut::Scene scene = tetcut::load_scene("slinky.json");   // validated, clear errors
//   tetcut::run_scene(scene, "out", {});                       // frames + ParaView series
//
// The format (every key optional unless marked; times in seconds; lengths in the mesh's units):
//
//   { "mesh":      {"file": PATH} | {"grid": {"box": [x0,y0,z0,x1,y1,z1], "cells": [nx,ny,nz],
//                                             "tets_per_cube": 5|6}}
//                  | {"bcc": {"box": [...], "spacing": H}} | {"tet": [[x,y,z] x 4]}   (mesh or embed required)
//     "embed":     {"surface": PATH, "keep": "inside"|"largest", "spacing": H | "cells": N}
//                  (with "archive": A.tar.gz, "surface" is a file inside that archive)
//     "material":  {"model": "stable_neo_hookean"|"corotated", "youngs_modulus", "poissons_ratio",
//                   "density", "mass_damping", "stiffness_damping"}
//     "gravity":   [gx, gy, gz]
//     "time":      {"dt", "duration" (required), "output_every"}
//     "solver":    {"mode": "converged"|"real_time", "tolerance", "max_newton_iterations",
//                   "max_cg_iterations", "reuse_hessian", "linear": "cg"|"cholesky",
//                   "first_guess": "prediction"|"start"}   real_time: a fixed budget per step (by
//                   default 1 Newton iteration of at most 30 CG iterations, the matrix kept for up
//                   to 4 steps; see StepOptions::real_time). "reuse_hessian": 1 assembles every
//                   step (steadier on sliver-rich embedded meshes after cuts); "first_guess":
//                   where Newton starts, "prediction" by default, "start" steadier where things
//                   collide or snap (StepOptions::first_guess)
//     "pin":       [{"box": [...]}]                     nodes whose rest position is in the box
//     "move":      [{"box": [...], "velocity": [...], "from", "until"}]   kinematic nodes
//     "obstacles": [{"plane": {"point", "normal"}} | {"sphere": {"centre", "radius"}}
//                   | {"box": {"min", "max"}}, and optionally "friction": mu (Coulomb; 0 by default)],
//     "contact_stiffness": K
//     "self_collision": true | false | {"thickness": m, "stiffness": N/m, "friction": mu,
//                   "cushion": thicknesses}   contact of the material surface with itself and
//                   between pieces (Simulator::set_contact_surface); off by default (see the
//                   README for its cost); "cushion": how far the sides of a cut are pushed apart
//                   so that they can slide along it (SurfaceContactOptions::cushion, 0 by default)
//     "cuts":      [{"time", "space": "rest"|"world", and one of
//                    "triangles": PATH | "plane": {"centre", "normal", "size"}
//                    | "cylinder": {"centre", "axis", "radius", "length", "segments"}
//                    | "helix": {"centre", "axis", "inner_radius", "outer_radius", "pitch", "turns",
//                                "segments_per_turn"}
//                    | "cookie_cutter": {"profile": [[u,v],...], "origin", "u", "v", "depth"}
//                    | "blade": {"poses": [[ax,ay,az, bx,by,bz], ...]}}]   the strip a blade sweeps
//     "scalpels":  [{"from", "until", "space": "world"|"rest", "poses": [[ax,ay,az, bx,by,bz], ...]}]
//                  a blade moving through the poses evenly in time from `from` to `until`; each step
//                  the strip it swept since the last step is cut, world-space poses followed in the
//                  material (mapped to rest space through the current motion, as examples/scalpel.cpp)
//     "transforms":[{"time", "rotate": {"axis", "degrees", "centre"}} | {"time", "translate": [...]}]
//     "events":    [{"time", and one of "blade": [ax,ay,az, bx,by,bz] | "lift_blade": true
//                    | "grab": [x,y,z] (with "stiffness") | "move_hook": {"hook", "to": [x,y,z]}
//                    | "release": HOOK | "pin": {"at": [x,y,z], "radius"} | "unpin": {...}}]
//                  a live session's events, as it records them (see tetcut/session.hpp); world space
//     "springs":   [{"time", "cuts": [FIRST, LAST], "stiffness"}]   close those cut events' incisions
//     "output":    {"mesh": true, "surface": true,
//                   "picture": {"box": [...], "azimuth", "elevation", "zoom", "size": [w, h]}} }
//                   the camera of pictures (tetcut sim --png): the region to frame (default: the
//                   first frame grown by half), the view angles in degrees (default 35 and 25), the
//                   zoom (1 fits the region) and the size in pixels (default 640 x 480)
//
// Paths are relative to the scene file. Unknown keys are errors, so a typo is never ignored.
//
// A cloth scene (the 2D version: a planar triangle mesh cut by polylines, simulated in 3D by
// tetcut::sim::ClothSimulator) has "cloth" instead of "mesh" and "material":
//
//   { "cloth":    {"mesh": {"file": PATH}  (required: a triangle surface in a coordinate plane)
//                          | {"grid": {"cells": N, "size": S, "origin": [x,y,z], "plane": "xy"|"xz"|"yz"}},
//                  "material": {"density" (kg/m^2), "stretch_stiffness" (N/m), "poisson_ratio",
//                               "bending_stiffness" (N m), "mass_damping" (1/s)}}
//     "gravity", "time", "pin", "output":  as above ("time.dt" defaults to 1/60 s)
//     "solver":   {"tolerance", "max_newton_iterations"}   (ClothStepOptions)
//     "cuts":     [{"time", "until" (rest space only), "space": "rest"|"world" (default "world",
//                   as above), and one of
//                    "polyline": [[x,y,z], ...] (with "closed": true|false) | "polylines": PATH
//                    (OBJ l, VTK or VTP lines, or a point list, as tetcut cut2d reads)
//                    | "spiral": {"centre": [x,y,z], "outer_radius", "spacing", "inner_radius"
//                                 (default: spacing), "step" (default: spacing / 8), "from": [x,y,z]}
//                    | "blade": {"poses": [[ax,ay,az, bx,by,bz], ...]} | "triangles": PATH;
//                   and with a polyline in world space "through": [dx,dy,dz]}]
//   }
//
// The mesh starts where its rest positions put it in space (a file's own coordinates; a grid's
// (u, v) added to the origin's coordinates on the plane's two axes). Rest-space cuts are polylines
// in the rest plane (given in space: the plane's normal coordinate is dropped), or a spiral in it
// (tetcut::spiral, Figure 1's cut, led in from the point "from" when given). With "until": T they
// are cut progressively: each step, the stretch from where the cut had got to as far along the
// polylines' length as the time since "time" goes towards T (ending between two of their points
// where it falls there; the next stretch starts at that very point). World-space cuts are placed
// on the cloth as it is at that time (PlanarCutter::cut_deformed, exact): the strip a blade sweeps
// through its poses, triangles from a file, or a polyline pushed through the cloth along
// "through" (the strip between the polyline moved by -through and by +through). A world-space cut
// happens at one time: stretches placed on the moving cloth at different times would not meet in
// the material. Keys of the tet scenes that a cloth has not ("mesh", "material", "obstacles",
// "scalpels", "events", ...) are errors in a cloth scene.

#include <tetcut/blade.hpp>
#include <tetcut/cloth.hpp>
#include <tetcut/cutter.hpp>
#include <tetcut/embed.hpp>
#include <tetcut/sim.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tetcut {

struct SceneCut {
  double time = 0;
  bool world_space = true;
  std::string description;  ///< e.g. "cylinder" or the file name
  TriangleSurface triangles;
};

struct SceneScalpel {
  double from = 0, until = 0;
  bool world_space = true;
  std::vector<BladePose> poses;  ///< at least 2
  /// The pose at time t (from <= t <= until): linear between the poses, spread evenly in time.
  BladePose at(double t) const;
};

/// A live event (tetcut/session.hpp): what a user does to a running session, as it is recorded and
/// replayed. World space throughout.
struct SessionEvent {
  enum class Kind { kBlade, kLiftBlade, kGrab, kMoveHook, kRelease, kPin, kUnpin };
  Kind kind = Kind::kBlade;
  double time = 0;            ///< simulated seconds: applied before the step that starts then
  BladePose pose{Vec3::Zero(), Vec3::Zero()};  ///< kBlade: where the blade is
  Vec3 point = Vec3::Zero();  ///< kGrab: the point to hook; kMoveHook: the target; kPin, kUnpin: the centre
  double radius = 0;          ///< kPin, kUnpin: nodes within this distance
  int hook = -1;              ///< kMoveHook, kRelease: which (grabs number them 0, 1, ...)
  double stiffness = 0;       ///< kGrab: N/m; 0 for the default
};

struct SceneTransform {
  double time = 0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 centre = Vec3::Zero();
  Vec3 translation = Vec3::Zero();  ///< x -> rotation (x - centre) + centre + translation
};

struct SceneSprings {
  double time = 0;
  int first_cut = 0, last_cut = 0;  ///< indices into Scene::cuts (inclusive)
  double stiffness = 0;             ///< 0: 100 times the contact stiffness
};

struct SceneMove {
  Box box;
  Vec3 velocity = Vec3::Zero();
  double from = 0, until = std::numeric_limits<double>::infinity();
};

/// A timed cut of a cloth scene.
struct ClothCut {
  double time = 0;
  /// Rest space: cut progressively until then, the polylines' points reached evenly along their
  /// length; equal to `time`: at once.
  double until = 0;
  bool world_space = true;
  std::string description;  ///< e.g. "spiral" or the file name
  std::vector<Polyline> polylines;  ///< rest space: in the plane's (u, v) coordinates
  TriangleSurface triangles;        ///< world space
};

/// The 2D version in a scene: a planar mesh lying in a coordinate plane of space.
struct ClothScene {
  PlanarMesh mesh;
  RestPlane plane;  ///< where the rest mesh lies in space: the cloth's first positions
  sim::ClothMaterial material;
  sim::ClothStepOptions step;  ///< dt and gravity as the scene's
  std::vector<ClothCut> cuts;  ///< sorted by time
};

struct Scene {
  std::filesystem::path source;
  /// Set for a cloth scene; then the tet-mesh parts below (mesh, material, obstacles, ...) are
  /// unused, and `pins`, `duration`, `output_every` and the output settings apply to the cloth.
  std::optional<ClothScene> cloth;
  TetMesh mesh;
  std::optional<TriangleSurface> embed_surface;
  EmbedOptions embed_options;
  sim::Material material;
  sim::StepOptions step;
  double duration = 0;
  double output_every = 0;  ///< 0: every step
  std::vector<Box> pins;
  std::vector<SceneMove> moves;
  std::vector<sim::Obstacle> obstacles;
  double contact_stiffness = 0;  ///< 0: the simulator's default
  /// Contact of the material surface with itself and between pieces (Simulator::set_contact_surface).
  bool self_collision = false;
  sim::SurfaceContactOptions self_contact;  ///< zeros: the simulator's defaults
  std::vector<SceneCut> cuts;    ///< sorted by time
  std::vector<SceneScalpel> scalpels;
  std::vector<SceneTransform> transforms;
  std::vector<SceneSprings> springs;
  std::vector<SessionEvent> events;  ///< sorted by time (stable: same-time events keep their order)
  /// The file's JSON as loaded, for a recording to extend.
  std::string json;
  bool write_mesh = true, write_surface = true;
  /// Where pictures of the frames look (for a renderer; the scene does not draw).
  std::optional<Box> picture_box;
  double picture_azimuth = 35, picture_elevation = 25, picture_zoom = 1;
  /// VGA unless the scene says: small enough for a software renderer to draw every frame of a
  /// run in a fraction of its step time, large enough to see the cuts.
  static constexpr int kDefaultPictureWidth = 640, kDefaultPictureHeight = 480;
  int picture_width = kDefaultPictureWidth, picture_height = kDefaultPictureHeight;
};

/// Reads and validates a scene. Throws Error(kInvalidInput) naming the file and the key path
/// (e.g. "cuts[2].cylinder.radius") for a missing, unknown or ill-typed key.
Scene load_scene(const std::filesystem::path& path);
/// The same from the file's text; `path` names it in errors, and relative paths in it are
/// relative to its directory.
Scene parse_scene(std::string_view text, const std::filesystem::path& path);

/// What an output frame shows.
struct SceneFrame {
  TriangleSurface surface;  ///< the material surface (for a cloth: its cells), where it is now
  /// Lines over it: |E| x 2 rows of `line_points` (a cloth's triangle copies; empty for tets).
  Points line_points;
  Edges lines;
};

struct SceneRunOptions {
  int max_frames = -1;  ///< stop after this many output frames (after frame 0); -1: run to the end
  /// Called after each output frame with (frame, frames expected).
  std::function<void(int, int)> progress;
  /// Called with each output frame (e.g. to render it): its material surface where it is now,
  /// and for a cloth the edges of its triangle copies as lines (none for tets).
  std::function<void(int, const SceneFrame&)> frame_surface;
  /// Count, at each output frame, the pairs of surface triangles of different tet copies that
  /// intersect (count_surface_intersections): SceneSummary::intersecting_pairs. Not for cloth
  /// scenes (Error(kInvalidArgument)).
  bool check_intersections = false;
};

/// Wall time of a run by stage, in seconds (totals).
struct SceneStageSeconds {
  double cut = 0;      ///< cutting (for world-space cuts and scalpels: the current shape, the mapping)
  double surface = 0;  ///< the material surface after cuts, when contact, springs or frames need it
  double remesh = 0;   ///< the simulator after cuts, and its contact points and springs
  double step = 0;     ///< the simulation steps
  double output = 0;   ///< frames, series and pictures
};

struct SceneSummary {
  int frames = 0, steps = 0, cuts_applied = 0;
  Index tets = 0, nodes = 0, pieces = 0;
  /// A tet scene: the pieces' material volumes in rest space, largest first (CutMesh::piece_volumes).
  std::vector<double> piece_volumes;
  /// A cloth scene: its input triangles and triangle copies at the end (tets stays 0), the pieces'
  /// areas (largest first), and the copies world-space cuts left uncut as coplanar with a blade.
  bool cloth = false;
  Index triangles_in = 0, triangle_copies = 0;
  std::vector<double> piece_areas;
  Index skipped_coplanar = 0;
  double simulated_seconds = 0;
  double wall_seconds = 0, seconds_per_frame = 0;
  double mean_newton_iterations = 0, mean_cg_iterations = 0;
  int unconverged_steps = 0;
  /// The largest residual a step left (StepReport::residual; at most the tolerance when every
  /// step converged).
  double max_residual = 0;
  SceneStageSeconds stage_seconds;
  /// Per simulation step, the time of its cut, surface, remesh and step stages (output apart):
  /// median, 99th percentile and largest, in milliseconds.
  double step_ms_median = 0, step_ms_p99 = 0, step_ms_max = 0;
  /// The bounding box of the nodes at the end.
  Box final_box;
  /// Springs across incisions at the end, and the widest distance between the two ends of one
  /// when they were attached (how far the incision had opened) and at the end (how well it closed).
  Index springs = 0;
  double spring_gap_when_attached = 0, spring_gap_final = 0;
  /// With SceneRunOptions::check_intersections: per output frame, the intersecting pairs of
  /// surface triangles of different copies, and the largest count (empty and 0 otherwise).
  std::vector<Index> intersecting_pairs;
  Index max_intersecting_pairs = 0;
  /// With Scene::self_collision: the most surface pairs in contact at the end of a step, the
  /// Newton steps continuous collision detection shortened, and its seconds (in the step stage).
  Index max_contact_pairs = 0;
  Index contact_limited_steps = 0;
  double contact_seconds = 0;
};

/// Runs the scene, writing into `directory`: mesh_NNNN.vtu (the simulation mesh, piece and
/// material fraction per tet) and surface_NNNN.vtp (the material surface) per output frame,
/// mesh.pvd and surface.pvd (ParaView series with their times) and summary.json. A cloth scene
/// writes mesh_NNNN.vtp (its triangle copies) and surface_NNNN.vtp (the material, the cells of
/// the cut as triangles) where they are at each frame.
SceneSummary run_scene(const Scene& scene, const std::filesystem::path& directory, const SceneRunOptions& options = {});

/// The name of output frame `frame`'s file in a series: "<stem>_NNNN<extension>", four digits
/// (mesh_0000.vtu, surface_0000.vtp, and tetcut sim's frame_0000.png). The one place these names
/// are made.
std::string frame_file_name(std::string_view stem, int frame, std::string_view extension);
/// The same names as a printf pattern, "<stem>_%04d<extension>" (for ffmpeg: render::write_animation).
std::string frame_file_pattern(std::string_view stem, std::string_view extension);

}  // namespace tetcut
