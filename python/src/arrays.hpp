#pragma once
// numpy arrays in and out of the library's Eigen buffers, checked: a wrong type, dtype, shape or
// layout is a TypeError or ValueError naming the argument and what it must be, never a crash or a
// silent conversion. In: V float64 (n, 3), T int32 (m, 4), F int32 (k, 3), C-contiguous.
// Out: fresh arrays that own their data (copies: the library's buffers may change under them).

#include <tetcut/surface.hpp>
#include <tetcut/tet_mesh.hpp>
#include <tetcut/types.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace tetcut::python {

namespace py = pybind11;

/// Float64 rows of `columns` numbers (`columns` 0: a 1-D array), finite or not (the library
/// checks finiteness where it matters and names the element).
Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> float_rows(py::handle array, const char* name, int columns);
Points points(py::handle array, const char* name);
/// Int32 rows of `columns` indices (0: 1-D), each in [0, bound) unless bound < 0.
Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> index_rows(py::handle array, const char* name, int columns,
                                                                                 std::int64_t bound);
Tets tets(py::handle array, const char* name, std::int64_t num_nodes);
/// The same as the rows Cutter::tet_nodes gives (what the surface and collision functions take).
std::vector<std::array<Index, 4>> tet_rows(py::handle array, const char* name, std::int64_t num_nodes);
Triangles triangles(py::handle array, const char* name, std::int64_t num_vertices);
/// A point: any sequence of three finite numbers (a tuple, a list, a numpy array).
Vec3 vec3(py::handle value, const char* name);

/// A tet mesh from V and T (the library checks finiteness and positive volumes), a surface from
/// V and F.
TetMesh mesh_of(py::handle V, py::handle T);
TriangleSurface surface_of(py::handle V, py::handle F);
/// (V, T) and (V, F) out.
py::tuple mesh_arrays(const TetMesh& mesh);
py::tuple surface_arrays(const TriangleSurface& s);

/// Copies out.
template <typename Matrix>
py::array_t<typename Matrix::Scalar> to_numpy(const Matrix& m) {
  using Scalar = typename Matrix::Scalar;
  py::array_t<Scalar> out({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto view = out.template mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) view(r, c) = m(r, c);
  }
  return out;
}
template <typename T>
py::array_t<T> to_numpy(std::span<const T> values) {
  py::array_t<T> out(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}
template <typename T>
py::array_t<T> to_numpy(const std::vector<T>& values) {
  return to_numpy(std::span<const T>(values));
}
template <std::size_t N>
py::array_t<Index> to_numpy(const std::vector<std::array<Index, N>>& rows) {
  py::array_t<Index> out({static_cast<py::ssize_t>(rows.size()), static_cast<py::ssize_t>(N)});
  Index* data = out.mutable_data();
  for (std::size_t r = 0; r < rows.size(); ++r) std::copy(rows[r].begin(), rows[r].end(), data + N * r);
  return out;
}
py::array_t<double> to_numpy(const Vec3& v);

}  // namespace tetcut::python
