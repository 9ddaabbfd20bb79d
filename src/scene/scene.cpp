// Scene files: validation with key paths in every message, and the runner: simulate, apply the
// timed cuts, transforms and springs, and write frames and ParaView series.

#include <tetcut/blade.hpp>
#include <tetcut/collision.hpp>
#include <tetcut/cutting_surfaces.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>
#include <tetcut/scene.hpp>
#include <tetcut/session.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <optional>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>

#include "scene/scene_internal.hpp"
#include "util/stopwatch.hpp"

namespace tetcut {
namespace {

// Output frames are numbered with four digits, so that file names sort in frame order up to 10,000
// frames (frame_file_name; more still work, sorted by ParaView's .pvd series).
constexpr const char* kFrameNumber = "%04d";

using Json = nlohmann::json;
using scene::percentile;
using scene::relative_to;
using scene::Value;

TetMesh load_mesh(const Value& mesh, const std::filesystem::path& source) {
  mesh.allow({"file", "grid", "bcc", "tet"});
  const int kinds = mesh.has("file") + mesh.has("grid") + mesh.has("bcc") + mesh.has("tet");
  if (kinds != 1) mesh.fail("give exactly one of 'file', 'grid', 'bcc' or 'tet'");
  if (const auto tet = mesh.get("tet")) {
    const std::vector<Value> corners = tet->array();
    if (corners.size() != 4) tet->fail("must list 4 corners");
    Points rest(4, 3);
    for (int k = 0; k < 4; ++k) rest.row(k) = corners[k].vec3().transpose();
    Tets tets(1, 4);
    tets << 0, 1, 2, 3;
    return TetMesh(std::move(rest), std::move(tets), tet->path());
  }
  if (const auto file = mesh.get("file")) return read_tet_mesh(relative_to(source, file->string()));
  if (const auto grid = mesh.get("grid")) {
    grid->allow({"box", "cells", "tets_per_cube"});
    const std::vector<Value> cells = grid->at("cells").array();
    if (cells.size() != 3) grid->at("cells").fail("must be an array of 3 integers");
    const int per_cube = grid->has("tets_per_cube") ? grid->at("tets_per_cube").integer(5) : 5;
    if (per_cube != 5 && per_cube != 6) grid->at("tets_per_cube").fail("must be 5 or 6");
    return make_grid(grid->at("box").box(), {cells[0].integer(1), cells[1].integer(1), cells[2].integer(1)}, per_cube);
  }
  const Value bcc = mesh.at("bcc");
  bcc.allow({"box", "spacing"});
  return make_bcc(bcc.at("box").box(), bcc.at("spacing").positive());
}

SceneCut load_cut(const Value& cut, const std::filesystem::path& source) {
  cut.allow({"time", "space", "triangles", "plane", "cylinder", "helix", "cookie_cutter", "blade"});
  SceneCut c;
  c.time = cut.at("time").non_negative();
  if (const auto space = cut.get("space")) c.world_space = space->choice({"rest", "world"}) == "world";
  const int kinds = cut.has("triangles") + cut.has("plane") + cut.has("cylinder") + cut.has("helix") +
                    cut.has("cookie_cutter") + cut.has("blade");
  if (kinds != 1) cut.fail("give exactly one of 'triangles', 'plane', 'cylinder', 'helix', 'cookie_cutter' or 'blade'");
  if (const auto file = cut.get("triangles")) {
    c.description = file->string();
    c.triangles = read_surface(relative_to(source, c.description));
  } else if (const auto plane = cut.get("plane")) {
    plane->allow({"centre", "normal", "size"});
    c.description = "plane";
    c.triangles = plane_square(plane->at("centre").vec3(), plane->at("normal").direction(), plane->at("size").positive());
  } else if (const auto cylinder = cut.get("cylinder")) {
    cylinder->allow({"centre", "axis", "radius", "length", "segments"});
    c.description = "cylinder";
    c.triangles = cylinder_side(cylinder->at("centre").vec3(), cylinder->at("axis").direction(), cylinder->at("radius").positive(),
                                cylinder->at("length").positive(),
                                cylinder->has("segments") ? cylinder->at("segments").integer(3) : 48);
  } else if (const auto helix = cut.get("helix")) {
    helix->allow({"centre", "axis", "inner_radius", "outer_radius", "pitch", "turns", "segments_per_turn"});
    c.description = "helix";
    const double inner = helix->at("inner_radius").non_negative(), outer = helix->at("outer_radius").positive();
    if (!(outer > inner)) helix->at("outer_radius").fail("must exceed inner_radius");
    c.triangles = helical_ribbon(helix->at("centre").vec3(), helix->at("axis").direction(), inner, outer,
                                 helix->at("pitch").number(), helix->at("turns").positive(),
                                 helix->has("segments_per_turn") ? helix->at("segments_per_turn").integer(3) : 48);
  } else if (const auto blade = cut.get("blade")) {
    blade->allow({"poses"});
    c.description = "blade";
    c.triangles = swept_blade(blade->at("poses").poses());
  } else {
    const Value cookie = cut.at("cookie_cutter");
    cookie.allow({"profile", "origin", "u", "v", "depth"});
    c.description = "cookie cutter";
    std::vector<Eigen::Vector2d> profile;
    for (const Value& p : cookie.at("profile").array()) {
      const auto uv = p.numbers(2);
      profile.emplace_back(uv[0], uv[1]);
    }
    if (profile.size() < 3) cookie.at("profile").fail("needs at least 3 points");
    const double depth = cookie.at("depth").number();
    if (depth == 0) cookie.at("depth").fail("must not be zero");
    c.triangles = cookie_cutter(profile, cookie.at("origin").vec3(), cookie.at("u").direction(), cookie.at("v").direction(), depth);
  }
  if (c.triangles.num_triangles() == 0) cut.fail("has no triangles");
  return c;
}

SessionEvent load_event(const Value& e) {
  e.allow({"time", "blade", "lift_blade", "grab", "stiffness", "move_hook", "release", "pin", "unpin"});
  SessionEvent event;
  event.time = e.at("time").non_negative();
  const int kinds = e.has("blade") + e.has("lift_blade") + e.has("grab") + e.has("move_hook") + e.has("release") + e.has("pin") + e.has("unpin");
  if (kinds != 1) e.fail("give exactly one of 'blade', 'lift_blade', 'grab', 'move_hook', 'release', 'pin' or 'unpin'");
  if (e.has("stiffness") && !e.has("grab")) e.at("stiffness").fail("goes with 'grab'");
  if (const auto blade = e.get("blade")) {
    event.kind = SessionEvent::Kind::kBlade;
    event.pose = blade->pose();
  } else if (const auto lift = e.get("lift_blade")) {
    if (!lift->boolean()) lift->fail("must be true");
    event.kind = SessionEvent::Kind::kLiftBlade;
  } else if (const auto grab = e.get("grab")) {
    event.kind = SessionEvent::Kind::kGrab;
    event.point = grab->vec3();
    if (const auto k = e.get("stiffness")) event.stiffness = k->positive();
  } else if (const auto move = e.get("move_hook")) {
    move->allow({"hook", "to"});
    event.kind = SessionEvent::Kind::kMoveHook;
    event.hook = move->at("hook").integer(0);
    event.point = move->at("to").vec3();
  } else if (const auto release = e.get("release")) {
    event.kind = SessionEvent::Kind::kRelease;
    event.hook = release->integer(0);
  } else {
    const bool pin = e.has("pin");
    const Value region = e.at(pin ? "pin" : "unpin");
    region.allow({"at", "radius"});
    event.kind = pin ? SessionEvent::Kind::kPin : SessionEvent::Kind::kUnpin;
    event.point = region.at("at").vec3();
    event.radius = region.at("radius").positive();
  }
  return event;
}

Json event_json(const SessionEvent& e) {
  Json j{{"time", e.time}};
  switch (e.kind) {
    case SessionEvent::Kind::kBlade:
      j["blade"] = {e.pose.a[0], e.pose.a[1], e.pose.a[2], e.pose.b[0], e.pose.b[1], e.pose.b[2]};
      break;
    case SessionEvent::Kind::kLiftBlade:
      j["lift_blade"] = true;
      break;
    case SessionEvent::Kind::kGrab:
      j["grab"] = {e.point[0], e.point[1], e.point[2]};
      if (e.stiffness > 0) j["stiffness"] = e.stiffness;
      break;
    case SessionEvent::Kind::kMoveHook:
      j["move_hook"] = {{"hook", e.hook}, {"to", {e.point[0], e.point[1], e.point[2]}}};
      break;
    case SessionEvent::Kind::kRelease:
      j["release"] = e.hook;
      break;
    case SessionEvent::Kind::kPin:
    case SessionEvent::Kind::kUnpin:
      j[e.kind == SessionEvent::Kind::kPin ? "pin" : "unpin"] = {{"at", {e.point[0], e.point[1], e.point[2]}}, {"radius", e.radius}};
      break;
  }
  return j;
}

}  // namespace

namespace scene {

// The largest picture side a scene may ask for: what `tetcut render --size` allows too.
constexpr int kMaxPictureSide = 16384;

std::vector<Box> load_pins(const Value& root) {
  std::vector<Box> pins;
  if (const auto list = root.get("pin")) {
    for (const Value& pin : list->array()) {
      pin.allow({"box"});
      pins.push_back(pin.at("box").box());
    }
  }
  return pins;
}

void load_output(const Value& root, Scene* scene) {
  if (const auto output = root.get("output")) {
    output->allow({"mesh", "surface", "picture"});
    if (const auto v = output->get("mesh")) scene->write_mesh = v->boolean();
    if (const auto v = output->get("surface")) scene->write_surface = v->boolean();
    if (const auto picture = output->get("picture")) {
      picture->allow({"box", "azimuth", "elevation", "zoom", "size"});
      if (const auto v = picture->get("box")) scene->picture_box = v->box();
      if (const auto v = picture->get("azimuth")) scene->picture_azimuth = v->number();
      if (const auto v = picture->get("elevation")) scene->picture_elevation = v->number();
      if (const auto v = picture->get("zoom")) scene->picture_zoom = v->positive();
      if (const auto v = picture->get("size")) {
        const std::vector<Value> size = v->array();
        if (size.size() != 2) v->fail("must be [width, height] in pixels");
        scene->picture_width = size[0].integer(1);
        scene->picture_height = size[1].integer(1);
        if (scene->picture_width > kMaxPictureSide || scene->picture_height > kMaxPictureSide) {
          v->fail("must be at most " + std::to_string(kMaxPictureSide) + " pixels a side");
        }
      }
    }
  }
}

namespace {
// The .pvd series of one kind of output, listing frames 0 .. times.size() - 1.
void write_frame_series(const std::filesystem::path& path, const std::string& prefix, const std::string& extension,
                        const std::vector<double>& times) {
  std::vector<SeriesEntry> entries;
  for (std::size_t f = 0; f < times.size(); ++f) entries.push_back({times[f], frame_file_name(prefix, static_cast<int>(f), extension)});
  write_series(path, entries);
}
}  // namespace

FrameSeries::FrameSeries(const Scene& scene, double dt, std::filesystem::path directory, const SceneRunOptions& options,
                         std::string mesh_extension)
    : scene_(scene), dt_(dt), directory_(std::move(directory)), options_(options), mesh_extension_(std::move(mesh_extension)) {
  steps_ = std::max(1, static_cast<int>(std::llround(scene.duration / dt)));
  every_ = scene.output_every > 0 ? std::max(1, static_cast<int>(std::llround(scene.output_every / dt))) : 1;
  expected_ = steps_ / every_;
}

void FrameSeries::written(double time, Clock::time_point start, SceneSummary* summary) {
  const int frame = next();
  times_.push_back(time);
  if (scene_.write_mesh) write_frame_series(directory_ / "mesh.pvd", "mesh", mesh_extension_, times_);
  if (scene_.write_surface) write_frame_series(directory_ / "surface.pvd", "surface", ".vtp", times_);
  summary->stage_seconds.output += seconds_since(start);
  if (options_.progress) options_.progress(frame, expected_);
}

void FrameSeries::finish(const std::vector<double>& step_ms, const Points& nodes, Clock::time_point start,
                         SceneSummary* summary) const {
  SceneSummary& s = *summary;
  s.frames = next();
  s.simulated_seconds = s.steps * dt_;
  s.wall_seconds = seconds_since(start);
  s.seconds_per_frame = s.frames > 1 ? s.wall_seconds / (s.frames - 1) : s.wall_seconds;
  s.step_ms_median = percentile(step_ms, 0.5);
  s.step_ms_p99 = percentile(step_ms, 0.99);
  s.step_ms_max = step_ms.empty() ? 0 : *std::max_element(step_ms.begin(), step_ms.end());
  s.final_box = {nodes.colwise().minCoeff().transpose(), nodes.colwise().maxCoeff().transpose()};
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5))];
}

