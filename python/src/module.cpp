// The Python module tetcut._tetcut (wrapped by the package tetcut): the library's public API over
// numpy arrays. This file: the module, tetcut.Error, files, generators and quality measures.

#include <tetcut/embed.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/io.hpp>
#include <tetcut/quality.hpp>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.hpp"
#include "bindings.hpp"

namespace tetcut::python {
namespace {

const char* kind_name(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::kInvalidInput: return "invalid_input";
    case ErrorKind::kIo: return "io";
    case ErrorKind::kUnsupported: return "unsupported";
    case ErrorKind::kInvalidArgument: return "invalid_argument";
    case ErrorKind::kInternal: return "internal";
  }
  return "unknown";
}

Box box_of(py::handle min, py::handle max) { return Box{vec3(min, "box_min"), vec3(max, "box_max")}; }

}  // namespace

void bind_meshes(py::module_& m) {
  // tetcut.Error: what the library throws, with its kind ('invalid_input', 'io', 'unsupported',
  // 'invalid_argument', 'internal': a bug), the file and line it names (or '' and 0), and the bare message.
  // Never destroyed: the interpreter may be gone by the time statics are.
  static auto* error_type = new py::exception<Error>(m, "Error");
  error_type->doc() = "An error from tetcut: attributes kind, message, file (or ''), line (or 0).";
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const Error& e) {
      const auto type = py::reinterpret_borrow<py::object>(*error_type);
      py::object instance = type(e.what());
      instance.attr("kind") = kind_name(e.kind());
      instance.attr("message") = e.message();
      instance.attr("file") = e.file();
      instance.attr("line") = e.line();
      PyErr_SetObject(error_type->ptr(), instance.ptr());
    }
  });

  m.def("read_tet_mesh", [](const std::filesystem::path& path) {
    TetMesh mesh;
    {
      py::gil_scoped_release release;
      mesh = read_tet_mesh(path);
    }
    return mesh_arrays(mesh);
  }, py::arg("path"), "Reads a tet mesh (.mesh, .msh, .node/.ele, .vtu, .vtk). Returns (V float64 (n, 3), T int32 (m, 4)).");

  m.def("write_tet_mesh", [](const std::filesystem::path& path, py::handle V, py::handle T, py::dict cell_fields, py::object labels) {
    const TetMesh mesh = mesh_of(V, T);
    TetMeshWriteOptions options;
    for (const auto& [name, values] : cell_fields) {
      const auto v = float_rows(values, "a cell field", 0);
      if (v.rows() != mesh.num_tets()) throw py::value_error("cell field '" + std::string(py::str(name)) + "' needs one value per tet");
      options.cell_fields.push_back({std::string(py::str(name)), std::vector<double>(v.data(), v.data() + v.size()), false});
    }
    if (!labels.is_none()) {
      const auto l = index_rows(labels, "labels", 0, -1);
      if (l.rows() != mesh.num_tets()) throw py::value_error("labels needs one label per tet");
      options.tet_labels.assign(l.data(), l.data() + l.size());
    }
    py::gil_scoped_release release;
    write_tet_mesh(path, mesh, options);
  }, py::arg("path"), py::arg("V"), py::arg("T"), py::arg("cell_fields") = py::dict(), py::arg("labels") = py::none(),
     "Writes a tet mesh by the path's extension. cell_fields: {name: float64 (m,)}; labels: int32 (m,) (e.g. pieces).");

  m.def("read_surface", [](const std::filesystem::path& path, const std::string& member) {
    TriangleSurface s;
    {
      py::gil_scoped_release release;
      s = member.empty() ? read_surface(path) : read_surface(path, member);
    }
    return surface_arrays(s);
  }, py::arg("path"), py::arg("member") = "",
     "Reads a triangle surface (.obj, .off, .ply, .stl, .vtp), or `member` of a .tar.gz archive. Returns (V, F int32 (k, 3)).");

  m.def("write_surface", [](const std::filesystem::path& path, py::handle V, py::handle F, bool binary) {
    const TriangleSurface s = surface_of(V, F);
    py::gil_scoped_release release;
    write_surface(path, s, SurfaceWriteOptions{binary});
  }, py::arg("path"), py::arg("V"), py::arg("F"), py::arg("binary") = false, "Writes a triangle surface by the path's extension.");

  m.def("write_series", [](const std::filesystem::path& pvd, const std::vector<std::pair<double, std::filesystem::path>>& entries) {
    std::vector<SeriesEntry> series;
    for (const auto& [time, file] : entries) series.push_back({time, file});
    write_series(pvd, series);
  }, py::arg("pvd"), py::arg("entries"),
     "Writes a ParaView collection (.pvd) of (time, file) entries, files relative to the .pvd's folder.");
  m.def("read_series", [](const std::filesystem::path& pvd) {
    std::vector<std::pair<double, std::filesystem::path>> out;
    for (const SeriesEntry& e : read_series(pvd)) out.emplace_back(e.time, e.file);
    return out;
  }, py::arg("pvd"), "Reads a .pvd collection: [(time, file)], files resolved against its folder.");

  m.def("make_grid", [](py::handle box_min, py::handle box_max, std::array<Index, 3> cells, int tets_per_cube) {
    return mesh_arrays(make_grid(box_of(box_min, box_max), cells, tets_per_cube));
  }, py::arg("box_min"), py::arg("box_max"), py::arg("cells"), py::arg("tets_per_cube") = 5,
     "A box of cells[0] x cells[1] x cells[2] cubes of 5 or 6 tets each. Returns (V, T).");

  m.def("make_bcc", [](py::handle box_min, py::handle box_max, double spacing) {
    return mesh_arrays(make_bcc(box_of(box_min, box_max), spacing));
  }, py::arg("box_min"), py::arg("box_max"), py::arg("spacing"), "A BCC lattice of cube size `spacing` covering the box. Returns (V, T).");

  py::class_<MeshQuality>(m, "MeshQuality", "Size and shape of a tet mesh (measure_quality).")
      .def_property_readonly("bbox_min", [](const MeshQuality& q) { return to_numpy(q.bbox_min); })
      .def_property_readonly("bbox_max", [](const MeshQuality& q) { return to_numpy(q.bbox_max); })
      .def_readonly("volume", &MeshQuality::volume)
      .def_readonly("min_volume", &MeshQuality::min_volume)
      .def_readonly("min_dihedral_degrees", &MeshQuality::min_dihedral_degrees)
      .def_readonly("max_dihedral_degrees", &MeshQuality::max_dihedral_degrees)
      .def_readonly("min_altitude", &MeshQuality::min_altitude)
      .def_readonly("num_unused_nodes", &MeshQuality::num_unused_nodes);
  m.def("measure_quality", [](py::handle V, py::handle T) { return measure_quality(mesh_of(V, T)); }, py::arg("V"), py::arg("T"),
        "Volume, bounding box, dihedral angles and smallest altitude of the mesh (V, T).");

  py::class_<SurfaceStats>(m, "SurfaceStats", "Area, enclosed volume and edge counts of a triangle surface (measure_surface).")
      .def_property_readonly("bbox_min", [](const SurfaceStats& q) { return to_numpy(q.bbox_min); })
      .def_property_readonly("bbox_max", [](const SurfaceStats& q) { return to_numpy(q.bbox_max); })
      .def_readonly("area", &SurfaceStats::area)
      .def_readonly("enclosed_volume", &SurfaceStats::enclosed_volume)
      .def_readonly("num_boundary_edges", &SurfaceStats::num_boundary_edges)
      .def_readonly("num_nonmanifold_edges", &SurfaceStats::num_nonmanifold_edges)
      .def_readonly("num_degenerate_triangles", &SurfaceStats::num_degenerate_triangles)
      .def_readonly("num_unbalanced_edges", &SurfaceStats::num_unbalanced_edges)
      .def_readonly("two_manifold", &SurfaceStats::two_manifold, "Every edge has exactly two triangles.")
      .def_readonly("balanced", &SurfaceStats::balanced,
                    "Every edge is used as often in each direction: closed and consistently oriented.");
  m.def("measure_surface", [](py::handle V, py::handle F) { return measure_surface(surface_of(V, F)); }, py::arg("V"), py::arg("F"),
        "Area, enclosed volume and edge counts of the surface (V float64 (n, 3), F int32 (k, 3)).");

  py::class_<SurfaceCheck>(m, "SurfaceCheck", "What combinatorics says about a surface (check_surface, EmbedReport.check).")
      .def_readonly("vertices", &SurfaceCheck::vertices)
      .def_readonly("triangles", &SurfaceCheck::triangles)
      .def_readonly("degenerate_triangles", &SurfaceCheck::degenerate_triangles)
      .def_readonly("unbalanced_edges", &SurfaceCheck::unbalanced_edges)
      .def_readonly("misoriented_edges", &SurfaceCheck::misoriented_edges)
      .def_readonly("nonmanifold_edges", &SurfaceCheck::nonmanifold_edges)
      .def_readonly("components", &SurfaceCheck::components)
      .def_property_readonly("balanced", &SurfaceCheck::balanced,
                             "Every edge is used as often in each direction (after welding): what embedding the inside needs.");
  m.def("check_surface", [](py::handle V, py::handle F) { return check_surface(surface_of(V, F)); }, py::arg("V"), py::arg("F"),
        "Welds equal vertices and counts unbalanced, misoriented and non-manifold edges and components: what embed checks.");
}

}  // namespace tetcut::python

PYBIND11_MODULE(_tetcut, m) {
  m.doc() = "tetcut's C++ library over numpy arrays (use the package tetcut).";
  tetcut::python::bind_meshes(m);
  tetcut::python::bind_cutting(m);
  tetcut::python::bind_sim(m);
}
