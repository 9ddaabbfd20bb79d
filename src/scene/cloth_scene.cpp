// Cloth scenes: the 2D version in a scene file (a planar mesh, its material, pins, timed polyline
// cuts in rest space and blades on the deformed cloth), and the runner behind `tetcut sim` for
// them: the planar cutter and the cloth simulator, frames as surfaces and ParaView series.

#include <tetcut/blade.hpp>
#include <tetcut/cloth.hpp>
#include <tetcut/cutting_surfaces.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>
#include <tetcut/planar_cutter.hpp>
#include <tetcut/scene.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "scene/scene_internal.hpp"
#include "util/stopwatch.hpp"

namespace tetcut::scene {
namespace {

PlanarMesh load_cloth_mesh(const Value& mesh, const std::filesystem::path& source, RestPlane* plane) {
  mesh.allow({"file", "grid"});
  if (mesh.has("file") == mesh.has("grid")) mesh.fail("give exactly one of 'file' or 'grid'");
  if (const auto file = mesh.get("file")) {
    const std::filesystem::path path = relative_to(source, file->string());
    const TriangleSurface surface = read_surface(path);
    try {
      PlanarMesh planar = planar_mesh(surface, plane);
      const PlanarCutter check(planar);  // counter-clockwise, edges of at most two triangles
      return planar;
    } catch (const Error& e) {
      if (e.kind() == ErrorKind::kInternal) throw;  // a bug, not a fault of the scene
      file->fail(path.string() + ": " + e.message());
    }
  }
  const Value grid = mesh.at("grid");
  grid.allow({"cells", "size", "origin", "plane"});
  const int cells = grid.at("cells").integer(1);
  const double size = grid.at("size").positive();
  const Vec3 origin = grid.has("origin") ? grid.at("origin").vec3() : Vec3::Zero();
  const std::string axes = grid.has("plane") ? grid.at("plane").choice({"xy", "xz", "yz"}) : "xy";
  // As planar_mesh() names a coordinate plane: (u, v) in axis order, the normal the third axis.
  plane->u = axes == "yz" ? 1 : 0;
  plane->v = axes == "xy" ? 1 : 2;
  plane->normal = 3 - plane->u - plane->v;
  plane->offset = origin[plane->normal];
  PlanarMesh planar = make_planar_grid(cells, size);
  planar.rest.col(0).array() += origin[plane->u];
  planar.rest.col(1).array() += origin[plane->v];
  return planar;
}

sim::ClothMaterial load_cloth_material(const Value& material) {
  material.allow({"density", "stretch_stiffness", "poisson_ratio", "bending_stiffness", "mass_damping"});
  sim::ClothMaterial m;
  if (const auto v = material.get("density")) m.density = v->positive();
  if (const auto v = material.get("stretch_stiffness")) m.stretch_stiffness = v->positive();
  if (const auto v = material.get("poisson_ratio")) {
    m.poisson_ratio = v->number();
    if (!sim::valid_poissons_ratio(m.poisson_ratio)) v->fail("must lie strictly between -1 and 0.5");
  }
  if (const auto v = material.get("bending_stiffness")) m.bending_stiffness = v->non_negative();
  if (const auto v = material.get("mass_damping")) m.mass_damping = v->non_negative();
  return m;
}

// A polyline given in space, as [[x, y, z], ...].
Points points_of(const Value& list) {
  const std::vector<Value> items = list.array();
  if (items.size() < 2) list.fail("needs at least 2 points");
  Points p(static_cast<Index>(items.size()), 3);
  for (std::size_t i = 0; i < items.size(); ++i) p.row(static_cast<Index>(i)) = items[i].vec3().transpose();
  return p;
}

// The polylines of a cut, in space (a closed one repeats its first point at the end).
std::vector<Points> polylines_of(const Value& cut, const std::filesystem::path& source, std::string* description) {
  if (const auto list = cut.get("polyline")) {
    *description = "polyline";
    Points p = points_of(*list);
    if (cut.has("closed") && cut.at("closed").boolean()) {
      p.conservativeResize(p.rows() + 1, 3);
      p.row(p.rows() - 1) = p.row(0);
    }
    return {p};
  }
  const Value file = cut.at("polylines");
  *description = file.string();
  return read_polylines(relative_to(source, *description));
}

ClothCut load_cloth_cut(const Value& cut, const std::filesystem::path& source, const RestPlane& plane) {
  cut.allow({"time", "until", "space", "polyline", "closed", "polylines", "spiral", "blade", "triangles", "through"});
  ClothCut c;
  c.time = cut.at("time").non_negative();
  c.until = c.time;
  if (const auto space = cut.get("space")) c.world_space = space->choice({"rest", "world"}) == "world";
  const int kinds = cut.has("polyline") + cut.has("polylines") + cut.has("spiral") + cut.has("blade") + cut.has("triangles");
  if (kinds != 1) cut.fail("give exactly one of 'polyline', 'polylines', 'spiral', 'blade' or 'triangles'");
  if (cut.has("closed") && !cut.has("polyline")) cut.at("closed").fail("goes with 'polyline'");
  const bool polyline = cut.has("polyline") || cut.has("polylines");
  if (c.world_space) {
    if (cut.has("until")) {
      cut.at("until").fail("a world-space cut is placed at one time (stretches placed on the moving cloth at different "
                           "times would not meet in the material); cut a path progressively in rest space");
    }
    if (cut.has("spiral")) cut.at("spiral").fail("a spiral is a path in the cloth's rest plane: give \"space\": \"rest\"");
    if (cut.has("through") != polyline) {
      if (polyline) cut.fail("a polyline placed in world space needs 'through': the vector it is pushed through the cloth along");
      cut.at("through").fail("goes with a polyline placed in world space");
    }
    if (const auto blade = cut.get("blade")) {
      blade->allow({"poses"});
      c.description = "blade";
      c.triangles = swept_blade(blade->at("poses").poses());
    } else if (const auto file = cut.get("triangles")) {
      c.description = file->string();
      c.triangles = read_surface(relative_to(source, c.description));
    } else {
      // The strip the polyline sweeps pushed from -through to +through: a blade through the
      // polyline's points.
      const Vec3 through = cut.at("through").direction();
      for (const Points& line : polylines_of(cut, source, &c.description)) {
        std::vector<BladePose> poses;
        for (Index i = 0; i < line.rows(); ++i) {
          const Vec3 p = line.row(i).transpose();
          poses.push_back({p - through, p + through});
        }
        const TriangleSurface strip = swept_blade(poses);
        const Index base = c.triangles.num_vertices();
        c.triangles.vertices.conservativeResize(base + strip.num_vertices(), 3);
        c.triangles.vertices.bottomRows(strip.num_vertices()) = strip.vertices;
        const Index first = c.triangles.num_triangles();
        c.triangles.triangles.conservativeResize(first + strip.num_triangles(), 3);
        c.triangles.triangles.bottomRows(strip.num_triangles()) = strip.triangles.array() + base;
      }
    }
    if (c.triangles.num_triangles() == 0) cut.fail("has no triangles");
    return c;
  }
  if (cut.has("through")) cut.at("through").fail("goes with a polyline placed in world space");
  if (cut.has("blade") || cut.has("triangles")) cut.fail("a blade or triangles are placed in world space: give \"space\": \"world\"");
  if (const auto until = cut.get("until")) {
    c.until = until->non_negative();
    if (!(c.until > c.time)) until->fail("must come after 'time'");
  }
  if (const auto spiral_cut = cut.get("spiral")) {
    spiral_cut->allow({"centre", "outer_radius", "inner_radius", "spacing", "step", "from"});
    c.description = "spiral";
    const double spacing = spiral_cut->at("spacing").positive();
    const double inner = spiral_cut->has("inner_radius") ? spiral_cut->at("inner_radius").non_negative() : spacing;
    const double step = spiral_cut->has("step") ? spiral_cut->at("step").positive() : spacing / 8;
    const Points centre = spiral_cut->at("centre").vec3().transpose();
    Points2 path;
    try {
      path = spiral(to_plane(centre, plane).row(0).transpose(), spiral_cut->at("outer_radius").positive(), inner, spacing, step);
    } catch (const Error& e) {
      if (e.kind() == ErrorKind::kInternal) throw;  // a bug, not a fault of the scene
      spiral_cut->fail(e.message());
    }
    if (const auto from = spiral_cut->get("from")) {
      Points2 led(path.rows() + 1, 2);
      led.row(0) = to_plane(from->vec3().transpose(), plane);
      led.bottomRows(path.rows()) = path;
      path = std::move(led);
    }
    if (path.rows() < 2) spiral_cut->fail("makes fewer than 2 points: give a larger outer radius or a smaller inner one");
    c.polylines.push_back({std::move(path), false});
    return c;
  }
  for (const Points& line : polylines_of(cut, source, &c.description)) c.polylines.push_back({to_plane(line, plane), false});
  return c;
}

}  // namespace

void load_cloth(const Value& root, const std::filesystem::path& path, Scene* scene) {
  for (const char* key : {"mesh", "embed", "material", "move", "obstacles", "contact_stiffness", "self_collision", "scalpels",
                          "transforms", "springs", "events"}) {
    if (root.has(key)) {
      root.at(key).fail("not in a cloth scene (it has 'cloth'; cloth scenes take gravity, time, solver, pin, cuts and output)");
    }
  }
  const Value cloth = root.at("cloth");
  cloth.allow({"mesh", "material"});
  ClothScene c;
  c.mesh = load_cloth_mesh(cloth.at("mesh"), path, &c.plane);
  if (const auto material = cloth.get("material")) c.material = load_cloth_material(*material);
  if (const auto gravity = root.get("gravity")) c.step.gravity = gravity->vec3();
  const Value time = root.at("time");
  time.allow({"dt", "duration", "output_every"});
  if (const auto dt = time.get("dt")) c.step.dt = dt->positive();
  scene->duration = time.at("duration").positive();
  if (const auto every = time.get("output_every")) scene->output_every = every->positive();
  if (const auto solver = root.get("solver")) {
    solver->allow({"tolerance", "max_newton_iterations"});
    if (const auto v = solver->get("tolerance")) c.step.tolerance = v->positive();
    if (const auto v = solver->get("max_newton_iterations")) c.step.max_newton_iterations = v->integer(1);
  }
  scene->pins = load_pins(root);
  if (const auto cuts = root.get("cuts")) {
    for (const Value& cut : cuts->array()) c.cuts.push_back(load_cloth_cut(cut, path, c.plane));
    std::stable_sort(c.cuts.begin(), c.cuts.end(), [](const ClothCut& a, const ClothCut& b) { return a.time < b.time; });
  }
  load_output(root, scene);
  scene->step.dt = c.step.dt;
  scene->step.gravity = c.step.gravity;
  scene->cloth = std::move(c);
}

namespace {

// A cut being applied: how far along its polylines it has come. Per polyline: the length along
// it at each point, the next point not yet reached, and the tip (where the cut has got to, a
// point or a point between two; each stretch starts at the last one's tip, the same doubles, so
// consecutive stretches meet exactly).
struct CutProgress {
  std::vector<std::vector<double>> along;
  std::vector<double> start;  // per polyline: the length of those before it
  std::vector<Index> next;
  std::vector<Eigen::Vector2d> tip;
  double length = 0;
  bool started = false, done = false;
};

CutProgress progress_of(const ClothCut& cut) {
  CutProgress p;
  for (const Polyline& line : cut.polylines) {
    p.start.push_back(p.length);
    std::vector<double>& along = p.along.emplace_back(1, 0.0);
    for (Index i = 1; i < line.points.rows(); ++i) along.push_back(along.back() + (line.points.row(i) - line.points.row(i - 1)).norm());
    p.length += along.back();
  }
  p.next.assign(cut.polylines.size(), 0);
  p.tip.assign(cut.polylines.size(), Eigen::Vector2d::Zero());
  return p;
}

// The stretches of the cut's polylines from their tips to `fraction` of their whole length.
std::vector<Polyline> advance(const ClothCut& cut, double fraction, CutProgress* p) {
  std::vector<Polyline> stretches;
  for (std::size_t l = 0; l < cut.polylines.size(); ++l) {
    const Points2& points = cut.polylines[l].points;
    const std::vector<double>& along = p->along[l];
    const Index n = static_cast<Index>(points.rows());
    const double to = fraction >= 1 ? along.back() : fraction * p->length - p->start[l];
    Index& next = p->next[l];
    if (to < 0 || next >= n) continue;
    std::vector<Eigen::Vector2d> stretch;
    if (next == 0) {
      p->tip[l] = points.row(0).transpose();
      next = 1;
    }
    stretch.push_back(p->tip[l]);
    for (; next < n && (along[next] <= to || fraction >= 1); ++next) stretch.push_back(points.row(next).transpose());
    if (next < n && to > along[next - 1]) {
      const double f = (to - along[next - 1]) / (along[next] - along[next - 1]);
      const Eigen::Vector2d between = points.row(next - 1).transpose() + f * (points.row(next) - points.row(next - 1)).transpose();
      if (between != stretch.back()) stretch.push_back(between);
    }
    p->tip[l] = stretch.back();
    if (stretch.size() < 2) continue;
    Polyline line;
    line.points.resize(static_cast<Index>(stretch.size()), 2);
    for (std::size_t i = 0; i < stretch.size(); ++i) line.points.row(static_cast<Index>(i)) = stretch[i].transpose();
    stretches.push_back(std::move(line));
  }
  return stretches;
}

class ClothRunner {
 public:
  ClothRunner(const Scene& scene, const std::filesystem::path& directory, const SceneRunOptions& options)
      : scene_(scene), cloth_(*scene.cloth), directory_(directory), options_(options), cutter_(cloth_.mesh),
        result_(cutter_.result()), sim_(result_.mesh, to_space(cloth_.mesh.rest, cloth_.plane), cloth_.material),
        frames_(scene, cloth_.step.dt, directory, options, ".vtp") {
    const Points rest = to_space(cloth_.mesh.rest, cloth_.plane);
    for (Index n = 0; n < rest.rows(); ++n) {
      for (const Box& box : scene_.pins) {
        if ((rest.row(n).transpose().array() >= box.min.array()).all() && (rest.row(n).transpose().array() <= box.max.array()).all()) {
          sim_.pin(n);
        }
      }
    }
    for (const ClothCut& cut : cloth_.cuts) progress_.push_back(progress_of(cut));
  }