Json ms_per_step_json(const SceneSummary& s) {
  const double per_step = s.steps > 0 ? 1e3 / s.steps : 0;
  const SceneStageSeconds& t = s.stage_seconds;
  return {{"cut", t.cut * per_step},
          {"surface", t.surface * per_step},
          {"remesh", t.remesh * per_step},
          {"step", t.step * per_step},
          {"total", (t.cut + t.surface + t.remesh + t.step) * per_step},
          {"median", s.step_ms_median},
          {"p99", s.step_ms_p99},
          {"max", s.step_ms_max}};
}

}  // namespace scene

Scene load_scene(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::kIo, "cannot open the scene file", path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return parse_scene(text.str(), path);
}

Scene parse_scene(std::string_view text, const std::filesystem::path& path) {
  Json json;
  try {
    json = Json::parse(text);
  } catch (const Json::parse_error& e) {
    // nlohmann reports "at line L, column C" in its message.
    throw Error(ErrorKind::kInvalidInput, std::string("not valid JSON: ") + e.what(), path.string());
  }
  const std::string file = path.string();
  const Value root(json, "", &file);
  root.allow({"mesh", "embed", "material", "gravity", "time", "solver", "pin", "move", "obstacles", "contact_stiffness",
              "self_collision", "cuts", "scalpels", "transforms", "springs", "events", "output", "cloth"});
  Scene scene;
  scene.source = path;
  scene.json = json.dump();
  if (root.has("cloth")) {
    scene::load_cloth(root, path, &scene);
    return scene;
  }

  const auto embed = root.get("embed");
  if (embed) {
    embed->allow({"surface", "archive", "keep", "spacing", "cells"});
    if (const auto archive = embed->get("archive")) {
      scene.embed_surface = read_surface(relative_to(path, archive->string()), embed->at("surface").string());
    } else {
      scene.embed_surface = read_surface(relative_to(path, embed->at("surface").string()));
    }
    if (const auto keep = embed->get("keep")) {
      scene.embed_options.keep = *keep_material_from_name(keep->choice({"inside", "largest"}));
    }
  }
  if (const auto mesh = root.get("mesh")) {
    if (embed && (embed->has("spacing") || embed->has("cells"))) embed->fail("'spacing' and 'cells' make a lattice: give them or 'mesh', not both");
    scene.mesh = load_mesh(*mesh, path);
  } else if (embed) {
    if (embed->has("spacing") && embed->has("cells")) embed->fail("give 'spacing' or 'cells', not both");
    const double spacing = embed->has("spacing") ? embed->at("spacing").positive()
                                                 : spacing_for_cubes(*scene.embed_surface, embed->has("cells") ? embed->at("cells").integer(1) : 16);
    scene.mesh = embedding_lattice(*scene.embed_surface, spacing);
  } else {
    root.fail("missing key 'mesh' (or 'embed' with a surface)");
  }

  if (const auto material = root.get("material")) {
    material->allow({"model", "youngs_modulus", "poissons_ratio", "density", "mass_damping", "stiffness_damping"});
    sim::Material& m = scene.material;
    if (const auto model = material->get("model")) {
      m.model = model->choice({"stable_neo_hookean", "corotated"}) == "corotated" ? sim::Model::kCorotated : sim::Model::kStableNeoHookean;
    }
    if (const auto v = material->get("youngs_modulus")) m.youngs_modulus = v->positive();
    if (const auto v = material->get("poissons_ratio")) {
      m.poissons_ratio = v->number();
      if (!sim::valid_poissons_ratio(m.poissons_ratio)) v->fail("must lie strictly between -1 and 0.5");
    }
    if (const auto v = material->get("density")) m.density = v->positive();
    if (const auto v = material->get("mass_damping")) m.mass_damping = v->non_negative();
    if (const auto v = material->get("stiffness_damping")) m.stiffness_damping = v->non_negative();
  }
  if (const auto gravity = root.get("gravity")) scene.step.gravity = gravity->vec3();
  const Value time = root.at("time");
  time.allow({"dt", "duration", "output_every"});
  if (const auto dt = time.get("dt")) scene.step.dt = dt->positive();
  scene.duration = time.at("duration").positive();
  if (const auto every = time.get("output_every")) scene.output_every = every->positive();
  if (const auto solver = root.get("solver")) {
    solver->allow({"mode", "tolerance", "max_newton_iterations", "max_cg_iterations", "reuse_hessian", "linear", "first_guess"});
    if (const auto mode = solver->get("mode"); mode && mode->choice({"converged", "real_time"}) == "real_time") {
      // The whole budget, keeping what the scene set before it (gravity; dt is real_time's own).
      const Vec3 gravity = scene.step.gravity;
      scene.step = sim::StepOptions::real_time(scene.step.dt);
      scene.step.gravity = gravity;
    }
    if (const auto v = solver->get("tolerance")) scene.step.tolerance = v->positive();
    if (const auto v = solver->get("max_newton_iterations")) scene.step.max_newton_iterations = v->integer(1);
    if (const auto v = solver->get("max_cg_iterations")) scene.step.max_cg_iterations = v->integer(1);
    if (const auto v = solver->get("reuse_hessian")) scene.step.reuse_hessian = v->integer(1);
    if (const auto v = solver->get("first_guess")) {
      scene.step.first_guess = v->choice({"prediction", "start"}) == "start" ? sim::FirstGuess::kStart : sim::FirstGuess::kPrediction;
    }
    if (const auto v = solver->get("linear")) {
      scene.step.solver = v->choice({"cg", "cholesky"}) == "cg" ? sim::LinearSolver::kConjugateGradient : sim::LinearSolver::kCholesky;
    }
  }
  scene.pins = scene::load_pins(root);
  if (const auto moves = root.get("move")) {
    for (const Value& move : moves->array()) {
      move.allow({"box", "velocity", "from", "until"});
      SceneMove m;
      m.box = move.at("box").box();
      m.velocity = move.at("velocity").vec3();
      if (const auto v = move.get("from")) m.from = v->non_negative();
      if (const auto v = move.get("until")) m.until = v->non_negative();
      scene.moves.push_back(m);
    }
  }
  if (const auto obstacles = root.get("obstacles")) {
    for (const Value& o : obstacles->array()) {
      o.allow({"plane", "sphere", "box", "friction"});
      if (o.has("plane") + o.has("sphere") + o.has("box") != 1) o.fail("give exactly one of 'plane', 'sphere' or 'box'");
      if (const auto plane = o.get("plane")) {
        plane->allow({"point", "normal"});
        scene.obstacles.push_back(sim::Obstacle::plane(plane->at("point").vec3(), plane->at("normal").direction()));
      } else if (const auto sphere = o.get("sphere")) {
        sphere->allow({"centre", "radius"});
        scene.obstacles.push_back(sim::Obstacle::sphere(sphere->at("centre").vec3(), sphere->at("radius").positive()));
      } else {
        const Value box = o.at("box");
        box.allow({"min", "max"});
        const Vec3 lo = box.at("min").vec3(), hi = box.at("max").vec3();
        if (!((lo.array() < hi.array()).all())) box.fail("'min' must be below 'max' on every axis");
        scene.obstacles.push_back(sim::Obstacle::box(lo, hi));
      }
      if (const auto mu = o.get("friction")) scene.obstacles.back().friction = mu->non_negative();
    }
  }
  if (const auto k = root.get("contact_stiffness")) scene.contact_stiffness = k->positive();
  if (const auto self = root.get("self_collision")) {
    // true | false | {"thickness": m, "stiffness": N/m, "friction": mu, "cushion": thicknesses}
    // (each may be left to its default; friction and cushion 0).
    if (self->is_object()) {
      self->allow({"thickness", "stiffness", "friction", "cushion"});
      scene.self_collision = true;
      if (const auto t = self->get("thickness")) scene.self_contact.thickness = t->positive();
      if (const auto k = self->get("stiffness")) scene.self_contact.stiffness = k->positive();
      if (const auto mu = self->get("friction")) scene.self_contact.friction = mu->non_negative();
      if (const auto cushion = self->get("cushion")) scene.self_contact.cushion = cushion->non_negative();
    } else {
      scene.self_collision = self->boolean();
    }
  }
  if (const auto cuts = root.get("cuts")) {
    for (const Value& cut : cuts->array()) scene.cuts.push_back(load_cut(cut, path));
    std::stable_sort(scene.cuts.begin(), scene.cuts.end(), [](const SceneCut& a, const SceneCut& b) { return a.time < b.time; });
  }
  if (const auto scalpels = root.get("scalpels")) {
    for (const Value& blade : scalpels->array()) {
      blade.allow({"from", "until", "space", "poses"});
      SceneScalpel scalpel;
      scalpel.from = blade.at("from").non_negative();
      scalpel.until = blade.at("until").non_negative();
      if (!(scalpel.until > scalpel.from)) blade.at("until").fail("must come after 'from'");
      if (const auto space = blade.get("space")) scalpel.world_space = space->choice({"rest", "world"}) == "world";
      scalpel.poses = blade.at("poses").poses();
      scene.scalpels.push_back(std::move(scalpel));
    }
  }
  if (const auto transforms = root.get("transforms")) {
    for (const Value& t : transforms->array()) {
      t.allow({"time", "rotate", "translate"});
      SceneTransform transform;
      transform.time = t.at("time").non_negative();
      if (t.has("rotate") == t.has("translate")) t.fail("give exactly one of 'rotate' or 'translate'");
      if (const auto rotate = t.get("rotate")) {
        rotate->allow({"axis", "degrees", "centre"});
        const double radians = rotate->at("degrees").number() * std::numbers::pi / 180;
        transform.rotation = Eigen::AngleAxisd(radians, rotate->at("axis").direction().normalized()).toRotationMatrix();
        if (const auto centre = rotate->get("centre")) transform.centre = centre->vec3();
      } else {
        transform.translation = t.at("translate").vec3();
      }
      scene.transforms.push_back(transform);
    }
    std::stable_sort(scene.transforms.begin(), scene.transforms.end(),
                     [](const SceneTransform& a, const SceneTransform& b) { return a.time < b.time; });
  }
  if (const auto springs = root.get("springs")) {
    for (const Value& s : springs->array()) {
      s.allow({"time", "cuts", "stiffness"});
      SceneSprings springs_event;
      springs_event.time = s.at("time").non_negative();
      const std::vector<Value> range = s.at("cuts").array();
      if (range.size() != 2) s.at("cuts").fail("must be [first, last], indices into 'cuts'");
      springs_event.first_cut = range[0].integer(0);
      springs_event.last_cut = range[1].integer(springs_event.first_cut);
      if (springs_event.last_cut >= static_cast<int>(scene.cuts.size())) s.at("cuts").fail("names a cut that does not exist");
      if (const auto k = s.get("stiffness")) springs_event.stiffness = k->positive();
      scene.springs.push_back(springs_event);
    }
  }
  if (const auto events = root.get("events")) {
    for (const Value& e : events->array()) scene.events.push_back(load_event(e));
    std::stable_sort(scene.events.begin(), scene.events.end(), [](const SessionEvent& a, const SessionEvent& b) { return a.time < b.time; });
  }
  scene::load_output(root, &scene);
  return scene;
}

