#include "arrays.hpp"

#include <cmath>

namespace tetcut::python {
namespace {

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string wanted(const char* dtype, int columns) {
  return std::string(dtype) + " array of shape " + (columns > 0 ? "(n, " + std::to_string(columns) + ")" : std::string("(n,)"));
}

// The array behind `value`, checked for dtype, shape and layout.
py::array checked(py::handle value, const char* name, const py::dtype& dtype, const char* dtype_name, int columns) {
  if (!py::isinstance<py::array>(value)) {
    throw py::type_error(std::string(name) + " must be a numpy " + wanted(dtype_name, columns) + ", not " +
                         std::string(py::str(py::type::handle_of(value).attr("__name__"))) + " (use numpy.asarray(" + name +
                         ", dtype=numpy." + dtype_name + "))");
  }
  py::array a = py::reinterpret_borrow<py::array>(value);
  if (!a.dtype().is(dtype)) {
    throw py::type_error(std::string(name) + " must be a " + wanted(dtype_name, columns) + ", not " +
                         std::string(py::str(a.dtype())) + " (use " + name + ".astype(numpy." + dtype_name + "))");
  }
  const bool shape_ok = columns > 0 ? a.ndim() == 2 && a.shape(1) == columns : a.ndim() == 1;
  if (!shape_ok) throw py::value_error(std::string(name) + " must be a " + wanted(dtype_name, columns) + ", not " + shape_of(a));
  if (!(a.flags() & py::array::c_style)) {
    throw py::value_error(std::string(name) + " must be C-contiguous (use numpy.ascontiguousarray(" + name + "))");
  }
  return a;
}

}  // namespace

Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> float_rows(py::handle value, const char* name, int columns) {
  const py::array a = checked(value, name, py::dtype::of<double>(), "float64", columns);
  const Eigen::Index rows = a.shape(0), cols = columns > 0 ? columns : 1;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(rows, cols);
  std::copy_n(static_cast<const double*>(a.data()), rows * cols, m.data());
  return m;
}

Points points(py::handle value, const char* name) { return float_rows(value, name, 3); }

Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> index_rows(py::handle value, const char* name, int columns,
                                                                                 std::int64_t bound) {
  const py::array a = checked(value, name, py::dtype::of<std::int32_t>(), "int32", columns);
  const Eigen::Index rows = a.shape(0), cols = columns > 0 ? columns : 1;
  Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(rows, cols);
  std::copy_n(static_cast<const std::int32_t*>(a.data()), rows * cols, m.data());
  if (bound >= 0) {
    for (Eigen::Index r = 0; r < rows; ++r) {
      for (Eigen::Index c = 0; c < cols; ++c) {
        if (m(r, c) < 0 || m(r, c) >= bound) {
          throw py::value_error(std::string(name) + "[" + std::to_string(r) + (columns > 0 ? ", " + std::to_string(c) : "") + "] is " +
                                std::to_string(m(r, c)) + ": indices must be in [0, " + std::to_string(bound) + ")");
        }
      }
    }
  }
  return m;
}

Tets tets(py::handle value, const char* name, std::int64_t num_nodes) { return index_rows(value, name, 4, num_nodes); }

std::vector<std::array<Index, 4>> tet_rows(py::handle value, const char* name, std::int64_t num_nodes) {
  const Tets t = tets(value, name, num_nodes);
  std::vector<std::array<Index, 4>> rows(static_cast<std::size_t>(t.rows()));
  for (Eigen::Index r = 0; r < t.rows(); ++r) {
    for (int k = 0; k < 4; ++k) rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)] = t(r, k);
  }
  return rows;
}
Triangles triangles(py::handle value, const char* name, std::int64_t num_vertices) { return index_rows(value, name, 3, num_vertices); }

Vec3 vec3(py::handle value, const char* name) {
  if (py::isinstance<py::str>(value) || (!py::isinstance<py::sequence>(value) && !py::isinstance<py::array>(value))) {
    throw py::type_error(std::string(name) + " must be three numbers");
  }
  const py::object object = py::reinterpret_borrow<py::object>(value);
  if (py::len(object) != 3) throw py::value_error(std::string(name) + " must be three numbers, not " + std::to_string(py::len(object)));
  Vec3 v;
  for (int c = 0; c < 3; ++c) {
    try {
      v[c] = py::cast<double>(object[py::int_(c)]);
    } catch (const py::cast_error&) {
      throw py::type_error(std::string(name) + " must be three numbers");
    }
    if (!std::isfinite(v[c])) throw py::value_error(std::string(name) + " must be three finite numbers");
  }
  return v;
}

TetMesh mesh_of(py::handle V, py::handle T) {
  Points rest = points(V, "V");
  Tets t = tets(T, "T", rest.rows());
  return TetMesh(std::move(rest), std::move(t));
}

TriangleSurface surface_of(py::handle V, py::handle F) {
  TriangleSurface s;
  s.vertices = points(V, "V");
  s.triangles = triangles(F, "F", s.vertices.rows());
  return s;
}

py::tuple mesh_arrays(const TetMesh& mesh) { return py::make_tuple(to_numpy(mesh.rest()), to_numpy(mesh.tets())); }
py::tuple surface_arrays(const TriangleSurface& s) { return py::make_tuple(to_numpy(s.vertices), to_numpy(s.triangles)); }

py::array_t<double> to_numpy(const Vec3& v) {
  py::array_t<double> out(3);
  std::copy(v.data(), v.data() + 3, out.mutable_data());
  return out;
}

}  // namespace tetcut::python