  SceneSummary run() {
    const auto start_time = Clock::now();
    std::filesystem::create_directories(directory_);
    const double dt = cloth_.step.dt;
    write_frame(0);
    std::vector<double> step_ms;
    int newton_total = 0;
    SceneStageSeconds& t = summary_.stage_seconds;
    for (int s = 0; s < frames_.steps(); ++s) {
      const SceneStageSeconds before = t;
      apply_cuts((s + 0.5) * dt);  // what is due by the middle of the step
      const auto start = Clock::now();
      const sim::ClothStepReport report = sim_.step(cloth_.step);
      t.step += seconds_since(start);
      step_ms.push_back(1e3 * (t.cut - before.cut + t.surface - before.surface + t.remesh - before.remesh + t.step - before.step));
      newton_total += report.newton_iterations;
      summary_.max_residual = std::max(summary_.max_residual, report.residual);
      summary_.unconverged_steps += report.converged ? 0 : 1;
      ++summary_.steps;
      if (frames_.frame_after(s)) {
        write_frame((s + 1) * dt);
        if (frames_.enough()) break;
      }
    }
    summary_.cloth = true;
    summary_.triangles_in = cloth_.mesh.num_triangles();
    summary_.triangle_copies = result_.mesh.mesh.num_triangles();
    summary_.nodes = result_.mesh.mesh.num_nodes();
    summary_.pieces = result_.mesh.num_pieces();
    summary_.piece_areas = result_.mesh.piece_areas;
    summary_.mean_newton_iterations = summary_.steps > 0 ? static_cast<double>(newton_total) / summary_.steps : 0;
    frames_.finish(step_ms, sim_.positions(), start_time, &summary_);
    write_summary();
    return summary_;
  }