BladePose SceneScalpel::at(double t) const {
  const double span = until - from;
  const double u = std::clamp(span > 0 ? (t - from) / span : 1.0, 0.0, 1.0) * static_cast<double>(poses.size() - 1);
  const std::size_t k = std::min(static_cast<std::size_t>(u), poses.size() - 2);
  const double f = u - static_cast<double>(k);
  return {(1 - f) * poses[k].a + f * poses[k + 1].a, (1 - f) * poses[k].b + f * poses[k + 1].b};
}

namespace {

// A run of a scene: a Session advanced step by step, its frames written as the scene asks.
class SceneRunner {
 public:
  SceneRunner(const Scene& scene, const std::filesystem::path& directory, const SceneRunOptions& options)
      : scene_(scene), directory_(directory), options_(options), session_(scene), frames_(scene, scene.step.dt, directory, options, ".vtu") {
    mesh_fields_.current_positions = true;
  }

  SceneSummary run() {
    const auto start_time = Clock::now();
    std::filesystem::create_directories(directory_);
    const double dt = scene_.step.dt;
    write_frame(0);
    std::vector<double> step_ms;
    double newton_total = 0, cg_total = 0;
    SceneStageSeconds& t = summary_.stage_seconds;
    for (int s = 0; s < frames_.steps(); ++s) {
      const SessionStep step = session_.advance();
      t.cut += step.seconds.cut;
      t.surface += step.seconds.surface;
      t.remesh += step.seconds.remesh;
      t.step += step.seconds.step;
      step_ms.push_back(1e3 * (step.seconds.cut + step.seconds.surface + step.seconds.remesh + step.seconds.step));
      newton_total += step.report.newton_iterations;
      cg_total += step.report.cg_iterations;
      summary_.max_residual = std::max(summary_.max_residual, step.report.residual);
      summary_.unconverged_steps += step.report.converged ? 0 : 1;
      summary_.max_contact_pairs = std::max(summary_.max_contact_pairs, step.report.contact_pairs);
      summary_.contact_limited_steps += step.report.contact_limited_steps;
      summary_.contact_seconds += step.report.contact_seconds;
      ++summary_.steps;
      if (frames_.frame_after(s)) {
        write_frame((s + 1) * dt);
        if (frames_.enough()) break;
      }
    }
    const CutResult& r = session_.result();
    summary_.cuts_applied = session_.cuts_applied();
    summary_.springs = session_.num_incision_springs();
    summary_.spring_gap_when_attached = session_.incision_gap_when_attached();
    summary_.spring_gap_final = session_.widest_incision_spring();
    summary_.tets = r.mesh.mesh.num_tets();
    summary_.nodes = r.mesh.mesh.num_nodes();
    summary_.pieces = r.mesh.num_pieces();
    summary_.piece_volumes = r.mesh.piece_volumes;
    summary_.mean_newton_iterations = summary_.steps > 0 ? newton_total / summary_.steps : 0;
    summary_.mean_cg_iterations = summary_.steps > 0 ? cg_total / summary_.steps : 0;
    frames_.finish(step_ms, session_.simulator().positions(), start_time, &summary_);
    write_summary();
    return summary_;
  }

