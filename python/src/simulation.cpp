// tetcut._tetcut.sim: the FEM simulator on (cut) tet meshes; and the live session (a scene's
// cutter, simulator and surface advanced a step at a time while taking events).

#include <tetcut/scene.hpp>
#include <tetcut/session.hpp>
#include <tetcut/sim.hpp>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.hpp"
#include "bindings.hpp"

namespace tetcut::python {
namespace {

// Embedded points: copy ids (k,) and barycentric weights (k, 4), checked against the copies.
std::vector<sim::EmbeddedPoint> embedded_points(py::handle tets_array, py::handle weights_array, Index num_tets) {
  const auto t = index_rows(tets_array, "tets", 0, num_tets);
  const auto w = float_rows(weights_array, "weights", 4);
  if (t.rows() != w.rows()) throw py::value_error("tets and weights need one row per point each");
  std::vector<sim::EmbeddedPoint> out(static_cast<std::size_t>(t.rows()));
  for (Eigen::Index i = 0; i < t.rows(); ++i) {
    out[static_cast<std::size_t>(i)].tet = t(i, 0);
    out[static_cast<std::size_t>(i)].weights = w.row(i).transpose();
  }
  return out;
}

sim::EmbeddedPoint embedded_point(Index tet, py::handle weights, Index num_tets) {
  if (tet < 0 || tet >= num_tets) throw py::value_error("no tet copy " + std::to_string(tet));
  const auto w = float_rows(weights, "weights", 0);
  if (w.rows() != 4) throw py::value_error("weights must be 4 numbers");
  return {tet, Eigen::Vector4d(w(0, 0), w(1, 0), w(2, 0), w(3, 0))};
}

// A node of the simulator, checked (an IndexError, not a crash, for one it lacks).
Index node_of(const sim::Simulator& s, Index node) {
  if (node < 0 || node >= s.num_nodes()) throw py::index_error("no node " + std::to_string(node));
  return node;
}

py::dict stage_seconds(const SceneStageSeconds& s) {
  py::dict d;
  d["cut"] = s.cut;
  d["surface"] = s.surface;
  d["remesh"] = s.remesh;
  d["step"] = s.step;
  return d;
}

}  // namespace

void bind_sim(py::module_& root) {
  py::module_ m = root.def_submodule("sim", "Finite elements on (cut) tet meshes: hyperelastic tets, backward Euler.");
  using namespace sim;

  py::enum_<Model>(m, "Model")
      .value("corotated", Model::kCorotated)
      .value("stable_neo_hookean", Model::kStableNeoHookean);

  py::class_<Material>(m, "Material", "A constitutive model and its parameters (SI units).")
      .def(py::init([](Model model, double E, double nu, double density, double mass_damping, double stiffness_damping) {
             lame_parameters(E, nu);  // range checks: tetcut.Error for a bad E or nu
             return Material{model, E, nu, density, mass_damping, stiffness_damping};
           }), py::arg("model") = Model::kStableNeoHookean, py::arg("youngs_modulus") = 1e5, py::arg("poissons_ratio") = 0.3,
           py::arg("density") = 1000.0, py::arg("mass_damping") = 0.0, py::arg("stiffness_damping") = 0.0)
      .def_readwrite("model", &Material::model)
      .def_readwrite("youngs_modulus", &Material::youngs_modulus)
      .def_readwrite("poissons_ratio", &Material::poissons_ratio)
      .def_readwrite("density", &Material::density)
      .def_readwrite("mass_damping", &Material::mass_damping)
      .def_readwrite("stiffness_damping", &Material::stiffness_damping);

  py::enum_<FirstGuess>(m, "FirstGuess", "Where Newton's method starts a dynamic step (see the C++ docs).")
      .value("prediction", FirstGuess::kPrediction)
      .value("start", FirstGuess::kStart);

  py::class_<StepOptions>(m, "StepOptions", "Time step, gravity and the Newton / conjugate gradient budget.")
      .def(py::init([](double dt, py::object gravity) {
             StepOptions o;
             o.dt = dt;
             if (!gravity.is_none()) o.gravity = vec3(gravity, "gravity");
             return o;
           }), py::arg("dt") = 1.0 / 120, py::arg("gravity") = py::none())
      .def_static("real_time", &StepOptions::real_time, py::arg("dt"), py::arg("newton_iterations") = 1, py::arg("cg_iterations") = 30,
                  py::arg("reuse") = 4, "A fixed budget of work per step, with a safety valve (see the C++ docs).")
      .def_readwrite("dt", &StepOptions::dt)
      .def_property("gravity", [](const StepOptions& o) { return to_numpy(o.gravity); },
                    [](StepOptions& o, py::handle g) { o.gravity = vec3(g, "gravity"); })
      .def_readwrite("max_newton_iterations", &StepOptions::max_newton_iterations)
      .def_readwrite("tolerance", &StepOptions::tolerance)
      .def_readwrite("max_cg_iterations", &StepOptions::max_cg_iterations)
      .def_readwrite("reuse_hessian", &StepOptions::reuse_hessian)
      .def_readwrite("single_precision_matrix", &StepOptions::single_precision_matrix)
      .def_readwrite("rescue_residual", &StepOptions::rescue_residual)
      .def_readwrite("rescue_iterations", &StepOptions::rescue_iterations)
      .def_readwrite("first_guess", &StepOptions::first_guess);

  py::class_<StepReport>(m, "StepReport", "What one step did.")
      .def_readonly("newton_iterations", &StepReport::newton_iterations)
      .def_readonly("cg_iterations", &StepReport::cg_iterations)
      .def_readonly("rescue_iterations", &StepReport::rescue_iterations)
      .def_readonly("converged", &StepReport::converged)
      .def_readonly("energy", &StepReport::energy)
      .def_readonly("residual", &StepReport::residual)
      .def_readonly("assemble_seconds", &StepReport::assemble_seconds)
      .def_readonly("solve_seconds", &StepReport::solve_seconds)
      .def_readonly("line_search_seconds", &StepReport::line_search_seconds)
      .def_readonly("constraint_matrix_seconds", &StepReport::constraint_matrix_seconds,
                    "Of assemble_seconds: the contact and spring terms added into the Newton matrix.")
      .def_readonly("contact_pairs", &StepReport::contact_pairs, "Surface pairs closer than the contact thickness at the end.")
      .def_readonly("contact_limited_steps", &StepReport::contact_limited_steps,
                    "Newton steps that continuous collision detection shortened.")
      .def_readonly("contact_seconds", &StepReport::contact_seconds);

  py::class_<SurfaceContactOptions>(m, "SurfaceContactOptions",
                                    "Contact of the material surface with itself: thickness (m), stiffness (N/m), friction (0 = defaults / none), "
                                    "cushion (thicknesses the two sides of a cut are pushed apart; 0 = none).")
      .def(py::init([](double thickness, double stiffness, double friction, double cushion) {
             return SurfaceContactOptions{thickness, stiffness, friction, cushion};
           }),
           py::arg("thickness") = 0.0, py::arg("stiffness") = 0.0, py::arg("friction") = 0.0, py::arg("cushion") = 0.0)
      .def_readwrite("thickness", &SurfaceContactOptions::thickness)
      .def_readwrite("stiffness", &SurfaceContactOptions::stiffness)
      .def_readwrite("friction", &SurfaceContactOptions::friction)
      .def_readwrite("cushion", &SurfaceContactOptions::cushion);

  py::class_<Obstacle>(m, "Obstacle", "A solid the contact points are kept out of: Obstacle.plane, .sphere or .box.")
      .def_static("plane", [](py::handle point, py::handle normal) { return Obstacle::plane(vec3(point, "point"), vec3(normal, "normal")); },
                  py::arg("point"), py::arg("normal"))
      .def_static("sphere", [](py::handle centre, double radius) { return Obstacle::sphere(vec3(centre, "centre"), radius); },
                  py::arg("centre"), py::arg("radius"))
      .def_static("box", [](py::handle min, py::handle max) { return Obstacle::box(vec3(min, "min"), vec3(max, "max")); },
                  py::arg("min"), py::arg("max"))
      .def_readwrite("friction", &Obstacle::friction, "Coulomb coefficient of points pressed into it (0: frictionless)")
      .def("distance", [](const Obstacle& o, py::handle x) {
             Vec3 direction;
             const double d = o.distance(vec3(x, "x"), &direction);
             return py::make_tuple(d, to_numpy(direction));
           }, py::arg("x"), "(signed distance, outward direction) of a point");

  py::class_<Simulator>(m, "Simulator", "Backward Euler on a (cut) tet mesh.")
      .def(py::init([](py::handle V, py::handle T, const Material& material, py::object fractions) {
             const TetMesh mesh = mesh_of(V, T);
             std::vector<double> f;
             if (!fractions.is_none()) {
               const auto a = float_rows(fractions, "volume_fraction", 0);
               f.assign(a.data(), a.data() + a.size());
             }
             return Simulator(mesh, material, f);
           }), py::arg("V"), py::arg("T"), py::arg("material") = Material{}, py::arg("volume_fraction") = py::none(),
           "A simulator of the mesh (V, T) (rest positions), each tet's mass and energy scaled by volume_fraction (m,).")
      .def("remesh", [](Simulator& s, const Cutter& cutter, const CutBatchReport& batch) {
             py::gil_scoped_release release;
             s.remesh(cutter, batch);
           }, py::arg("cutter"), py::arg("batch"), "After a cut batch of `cutter` (whose mesh this simulates): the new mesh, state carried over.")
      .def_property_readonly("num_nodes", &Simulator::num_nodes)
      .def_property_readonly("num_tets", &Simulator::num_tets)
      .def_property("positions", [](const Simulator& s) { return to_numpy(s.positions()); },
                    [](Simulator& s, py::handle X) { s.set_positions(points(X, "positions")); }, "float64 (n, 3)")
      .def_property("velocities", [](const Simulator& s) { return to_numpy(s.velocities()); },
                    [](Simulator& s, py::handle X) { s.set_velocities(points(X, "velocities")); }, "float64 (n, 3)")
      .def_property_readonly("masses", [](const Simulator& s) {
        const Eigen::VectorXd& mass = s.masses();
        return to_numpy(std::span<const double>(mass.data(), static_cast<std::size_t>(mass.size())));
      })
      .def("pin", [](Simulator& s, Index node) {
             s.pin(node_of(s, node));
           }, py::arg("node"), "Holds a node where it is.")
      .def("move_to", [](Simulator& s, Index node, py::handle target) {
             s.move_to(node_of(s, node), vec3(target, "target"));
           }, py::arg("node"), py::arg("target"), "Moves a node to target over the next step.")
      .def("release", [](Simulator& s, Index node) {
             s.release(node_of(s, node));
           }, py::arg("node"), "Frees a pinned or moved node.")
      .def("step", &Simulator::step, py::arg("options") = StepOptions{}, py::call_guard<py::gil_scoped_release>(),
           "One backward Euler step; returns a StepReport.")
      .def("solve_static", &Simulator::solve_static, py::arg("options") = StepOptions{}, py::call_guard<py::gil_scoped_release>(),
           "Static equilibrium under gravity with the pinned and moved nodes held.")
      .def("set_contact_points", [](Simulator& s, py::handle tets, py::handle weights) {
             s.set_contact_points(embedded_points(tets, weights, s.num_tets()));
           }, py::arg("tets"), py::arg("weights"),
           "Points kept out of the obstacles: copy ids int32 (k,) and weights (k, 4), e.g. a MaterialSurface's vertex_tet and vertex_weights.")
      .def("add_obstacle", &Simulator::add_obstacle, py::arg("obstacle"), "Keeps the contact points out of an Obstacle.")
      .def("set_contact_surface", &Simulator::set_contact_surface, py::arg("surface"), py::arg("options") = SurfaceContactOptions{},
           py::call_guard<py::gil_scoped_release>(),
           "Contact of the material surface (a MaterialSurface of this mesh) with itself and between pieces: a barrier below the\n"
           "thickness and steps stopped short of any two parts meeting. Set it again after every cut.")
      .def("clear_contact_surface", &Simulator::clear_contact_surface, "No surface contact.")
      .def("surface_contact", [](const Simulator& s) {
             const Simulator::SurfaceContactState c = s.surface_contact();
             py::dict d;
             d["enabled"] = c.enabled;
             d["thickness"] = c.thickness;
             d["stiffness"] = c.stiffness;
             d["candidates"] = c.candidates;
             d["joined_copy_pairs"] = c.joined_copy_pairs;
             d["rebuilds"] = c.rebuilds;
             d["guards"] = c.guards;
             d["fresh_cut_allowance"] = c.fresh_cut_allowance;
             d["guarded_reach"] = c.guarded_reach;
             d["seconds"] = py::dict(py::arg("rebuild") = c.rebuild_seconds, py::arg("ccd") = c.ccd_seconds, py::arg("active") = c.active_seconds,
                                     py::arg("guards") = c.guard_seconds, py::arg("joins") = c.join_seconds);
             return d;
           }, "What surface contact works with (a dict).")
      .def("surface_contact_energy", &Simulator::surface_contact_energy, "The surface contact energy now (J; inf if two parts touch).")
      .def_property("contact_stiffness", &Simulator::contact_stiffness, &Simulator::set_contact_stiffness,
                    "N/m of the obstacles' penalty (by default 10 E h, h the mean edge length)")
      .def("add_spring", [](Simulator& s, Index tet_p, py::handle weights_p, Index tet_q, py::handle weights_q, double stiffness) {
             s.add_spring(embedded_point(tet_p, weights_p, s.num_tets()), embedded_point(tet_q, weights_q, s.num_tets()), stiffness);
           }, py::arg("tet_p"), py::arg("weights_p"), py::arg("tet_q"), py::arg("weights_q"), py::arg("stiffness"),
           "A zero-length spring between two embedded points.")
      .def("clear_springs", &Simulator::clear_springs, "Removes every spring.")
      .def_property_readonly("num_springs", &Simulator::num_springs)
      .def("set_anchors", [](Simulator& s, py::handle tets, py::handle weights, py::handle targets, py::handle stiffness) {
             const std::vector<EmbeddedPoint> p = embedded_points(tets, weights, s.num_tets());
             const Points to = points(targets, "targets");
             const auto k = float_rows(stiffness, "stiffness", 0);
             if (to.rows() != static_cast<Eigen::Index>(p.size()) || k.rows() != to.rows()) {
               throw py::value_error("tets, weights, targets and stiffness need one row per anchor each");
             }
             std::vector<Simulator::Anchor> anchors;
             for (std::size_t i = 0; i < p.size(); ++i) anchors.push_back({p[i], to.row(static_cast<Index>(i)).transpose(), k(static_cast<Index>(i), 0)});
             s.set_anchors(std::move(anchors));
           }, py::arg("tets"), py::arg("weights"), py::arg("targets"), py::arg("stiffness"),
           "Springs from embedded points to targets (k, 3) with stiffness (k,): hooks.")
      .def("position", [](const Simulator& s, Index tet, py::handle weights) { return to_numpy(s.position(embedded_point(tet, weights, s.num_tets()))); },
           py::arg("tet"), py::arg("weights"), "Where an embedded point is now.")
      .def("elastic_energy", &Simulator::elastic_energy, "Elastic energy of the current positions (J).")
      .def("elastic_gradient", [](const Simulator& s) { return to_numpy(s.elastic_gradient()); }, "d(energy)/d(positions), (n, 3): minus the forces.")
      .def("momentum", [](const Simulator& s) { return to_numpy(s.momentum()); }, "Total momentum, sum of m v (3,).");

  // The live session, over a scene.
  py::class_<Scene>(root, "Scene", "A validated scene (load_scene / parse_scene): mesh or embedding, material, events.");
  root.def("load_scene", &load_scene, py::arg("path"), "Reads and validates a scene file (JSON).");
  root.def("parse_scene", &parse_scene, py::arg("text"), py::arg("path"),
           "Validates a scene given as JSON text; relative paths in it are resolved against path's folder.");

  py::class_<SessionStep>(root, "SessionStep", "What one step of a session did.")
      .def_readonly("report", &SessionStep::report)
      .def_property_readonly("seconds", [](const SessionStep& s) { return stage_seconds(s.seconds); })
      .def_readonly("topology_changed", &SessionStep::topology_changed);

  py::class_<Session>(root, "Session", "A scene's cutter, simulator and material surface, advanced a step at a time while taking events.")
      // The session reads its scene as it runs: the Scene lives at least as long (keep_alive).
      .def(py::init([](const Scene& scene) {
             py::gil_scoped_release release;
             return Session(scene);
           }), py::arg("scene"), py::keep_alive<1, 2>())
      .def("advance", &Session::advance, py::call_guard<py::gil_scoped_release>(), "The scene's events due, then one step.")
      .def_property_readonly("time", &Session::time)
      .def_property_readonly("steps", &Session::steps)
      .def("blade", [](Session& s, py::handle a, py::handle b) {
             const BladePose pose{vec3(a, "a"), vec3(b, "b")};
             py::gil_scoped_release release;
             s.blade(pose);
           }, py::arg("a"), py::arg("b"), "The blade's edge is now a-b (world space): the strip since its last pose is cut.")
      .def("lift_blade", &Session::lift_blade, "The blade leaves the material: its next pose starts a new stroke.")
      .def("grab", [](Session& s, py::handle point, double stiffness) { return s.grab(vec3(point, "point"), stiffness); },
           py::arg("point"), py::arg("stiffness") = 0.0, "Hooks the surface point nearest `point`; returns the hook's number.")
      .def("move_hook", [](Session& s, int hook, py::handle target) { s.move_hook(hook, vec3(target, "target")); },
           py::arg("hook"), py::arg("target"), "Moves a hook's target (world space).")
      .def("release", &Session::release, py::arg("hook"), "Lets go of a hook.")
      .def("pin", [](Session& s, py::handle point, double radius) { s.pin(vec3(point, "point"), radius); }, py::arg("point"), py::arg("radius"),
           "Holds the nodes within radius of point (world space) where they are.")
      .def("unpin", [](Session& s, py::handle point, double radius) { s.unpin(vec3(point, "point"), radius); }, py::arg("point"), py::arg("radius"),
           "Lets the nodes within radius of point go.")
      .def("surface", &Session::surface, py::return_value_policy::copy, "The material surface (rest positions).")
      .def("surface_positions", [](Session& s) { return to_numpy(s.surface_positions()); }, "Where the surface's vertices are now.")
      .def("positions", [](const Session& s) { return to_numpy(s.simulator().positions()); }, "The simulated nodes' positions.")
      .def("tet_nodes", [](const Session& s) { return to_numpy(s.cutter().tet_nodes()); }, "The cut mesh's copies' nodes.")
      .def("result", &Session::result, py::return_value_policy::copy, py::call_guard<py::gil_scoped_release>(),
           "The whole result: pieces, mesh, surface (CutResult).")
      .def_property_readonly("cuts_applied", &Session::cuts_applied)
      .def_property_readonly("topology_changes", &Session::topology_changes)
      .def_property_readonly("num_hooks", &Session::num_hooks);
  root.def("write_recording", &write_recording, py::arg("path"), py::arg("scene"), py::arg("session"),
           "Writes the session's events as a scene file that `tetcut sim` replays.");
}

}  // namespace tetcut::python
