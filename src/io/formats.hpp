#pragma once
// Per-format readers and writers behind tetcut/io.hpp. Readers parse bytes already in memory;
// writers write to a stream. `source` names the file in error messages.

#include <tetcut/io.hpp>

#include <cstdint>
#include <functional>
#include <ostream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace tetcut::io {

class TextScanner;

/// VTK's cell type number for a linear tetrahedron (legacy VTK and VTU alike).
constexpr int kVtkTetra = 10;

/// A tet mesh as parsed, before validation by the TetMesh constructor.
struct TetMeshData {
  Points points;
  Tets tets;
  std::vector<std::int64_t> tet_lines;  ///< source line of each tet; empty for binary data
};

TetMeshData read_medit(std::string_view text, const std::string& source);
void write_medit(std::ostream& out, const Points& points, const Tets& tets, const std::vector<Index>& labels);

TetMeshData read_gmsh(std::string_view text, const std::string& source);
void write_gmsh(std::ostream& out, const Points& points, const Tets& tets, int version, const std::vector<Index>& labels);

/// TetGen: parse the .node file first, then the .ele file against its node numbering.
struct TetgenNodes {
  std::vector<double> xyz;
  std::unordered_map<std::int64_t, Index> node_of_id;
  std::string source;
};
TetgenNodes read_tetgen_nodes(std::string_view node_text, const std::string& node_source);
TetMeshData read_tetgen_elements(TetgenNodes nodes, std::string_view ele_text, const std::string& ele_source);
void write_tetgen_node(std::ostream& out, const Points& points);
void write_tetgen_ele(std::ostream& out, const Tets& tets);

TetMeshData read_vtu(std::string_view bytes, const std::string& source);
void write_vtu(std::ostream& out, const Points& points, const Tets& tets, const std::vector<CellField>& fields);
/// VTK XML PolyData: a triangle surface (polygons read as fans).
TriangleSurface read_vtp(std::string_view bytes, const std::string& source);
void write_vtp(std::ostream& out, const Points& points, const Triangles& triangles);
/// The Lines of VTK XML PolyData, each polyline as its points.
std::vector<Points> read_vtp_lines(std::string_view bytes, const std::string& source);
std::vector<SeriesEntry> read_pvd(std::string_view bytes, const std::string& source);
void write_pvd(std::ostream& out, const std::vector<SeriesEntry>& entries);

TetMeshData read_vtk_legacy(std::string_view bytes, const std::string& source);
void write_vtk_legacy(std::ostream& out, const Points& points, const Tets& tets, const std::vector<CellField>& fields);

TriangleSurface read_obj(std::string_view text, const std::string& source);
/// The rest of an OBJ `v` line: three finite coordinates appended to `xyz`; `fail` reports.
void read_obj_vertex(TextScanner& in, const std::function<void(const std::string&)>& fail, std::vector<double>* xyz);
/// The rest of an OBJ `f` or `l` line: vertex indices (1-based, or negative from the end; "i/t/n"
/// forms), resolved against the `defined` vertices before it and appended to `ids`. `item` and
/// `element` name a corner and the line in messages ("face corner", "face").
void read_obj_indices(TextScanner& in, const std::function<void(const std::string&)>& fail, const std::string& item,
                      const std::string& element, std::int64_t defined, std::vector<Index>* ids);
void write_obj(std::ostream& out, const TriangleSurface& surface);
TriangleSurface read_off(std::string_view text, const std::string& source);
void write_off(std::ostream& out, const TriangleSurface& surface);
TriangleSurface read_ply(std::string_view bytes, const std::string& source);
void write_ply(std::ostream& out, const TriangleSurface& surface, bool binary);
TriangleSurface read_stl(std::string_view bytes, const std::string& source);
/// A surface file's bytes, in the format its name's extension says; `source` names it in errors.
TriangleSurface read_surface_bytes(std::string_view bytes, const std::filesystem::path& name, const std::string& source);
/// One file of a .tar.gz archive, decompressed as far as it and no further. Throws
/// Error(kInvalidInput) naming the archive when it holds no such file or is corrupt.
std::string read_archive_member(const std::filesystem::path& archive, const std::string& member);
void write_stl(std::ostream& out, const TriangleSurface& surface, bool binary);

/// Writes `value` in the shortest decimal form that reads back to the same double.
void write_real(std::ostream& out, double value);

/// Copies parsed rows into a |rows| x C Eigen buffer.
Points to_points(const std::vector<double>& xyz);
Tets to_tets(const std::vector<Index>& ids);
Triangles to_triangles(const std::vector<Index>& ids);

/// Fails with a message naming `source` when a count read from a header is negative or
/// implausibly large for the file (each item needs at least `min_bytes_per_item` bytes), so a
/// corrupt count cannot make us allocate gigabytes.
void check_count(std::int64_t count, std::size_t file_size, std::size_t min_bytes_per_item, const char* what,
                 const std::string& source, std::int64_t line);

}  // namespace tetcut::io