 private:
  void write_frame(double time) {
    const auto start = Clock::now();
    const int frame = frames_.next();
    if (scene_.write_mesh) {
      CutResult& r = session_.result();
      if (fields_for_cut_ != session_.cuts_applied() || frame == 0) {
        // What a frame's mesh file carries per tet changes only with the mesh.
        CellField piece{"piece", {}, true}, fraction{"material_fraction", {}, false};
        piece.values.assign(r.mesh.tet_piece.begin(), r.mesh.tet_piece.end());
        fraction.values = r.mesh.material_fractions();
        for (double& f : fraction.values) f = std::min(f, 1.0);
        mesh_fields_.cell_fields = {std::move(piece), std::move(fraction)};
        fields_for_cut_ = session_.cuts_applied();
      }
      r.mesh.mesh.set_current(session_.simulator().positions());
      write_tet_mesh(directory_ / frame_file_name("mesh", frame, ".vtu"), r.mesh.mesh, mesh_fields_);
    }
    if (options_.check_intersections) {
      // A cut counts as opened where its sides are more than kSolverNoise of the mesh apart: less
      // is the solver's noise (a converged step settles positions to 1e-7 of the mesh's size). With
      // surface contact, the sides of a fresh cut pressed together may go into each other by up
      // to its allowance (a hundredth of an edge), and the cut has not opened there either.
      const Points& rest = session_.surface().surface.vertices;
      constexpr double kSolverNoise = 1e-6;  // of the mesh's diagonal
      const double noise = rest.rows() > 0 ? kSolverNoise * (rest.colwise().maxCoeff() - rest.colwise().minCoeff()).norm() : 0.0;
      // Pairs that contact leaves to its guards may have slid along a cut, pressed together by as
      // much as those allow (see count_surface_intersections).
      const sim::Simulator::SurfaceContactState contact = session_.simulator().surface_contact();
      const double opened = std::max(noise, contact.fresh_cut_allowance);
      const SurfaceIntersections found = count_surface_intersections(session_.surface(), session_.cutter().tet_nodes(),
                                                                     session_.surface_positions(), opened, contact.guarded_reach);
      summary_.intersecting_pairs.push_back(found.intersecting_pairs);
      summary_.max_intersecting_pairs = std::max(summary_.max_intersecting_pairs, found.intersecting_pairs);
    }
    if (scene_.write_surface || options_.frame_surface) {
      TriangleSurface moved = session_.surface().surface;
      moved.vertices = session_.surface_positions();
      if (scene_.write_surface) write_surface(directory_ / frame_file_name("surface", frame, ".vtp"), moved);
      if (options_.frame_surface) {
        SceneFrame shown;
        shown.surface = std::move(moved);
        options_.frame_surface(frame, shown);
      }
    }
    frames_.written(time, start, &summary_);
  }

