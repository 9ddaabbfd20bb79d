// tetcut._tetcut: the Cutter (rest-space and world-space cuts, provenance of every batch), its
// material surface and result, embedding, and blades.

#include <tetcut/blade.hpp>
#include <tetcut/collision.hpp>
#include <tetcut/cutter.hpp>
#include <tetcut/embed.hpp>

#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"

namespace tetcut::python {
namespace {

KeepMaterial keep_of(const std::string& keep) {
  if (const std::optional<KeepMaterial> known = keep_material_from_name(keep)) return *known;
  throw py::value_error("keep must be 'inside', 'largest' or 'point', not '" + keep + "'");
}

// The cut mesh's copies T (checked against the nodes, and against the copies the surface names).
std::vector<std::array<Index, 4>> copies_for(const MaterialSurface& surface, py::handle T, std::int64_t num_nodes) {
  std::vector<std::array<Index, 4>> copies = tet_rows(T, "T", num_nodes);
  for (const Index copy : surface.vertex_tet) {
    if (copy < 0 || static_cast<std::size_t>(copy) >= copies.size()) {
      throw py::value_error("T has no tet copy " + std::to_string(copy) + ": pass the cut mesh's tets");
    }
  }
  return copies;
}

}  // namespace

void bind_cutting(py::module_& m) {
  py::class_<MaterialSurface>(m, "MaterialSurface",
                              "The boundary of the material, oriented outward, each vertex embedded in a tet copy.")
      .def_property_readonly("vertices", [](const MaterialSurface& s) { return to_numpy(s.surface.vertices); }, "float64 (n, 3), rest positions")
      .def_property_readonly("triangles", [](const MaterialSurface& s) { return to_numpy(s.surface.triangles); }, "int32 (k, 3)")
      .def_property_readonly("vertex_tet", [](const MaterialSurface& s) { return to_numpy(s.vertex_tet); }, "int32 (n,): the copy each vertex is embedded in")
      .def_property_readonly("vertex_weights", [](const MaterialSurface& s) { return to_numpy(s.vertex_weights); },
                             "float64 (n, 4): barycentric weights in that copy's nodes")
      .def_property_readonly("triangle_source", [](const MaterialSurface& s) { return to_numpy(s.triangle_source); },
                             "int64 (k,): the cut triangle each lies on, or -1 - f for input face f")
      .def_property_readonly("triangle_tet", [](const MaterialSurface& s) { return to_numpy(s.triangle_tet); }, "int32 (k,): the copy each bounds")
      .def("positions", [](const MaterialSurface& s, py::handle T, py::handle X) {
             const Points nodes = points(X, "X");
             return to_numpy(s.positions(copies_for(s, T, nodes.rows()), nodes));
           }, py::arg("T"), py::arg("X"),
           "Vertex positions (n, 3) for the cut mesh's tets T and node positions X (e.g. a simulator's).");

  py::class_<CutBatchReport>(m, "CutBatchReport", "What one batch did, and where its new nodes and copies came from.")
      .def_readonly("triangles", &CutBatchReport::triangles)
      .def_property_readonly("degenerate", [](const CutBatchReport& r) { return to_numpy(r.degenerate); }, "zero-area triangles, skipped")
      .def_readonly("tets_touched", &CutBatchReport::tets_touched)
      .def_property_readonly("touched", [](const CutBatchReport& r) { return to_numpy(r.touched); }, "input tets whose material changed")
      .def_property_readonly("skipped_inverted", [](const CutBatchReport& r) { return to_numpy(r.skipped_inverted); })
      .def_readonly("first_new_node", &CutBatchReport::first_new_node)
      .def_property_readonly("new_node_source", [](const CutBatchReport& r) { return to_numpy(r.new_node_source); },
                             "node first_new_node + i was split from node new_node_source[i]")
      .def_readonly("first_new_tet", &CutBatchReport::first_new_tet)
      .def_property_readonly("new_tet_source", [](const CutBatchReport& r) { return to_numpy(r.new_tet_source); },
                             "copy first_new_tet + i was split from copy new_tet_source[i]")
      .def_property_readonly("changed_tets", [](const CutBatchReport& r) { return to_numpy(r.changed_tets); }, "older copies whose nodes changed");

  py::class_<CutResult>(m, "CutResult", "The simulation mesh (one copy of a tet per material component), its pieces and material surface.")
      .def_property_readonly("vertices", [](const CutResult& r) { return to_numpy(r.mesh.mesh.rest()); }, "float64 (n, 3), rest positions")
      .def_property_readonly("current", [](const CutResult& r) { return to_numpy(r.mesh.mesh.current()); }, "float64 (n, 3)")
      .def_property_readonly("tets", [](const CutResult& r) { return to_numpy(r.mesh.mesh.tets()); }, "int32 (m, 4)")
      .def_property_readonly("node_parent", [](const CutResult& r) { return to_numpy(r.mesh.node_parent); })
      .def_property_readonly("tet_parent", [](const CutResult& r) { return to_numpy(r.mesh.tet_parent); })
      .def_property_readonly("tet_piece", [](const CutResult& r) { return to_numpy(r.mesh.tet_piece); }, "pieces by volume, largest first")
      .def_property_readonly("tet_material_volume", [](const CutResult& r) { return to_numpy(r.mesh.tet_material_volume); })
      .def_property_readonly("piece_volumes", [](const CutResult& r) { return to_numpy(r.mesh.piece_volumes); })
      .def_property_readonly("num_pieces", [](const CutResult& r) { return r.mesh.num_pieces(); })
      .def_property_readonly("material_fractions", [](const CutResult& r) { return to_numpy(r.mesh.material_fractions()); },
                             "per copy: the fraction of its tet that is material (what a simulator scales it by)")
      .def_readonly("surface", &CutResult::surface)
      .def_readonly("seconds_mesh", &CutResult::seconds_mesh)
      .def_readonly("seconds_surface", &CutResult::seconds_surface);

  py::class_<Cutter>(m, "Cutter", "The cut state of one tet mesh; batches of triangles accumulate, exactly.")
      .def(py::init([](py::handle V, py::handle T) { return Cutter(mesh_of(V, T)); }), py::arg("V"), py::arg("T"),
           "Takes the mesh to cut: V float64 (n, 3), T int32 (m, 4), positively oriented.")
      .def("cut", [](Cutter& c, py::handle V, py::handle F) {
             const TriangleSurface batch = surface_of(V, F);
             py::gil_scoped_release release;
             return c.cut(batch);
           }, py::arg("V"), py::arg("F"), "Cuts by triangles (V, F) in rest space; returns the batch's CutBatchReport.")
      .def("cut_deformed", [](Cutter& c, py::handle V, py::handle F, py::object X) {
             const TriangleSurface batch = surface_of(V, F);
             std::optional<Points> nodes;
             if (!X.is_none()) nodes = points(X, "X");
             py::gil_scoped_release release;
             return nodes ? c.cut_deformed(batch, *nodes) : c.cut_deformed(batch);
           }, py::arg("V"), py::arg("F"), py::arg("X") = py::none(),
           "Cuts by triangles placed in world space on the mesh at its current positions (or at X, num_nodes x 3).")
      .def("set_current", [](Cutter& c, py::handle X) { c.set_current(points(X, "X")); }, py::arg("X"),
           "Sets the cut mesh's current (deformed) node positions, num_nodes x 3.")
      .def("current", [](const Cutter& c) { return to_numpy(c.current()); }, "The current node positions, num_nodes x 3.")
      .def("to_rest", [](const Cutter& c, py::handle P) { return to_numpy(c.to_rest(points(P, "P"))); }, py::arg("P"),
           "Maps world-space points (k, 3) on the deformed mesh to rest space.")
      .def_property_readonly("num_nodes", &Cutter::num_nodes)
      .def_property_readonly("num_tets", &Cutter::num_tets)
      .def_property_readonly("tet_nodes", [](const Cutter& c) { return to_numpy(c.tet_nodes()); }, "int32 (m, 4): each copy's nodes")
      .def_property_readonly("node_parent", [](const Cutter& c) { return to_numpy(c.node_parent()); })
      .def_property_readonly("tet_parent", [](const Cutter& c) { return to_numpy(c.tet_parent()); })
      .def("copies_of", [](const Cutter& c, Index tet) {
             if (tet < 0 || tet >= c.input().num_tets()) throw py::index_error("no input tet " + std::to_string(tet));
             return to_numpy(c.copies_of(tet));
           }, py::arg("tet"), "The copies (int32) of input tet `tet`; empty when it holds no material.")
      .def("material_fraction", [](const Cutter& c, Index copy) {
             if (copy < 0 || copy >= c.num_tets()) throw py::index_error("no tet copy " + std::to_string(copy));
             return c.material_fraction(copy);
           }, py::arg("copy"), "The fraction of its tet's volume that copy `copy` holds as material.")
      .def("surface", [](Cutter& c) {
             py::gil_scoped_release release;
             return c.surface();
           }, "The material surface as it stands (MaterialSurface).")
      .def("result", [](Cutter& c) {
             py::gil_scoped_release release;
             return c.result();
           }, "The simulation mesh, pieces and material surface (CutResult).")
      .def("input_mesh", [](const Cutter& c) { return mesh_arrays(c.input()); }, "(V, T) of the mesh it cuts")
      .def_property_readonly("num_cut_triangles", &Cutter::num_cut_triangles);

  py::class_<EmbedReport>(m, "EmbedReport", "What an embedding did, with the time of each stage.")
      .def_readonly("check", &EmbedReport::check)
      .def_readonly("tets_in", &EmbedReport::tets_in)
      .def_readonly("tets_with_material", &EmbedReport::tets_with_material)
      .def_readonly("tets_duplicated", &EmbedReport::tets_duplicated)
      .def_readonly("covered_facets_joined", &EmbedReport::covered_facets_joined)
      .def_readonly("seconds_check", &EmbedReport::seconds_check)
      .def_readonly("seconds_insert", &EmbedReport::seconds_insert)
      .def_readonly("seconds_classify", &EmbedReport::seconds_classify)
      .def_readonly("seconds_copies", &EmbedReport::seconds_copies);

  m.def("embed", [](py::handle V, py::handle T, py::handle surface_V, py::handle surface_F, const std::string& keep, py::object point) {
          TetMesh mesh = mesh_of(V, T);
          const TriangleSurface surface = surface_of(surface_V, surface_F);
          EmbedOptions options;
          options.keep = keep_of(keep);
          if (options.keep == KeepMaterial::kPoint) {
            if (point.is_none()) throw py::value_error("keep='point' needs a point");
            options.point = vec3(point, "point");
          }
          EmbedReport report;
          std::optional<Cutter> cutter;
          {
            py::gil_scoped_release release;
            cutter.emplace(embed(std::move(mesh), surface, options, &report));
          }
          return py::make_tuple(std::move(*cutter), report);
        }, py::arg("V"), py::arg("T"), py::arg("surface_V"), py::arg("surface_F"), py::arg("keep") = "inside", py::arg("point") = py::none(),
        "Carves the surface out of the tet mesh (V, T), keeping 'inside' (winding number), the 'largest' piece or the piece at "
        "'point'. Returns (Cutter, EmbedReport); the cutter can be cut further.");
  m.def("embedding_lattice", [](py::handle V, py::handle F, double spacing) { return mesh_arrays(embedding_lattice(surface_of(V, F), spacing)); },
        py::arg("V"), py::arg("F"), py::arg("spacing"), "A BCC lattice covering the surface with a cube's margin. Returns (V, T).");
  m.def("spacing_for_cubes", [](py::handle V, py::handle F, Index cubes) { return spacing_for_cubes(surface_of(V, F), cubes); },
        py::arg("V"), py::arg("F"), py::arg("cubes"), "The spacing that puts `cubes` BCC cubes along the surface's longest side.");

  py::class_<SurfaceIntersections>(m, "SurfaceIntersections", "Where the material surface passes through itself.")
      .def_readonly("intersecting_pairs", &SurfaceIntersections::intersecting_pairs)
      .def_readonly("candidate_pairs", &SurfaceIntersections::candidate_pairs)
      .def_readonly("degenerate_triangles", &SurfaceIntersections::degenerate_triangles)
      .def_property_readonly("examples", [](const SurfaceIntersections& r) { return to_numpy(r.examples); },
                             "int32 (k, 2): up to 16 intersecting pairs of triangle ids");
  m.def("count_surface_intersections", [](const MaterialSurface& surface, py::handle T, py::handle X, double opened, double slid) {
          const std::vector<std::array<Index, 4>> copies = tet_rows(T, "T", -1);
          const Points positions = points(X, "X");
          py::gil_scoped_release release;
          return count_surface_intersections(surface, copies, positions, opened, slid);
        }, py::arg("surface"), py::arg("T"), py::arg("X"), py::arg("opened") = 0.0, py::arg("slid") = 0.0,
        "Pairs of the surface's triangles of different copies that intersect, with its vertices at X (n, 3) and the cut "
        "mesh's copies T (m, 4): exact tests; pairs sharing a vertex and unopened cuts left out, and sides of a cut "
        "pressed into each other no deeper than `opened` (what a simulation's guards allow: "
        "Simulator.surface_contact()[\"fresh_cut_allowance\"]), where they touch in the material or lie within `slid` "
        "of each other there (slid along the cut; a simulation's guards allow that up to "
        "Simulator.surface_contact()[\"guarded_reach\"]).");

  m.def("swept_blade", [](py::handle A, py::handle B) {
          const Points a = points(A, "A"), b = points(B, "B");
          if (a.rows() != b.rows()) throw py::value_error("A and B need one row per blade pose each");
          std::vector<BladePose> poses;
          for (Index i = 0; i < a.rows(); ++i) poses.push_back({a.row(i).transpose(), b.row(i).transpose()});
          return surface_arrays(swept_blade(poses));
        }, py::arg("A"), py::arg("B"),
        "The strip a straight blade sweeps through poses (A[i], B[i]) (each (k, 3)), as (V, F) to cut by.");
}

}  // namespace tetcut::python