 private:
  // The cuts due by `due`: whole ones at once, progressive ones as far as they have come.
  void apply_cuts(double due) {
    for (std::size_t k = 0; k < cloth_.cuts.size(); ++k) {
      const ClothCut& cut = cloth_.cuts[k];
      CutProgress& p = progress_[k];
      if (cut.time > due) break;  // sorted by time
      if (p.done) continue;
      if (cut.world_space) {
        const auto start = Clock::now();
        const PlanarCutReport report = cutter_.cut_deformed(cut.triangles, sim_.positions());
        summary_.stage_seconds.cut += seconds_since(start);
        summary_.skipped_coplanar += static_cast<Index>(report.skipped_coplanar.size());
        after_batch(report);
        p.started = p.done = true;
        ++summary_.cuts_applied;
        continue;
      }
      // Rest space: as far as it has come by now, evenly along the polylines' length.
      const double fraction = cut.until > cut.time ? std::clamp((due - cut.time) / (cut.until - cut.time), 0.0, 1.0) : 1.0;
      const std::vector<Polyline> batch = advance(cut, fraction, &p);
      p.done = fraction >= 1;
      if (batch.empty()) continue;
      const auto start = Clock::now();
      const PlanarCutReport report = cutter_.cut(batch);
      summary_.stage_seconds.cut += seconds_since(start);
      after_batch(report);
      if (!p.started) ++summary_.cuts_applied;
      p.started = true;
    }
  }