  void write_summary() const {
    const SceneSummary& s = summary_;
    const double per_step = s.steps > 0 ? 1e3 / s.steps : 0;
    const SceneStageSeconds& t = s.stage_seconds;
    const Json json{{"scene", scene_.source.string()},
                    {"frames", s.frames},
                    {"steps", s.steps},
                    {"simulated_seconds", s.simulated_seconds},
                    {"cuts_applied", s.cuts_applied},
                    {"tets", s.tets},
                    {"nodes", s.nodes},
                    {"pieces", s.pieces},
                    {"piece_volumes", s.piece_volumes},
                    {"wall_seconds", s.wall_seconds},
                    {"seconds_per_frame", s.seconds_per_frame},
                    {"mean_newton_iterations", s.mean_newton_iterations},
                    {"mean_cg_iterations", s.mean_cg_iterations},
                    {"unconverged_steps", s.unconverged_steps},
                    {"max_residual", s.max_residual},
                    {"ms_per_step", scene::ms_per_step_json(s)},
                    {"output_seconds", t.output},
                    {"final_box", {s.final_box.min[0], s.final_box.min[1], s.final_box.min[2], s.final_box.max[0], s.final_box.max[1], s.final_box.max[2]}},
                    {"springs", s.springs},
                    {"spring_gap_when_attached", s.spring_gap_when_attached},
                    {"spring_gap_final", s.spring_gap_final}};
    Json out = json;
    if (scene_.self_collision) {
      out["self_collision"] = {{"max_contact_pairs", s.max_contact_pairs},
                               {"limited_newton_steps", s.contact_limited_steps},
                               {"ccd_ms_per_step", s.contact_seconds * per_step}};
    }
    if (options_.check_intersections) {
      out["intersecting_pairs"] = s.intersecting_pairs;
      out["max_intersecting_pairs"] = s.max_intersecting_pairs;
    }
    write_text_file(directory_ / "summary.json", out.dump(2) + "\n");
  }

