// Scene files: validation with key paths in every message, and the runner: simulate, apply the
// timed cuts, transforms and springs, and write frames and ParaView series.

#include <tetcut/blade.hpp>
#include <tetcut/cutting_surfaces.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>
#include <tetcut/scene.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>

namespace tetcut {
namespace {

using Json = nlohmann::json;

// A JSON value and where it is in the file, for messages like "cuts[2].cylinder.radius: ...".
class Value {
 public:
  Value(const Json& json, std::string path, const std::string* file) : json_(&json), path_(std::move(path)), file_(file) {}

  [[noreturn]] void fail(const std::string& why) const {
    throw Error(ErrorKind::kInvalidInput, (path_.empty() ? std::string("the scene") : path_) + ": " + why, *file_);
  }
  const std::string& path() const { return path_; }

  // Objects: the keys allowed; any other is an error (a typo must not be ignored).
  void allow(std::initializer_list<const char*> keys) const {
    if (!json_->is_object()) fail("must be an object");
    for (const auto& [key, value] : json_->items()) {
      if (std::find_if(keys.begin(), keys.end(), [&](const char* k) { return key == k; }) == keys.end()) {
        std::string known;
        for (const char* k : keys) known += std::string(known.empty() ? "" : ", ") + k;
        fail("unknown key '" + key + "' (known: " + known + ")");
      }
    }
  }
  bool has(const char* key) const { return json_->is_object() && json_->contains(key); }
  Value at(const char* key) const {
    if (!has(key)) fail(std::string("missing key '") + key + "'");
    return Value((*json_)[key], join(key), file_);
  }
  std::optional<Value> get(const char* key) const {
    if (!has(key)) return std::nullopt;
    return Value((*json_)[key], join(key), file_);
  }
  std::vector<Value> array() const {
    if (!json_->is_array()) fail("must be an array");
    std::vector<Value> items;
    for (std::size_t i = 0; i < json_->size(); ++i) items.emplace_back((*json_)[i], path_ + "[" + std::to_string(i) + "]", file_);
    return items;
  }