  // The cut mesh and material after a batch, and the simulator on the new mesh (new nodes start
  // where, and as, the nodes they were split from).
  void after_batch(const PlanarCutReport& report) {
    if (report.touched.empty()) return;  // nothing changed: no new copy or node
    auto start = Clock::now();
    result_ = cutter_.result();
    summary_.stage_seconds.surface += seconds_since(start);
    start = Clock::now();
    sim_.remesh(result_.mesh, report);
    summary_.stage_seconds.remesh += seconds_since(start);
  }

  void write_frame(double time) {
    const auto start = Clock::now();
    const int frame = frames_.next();
    const Points& nodes = sim_.positions();
    if (scene_.write_mesh) {
      write_surface(directory_ / frame_file_name("mesh", frame, ".vtp"), TriangleSurface{nodes, result_.mesh.mesh.triangles});
    }
    if (scene_.write_surface || options_.frame_surface) {
      SceneFrame shown;
      shown.surface = TriangleSurface{result_.material.positions(result_.mesh, nodes), result_.material.triangles};
      if (scene_.write_surface) write_surface(directory_ / frame_file_name("surface", frame, ".vtp"), shown.surface);
      if (options_.frame_surface) {
        shown.line_points = nodes;
        shown.lines = triangle_edges(result_.mesh.mesh.triangles);
        options_.frame_surface(frame, shown);
      }
    }
    frames_.written(time, start, &summary_);
  }