  const Scene& scene_;
  std::filesystem::path directory_;
  const SceneRunOptions& options_;
  Session session_;
  TetMeshWriteOptions mesh_fields_;
  int fields_for_cut_ = -1;
  scene::FrameSeries frames_;
  SceneSummary summary_;
};

}  // namespace

std::string frame_file_name(std::string_view stem, int frame, std::string_view extension) {
  char digits[16];
  std::snprintf(digits, sizeof digits, kFrameNumber, frame);
  return std::string(stem) + "_" + digits + std::string(extension);
}

std::string frame_file_pattern(std::string_view stem, std::string_view extension) {
  return std::string(stem) + "_" + kFrameNumber + std::string(extension);
}

SceneSummary run_scene(const Scene& scene, const std::filesystem::path& directory, const SceneRunOptions& options) {
  if (scene.cloth) return scene::run_cloth_scene(scene, directory, options);
  return SceneRunner(scene, directory, options).run();
}

std::string recording_json(const Scene& scene, const Session& session) {
  Json json = Json::parse(scene.json);
  // Paths in the scene are relative to it: absolute, so the recording replays from anywhere.
  const auto absolute = [&](Json& value) {
    if (value.is_string()) value = std::filesystem::absolute(relative_to(scene.source, value.get<std::string>())).string();
  };
  if (json.contains("mesh") && json["mesh"].contains("file")) absolute(json["mesh"]["file"]);
  if (json.contains("embed")) {
    // An archive's member is a path inside it: the archive is what lies on disk.
    absolute(json["embed"].contains("archive") ? json["embed"]["archive"] : json["embed"]["surface"]);
  }
  if (json.contains("cuts")) {
    for (Json& cut : json["cuts"]) {
      if (cut.contains("triangles")) absolute(cut["triangles"]);
    }
  }
  Json events = Json::array();
  for (const SessionEvent& e : session.recording()) events.push_back(event_json(e));
  json["events"] = std::move(events);
  json["time"]["duration"] = session.time();
  return json.dump(2) + "\n";
}

void write_recording(const std::filesystem::path& path, const Scene& scene, const Session& session) {
  write_text_file(path, recording_json(scene, session));
}

}  // namespace tetcut