  double number() const {
    if (!json_->is_number()) fail("must be a number");
    const double x = json_->get<double>();
    if (!std::isfinite(x)) fail("must be finite");
    return x;
  }
  double positive() const {
    const double x = number();
    if (!(x > 0)) fail("must be positive");
    return x;
  }
  double non_negative() const {
    const double x = number();
    if (x < 0) fail("must not be negative");
    return x;
  }
  int integer(int lowest) const {
    if (!json_->is_number_integer()) fail("must be an integer");
    const auto x = json_->get<std::int64_t>();
    if (x < lowest || x > 1'000'000'000) fail("must be an integer from " + std::to_string(lowest));
    return static_cast<int>(x);
  }
  bool boolean() const {
    if (!json_->is_boolean()) fail("must be true or false");
    return json_->get<bool>();
  }
  std::string string() const {
    if (!json_->is_string()) fail("must be a string");
    return json_->get<std::string>();
  }
  std::string choice(std::initializer_list<const char*> options) const {
    const std::string s = string();
    std::string known;
    for (const char* o : options) {
      if (s == o) return s;
      known += std::string(known.empty() ? "" : ", ") + o;
    }
    fail("'" + s + "' is not one of " + known);
  }
  std::vector<double> numbers(std::size_t count) const {
    if (!json_->is_array() || json_->size() != count) fail("must be an array of " + std::to_string(count) + " numbers");
    std::vector<double> out;
    for (const Value& v : array()) out.push_back(v.number());
    return out;
  }
  Vec3 vec3() const {
    const auto v = numbers(3);
    return Vec3(v[0], v[1], v[2]);
  }
  Vec3 direction() const {
    const Vec3 v = vec3();
    if (!(v.norm() > 0)) fail("must not be the zero vector");
    return v;
  }
  Box box() const {
    const auto v = numbers(6);
    Box b{Vec3(v[0], v[1], v[2]), Vec3(v[3], v[4], v[5])};
    if (!((b.min.array() <= b.max.array()).all())) fail("its minimum corner must not exceed its maximum corner");
    return b;
  }

 private:
  std::string join(const char* key) const { return path_.empty() ? key : path_ + "." + key; }
  const Json* json_;
  std::string path_;
  const std::string* file_;
};

std::filesystem::path relative_to(const std::filesystem::path& scene, const std::string& path) {
  const std::filesystem::path p(path);
  return p.is_absolute() ? p : scene.parent_path() / p;
}

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
    std::vector<BladePose> poses;
    for (const Value& pose : blade->at("poses").array()) {
      const auto ab = pose.numbers(6);
      poses.push_back({Vec3(ab[0], ab[1], ab[2]), Vec3(ab[3], ab[4], ab[5])});
    }
    if (poses.size() < 2) blade->at("poses").fail("needs at least 2 poses");
    c.triangles = swept_blade(poses);
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

}  // namespace

Scene load_scene(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw Error(ErrorKind::kIo, "cannot open the scene file", path.string());
  Json json;
  try {
    json = Json::parse(in);
  } catch (const Json::parse_error& e) {
    // nlohmann reports "at line L, column C" in its message.
    throw Error(ErrorKind::kInvalidInput, std::string("not valid JSON: ") + e.what(), path.string());
  }
  const std::string file = path.string();
  const Value root(json, "", &file);
  root.allow({"mesh", "embed", "material", "gravity", "time", "solver", "pin", "move", "obstacles", "contact_stiffness",
              "cuts", "transforms", "springs", "output"});
  Scene scene;
  scene.source = path;

  const auto embed = root.get("embed");
  if (embed) {
    embed->allow({"surface", "keep", "spacing", "cells"});
    scene.embed_surface = read_surface(relative_to(path, embed->at("surface").string()));
    if (const auto keep = embed->get("keep")) {
      scene.embed_options.keep = keep->choice({"inside", "largest"}) == "inside" ? KeepMaterial::kInside : KeepMaterial::kLargest;
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
      if (!(m.poissons_ratio > -1 && m.poissons_ratio < 0.5)) v->fail("must lie strictly between -1 and 0.5");
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
    solver->allow({"tolerance", "max_newton_iterations", "linear"});
    if (const auto v = solver->get("tolerance")) scene.step.tolerance = v->positive();
    if (const auto v = solver->get("max_newton_iterations")) scene.step.max_newton_iterations = v->integer(1);
    if (const auto v = solver->get("linear")) {
      scene.step.solver = v->choice({"cg", "cholesky"}) == "cg" ? sim::LinearSolver::kConjugateGradient : sim::LinearSolver::kCholesky;
    }
  }
  if (const auto pins = root.get("pin")) {
    for (const Value& pin : pins->array()) {
      pin.allow({"box"});
      scene.pins.push_back(pin.at("box").box());
    }
  }
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
      o.allow({"plane", "sphere", "box"});
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
    }
  }
  if (const auto k = root.get("contact_stiffness")) scene.contact_stiffness = k->positive();
  if (const auto cuts = root.get("cuts")) {
    for (const Value& cut : cuts->array()) scene.cuts.push_back(load_cut(cut, path));
    std::stable_sort(scene.cuts.begin(), scene.cuts.end(), [](const SceneCut& a, const SceneCut& b) { return a.time < b.time; });
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
  if (const auto output = root.get("output")) {
    output->allow({"mesh", "surface", "picture"});
    if (const auto v = output->get("mesh")) scene.write_mesh = v->boolean();
    if (const auto v = output->get("surface")) scene.write_surface = v->boolean();
    if (const auto picture = output->get("picture")) {
      picture->allow({"box", "azimuth", "elevation"});
      if (const auto v = picture->get("box")) scene.picture_box = v->box();
      if (const auto v = picture->get("azimuth")) scene.picture_azimuth = v->number();
      if (const auto v = picture->get("elevation")) scene.picture_elevation = v->number();
    }
  }
  return scene;
}

namespace {

// The simulator's volume fractions: the cut mesh's, at most 1 (a rounding above it is not material).
std::vector<double> material_fractions(const CutMesh& mesh) {
  std::vector<double> fraction = mesh.material_fractions();
  for (double& f : fraction) f = std::min(f, 1.0);
  return fraction;
}

bool in_box(const Box& box, const Vec3& x) { return (x.array() >= box.min.array()).all() && (x.array() <= box.max.array()).all(); }

// The .pvd series of one kind of output, listing frames 0 .. times.size() - 1.
void write_frame_series(const std::filesystem::path& path, const std::string& prefix, const std::string& extension,
                        const std::vector<double>& times) {
  std::vector<SeriesEntry> entries;
  for (std::size_t f = 0; f < times.size(); ++f) {
    char name[64];
    std::snprintf(name, sizeof name, "%s_%04zu%s", prefix.c_str(), f, extension.c_str());
    entries.push_back({times[f], name});
  }
  write_series(path, entries);
}

}  // namespace

SceneSummary run_scene(const Scene& scene, const std::filesystem::path& directory, const SceneRunOptions& options) {
  const auto start_time = std::chrono::steady_clock::now();
  std::filesystem::create_directories(directory);
  Cutter cutter = scene.embed_surface ? embed(scene.mesh, *scene.embed_surface, scene.embed_options) : Cutter(scene.mesh);
  CutResult result = cutter.result();
  std::vector<double> fractions = material_fractions(result.mesh);
  sim::Simulator sim(result.mesh.mesh, scene.material, fractions);
  if (scene.contact_stiffness > 0) sim.set_contact_stiffness(scene.contact_stiffness);
  for (const sim::Obstacle& o : scene.obstacles) sim.add_obstacle(o);

  const auto rest_of = [&](Index node) { return Vec3(result.mesh.mesh.rest().row(node).transpose()); };
  std::vector<std::uint8_t> pinned;
  const auto apply_pins = [&] {
    pinned.assign(static_cast<std::size_t>(sim.num_nodes()), 0);
    for (Index n = 0; n < sim.num_nodes(); ++n) {
      for (const Box& box : scene.pins) {
        if (in_box(box, rest_of(n))) {
          pinned[n] = 1;
          sim.pin(n);
        }
      }
    }
  };
  apply_pins();
  // Cut id ranges of the applied cut events, for springs.
  std::vector<std::pair<std::int64_t, std::int64_t>> cut_ids(scene.cuts.size(), {-1, -1});
  std::vector<const SceneSprings*> active_springs;
  std::vector<std::pair<sim::EmbeddedPoint, sim::EmbeddedPoint>> spring_ends;
  const auto refresh_constraints = [&] {
    if (!scene.obstacles.empty()) {
      std::vector<sim::EmbeddedPoint> points;
      for (Index v = 0; v < result.surface.surface.num_vertices(); ++v) {
        points.push_back({result.surface.vertex_tet[v], result.surface.vertex_weights.row(v).transpose()});
      }
      sim.set_contact_points(std::move(points));
    }
    sim.clear_springs();
    spring_ends.clear();
    for (const SceneSprings* s : active_springs) {
      const double k = s->stiffness > 0 ? s->stiffness : 100 * sim.contact_stiffness();
      for (int c = s->first_cut; c <= s->last_cut; ++c) {
        if (cut_ids[c].first < 0) continue;  // not applied yet
        for (const auto& [p, q] : sim::incision_pairs(result.surface, cut_ids[c].first, cut_ids[c].second)) {
          sim.add_spring(p, q, k);
          spring_ends.emplace_back(p, q);
        }
      }
    }
  };
  const auto widest_spring = [&] {
    double gap = 0;
    for (const auto& [p, q] : spring_ends) gap = std::max(gap, (sim.position(p) - sim.position(q)).norm());
    return gap;
  };
  refresh_constraints();

  const double dt = scene.step.dt;
  const int steps = std::max(1, static_cast<int>(std::llround(scene.duration / dt)));
  const int every = scene.output_every > 0 ? std::max(1, static_cast<int>(std::llround(scene.output_every / dt))) : 1;
  const int expected_frames = steps / every;
  std::vector<double> times;
  SceneSummary summary;
  // What a frame's mesh file carries per tet changes only with the mesh: set after each cut.
  TetMeshWriteOptions mesh_fields;
  mesh_fields.current_positions = true;
  const auto refresh_mesh_fields = [&] {
    CellField piece{"piece", {}, true}, fraction{"material_fraction", {}, false};
    piece.values.assign(result.mesh.tet_piece.begin(), result.mesh.tet_piece.end());
    fraction.values = fractions;
    mesh_fields.cell_fields = {std::move(piece), std::move(fraction)};
  };
  refresh_mesh_fields();
  const auto write_frame = [&](double t) {
    const int frame = static_cast<int>(times.size());
    char name[64];
    if (scene.write_mesh) {
      result.mesh.mesh.set_current(sim.positions());
      std::snprintf(name, sizeof name, "mesh_%04d.vtu", frame);
      write_tet_mesh(directory / name, result.mesh.mesh, mesh_fields);
    }
    if (scene.write_surface || options.frame_surface) {
      TriangleSurface surface = result.surface.surface;
      surface.vertices = result.surface.positions(result.mesh, sim.positions());
      std::snprintf(name, sizeof name, "surface_%04d.vtp", frame);
      if (scene.write_surface) write_surface(directory / name, surface);
      if (options.frame_surface) options.frame_surface(frame, surface);
    }
    times.push_back(t);
    if (scene.write_mesh) write_frame_series(directory / "mesh.pvd", "mesh", ".vtu", times);
    if (scene.write_surface) write_frame_series(directory / "surface.pvd", "surface", ".vtp", times);
    if (options.progress) options.progress(frame, expected_frames);
  };
  write_frame(0);

  std::size_t next_cut = 0, next_transform = 0, next_springs = 0;
  double newton_total = 0;
  for (int s = 0; s < steps; ++s) {
    const double t = s * dt;
    const double now = t + dt / 2;  // events due by the middle of this step happen before it
    while (next_transform < scene.transforms.size() && scene.transforms[next_transform].time <= now) {
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
    }
    bool remeshed = false;
    while (next_cut < scene.cuts.size() && scene.cuts[next_cut].time <= now) {
      const SceneCut& cut = scene.cuts[next_cut];
      const std::int64_t first_id = cutter.num_cut_triangles();
      CutBatchReport batch;
      if (cut.world_space) {
        cutter.set_current(sim.positions());
        batch = cutter.cut_deformed(cut.triangles);
      } else {
        batch = cutter.cut(cut.triangles);
      }
      cut_ids[next_cut] = {first_id, cutter.num_cut_triangles()};
      ++next_cut;
      ++summary.cuts_applied;
      result = cutter.result();
      fractions = material_fractions(result.mesh);
      refresh_mesh_fields();
      sim.remesh(result.mesh.mesh, fractions, batch.first_new_node, batch.new_node_source);
      pinned.resize(static_cast<std::size_t>(sim.num_nodes()), 0);
      for (Index i = 0; i < static_cast<Index>(batch.new_node_source.size()); ++i) {
        pinned[batch.first_new_node + i] = pinned[batch.new_node_source[i]];
      }
      remeshed = true;
    }
    bool springs_added = false;
    while (next_springs < scene.springs.size() && scene.springs[next_springs].time <= now) {
      active_springs.push_back(&scene.springs[next_springs++]);
      remeshed = springs_added = true;
    }
    if (remeshed) refresh_constraints();
    if (springs_added) summary.spring_gap_when_attached = std::max(summary.spring_gap_when_attached, widest_spring());
    // Kinematic nodes: those in an active move box go with its velocity; others are let go.
    for (Index n = 0; n < sim.num_nodes() && !scene.moves.empty(); ++n) {
      if (pinned[n]) continue;
      bool moved = false;
      for (const SceneMove& m : scene.moves) {
        if (t + 1e-12 >= m.from && t < m.until && in_box(m.box, rest_of(n))) {
          sim.move_to(n, sim.positions().row(n).transpose() + dt * m.velocity);
          moved = true;
          break;
        }
      }
      if (!moved) sim.release(n);
    }
    const sim::StepReport report = sim.step(scene.step);
    newton_total += report.newton_iterations;
    summary.unconverged_steps += report.converged ? 0 : 1;
    ++summary.steps;
    if ((s + 1) % every == 0) {
      write_frame((s + 1) * dt);
      if (options.max_frames >= 0 && static_cast<int>(times.size()) - 1 >= options.max_frames) break;
    }
  }
  summary.frames = static_cast<int>(times.size());
  summary.springs = static_cast<Index>(spring_ends.size());
  summary.spring_gap_final = widest_spring();
  summary.tets = result.mesh.mesh.num_tets();
  summary.nodes = result.mesh.mesh.num_nodes();
  summary.pieces = result.mesh.num_pieces();
  summary.simulated_seconds = summary.steps * dt;
  summary.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  summary.seconds_per_frame = summary.frames > 1 ? summary.wall_seconds / (summary.frames - 1) : summary.wall_seconds;
  summary.mean_newton_iterations = summary.steps > 0 ? newton_total / summary.steps : 0;
  const Json json{{"scene", scene.source.string()},
                  {"frames", summary.frames},
                  {"steps", summary.steps},
                  {"simulated_seconds", summary.simulated_seconds},
                  {"cuts_applied", summary.cuts_applied},
                  {"tets", summary.tets},
                  {"nodes", summary.nodes},
                  {"pieces", summary.pieces},
                  {"wall_seconds", summary.wall_seconds},
                  {"seconds_per_frame", summary.seconds_per_frame},
                  {"mean_newton_iterations", summary.mean_newton_iterations},
                  {"unconverged_steps", summary.unconverged_steps},
                  {"springs", summary.springs},
                  {"spring_gap_when_attached", summary.spring_gap_when_attached},
                  {"spring_gap_final", summary.spring_gap_final}};
  write_text_file(directory / "summary.json", json.dump(2) + "\n");
  return summary;
}

}  // namespace tetcut