  void write_summary() const {
    const SceneSummary& s = summary_;
    const Json out{{"scene", scene_.source.string()},
                   {"cloth", true},
                   {"frames", s.frames},
                   {"steps", s.steps},
                   {"simulated_seconds", s.simulated_seconds},
                   {"cuts_applied", s.cuts_applied},
                   {"triangles_in", s.triangles_in},
                   {"triangle_copies", s.triangle_copies},
                   {"nodes", s.nodes},
                   {"pieces", s.pieces},
                   {"piece_areas", s.piece_areas},
                   {"skipped_coplanar", s.skipped_coplanar},
                   {"wall_seconds", s.wall_seconds},
                   {"seconds_per_frame", s.seconds_per_frame},
                   {"mean_newton_iterations", s.mean_newton_iterations},
                   {"unconverged_steps", s.unconverged_steps},
                   {"max_residual", s.max_residual},
                   {"ms_per_step", ms_per_step_json(s)},
                   {"output_seconds", s.stage_seconds.output},
                   {"final_box", {s.final_box.min[0], s.final_box.min[1], s.final_box.min[2], s.final_box.max[0],
                                  s.final_box.max[1], s.final_box.max[2]}}};
    write_text_file(directory_ / "summary.json", out.dump(2) + "\n");
  }

  const Scene& scene_;
  const ClothScene& cloth_;
  std::filesystem::path directory_;
  const SceneRunOptions& options_;
  PlanarCutter cutter_;
  PlanarCutResult result_;
  sim::ClothSimulator sim_;
  std::vector<CutProgress> progress_;
  FrameSeries frames_;
  SceneSummary summary_;
};

}  // namespace

SceneSummary run_cloth_scene(const Scene& scene, const std::filesystem::path& directory, const SceneRunOptions& options) {
  if (options.check_intersections) {
    throw Error(ErrorKind::kInvalidArgument,
                "counting intersections is for tet scenes' material surfaces; a cloth scene has none to count yet",
                scene.source.string());
  }
  return ClothRunner(scene, directory, options).run();
}

}  // namespace tetcut::scene
