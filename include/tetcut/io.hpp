#pragma once
// Reading and writing tet meshes and triangle surfaces. The format follows the file extension:
//
//   tet meshes  .mesh (Medit, ASCII)   .msh (Gmsh 2.2 / 4.1, ASCII)   .node/.ele (TetGen)
//               .vtu (VTK XML: ascii, base64, appended raw, zlib)   .vtk (legacy VTK, ASCII/binary)
//   surfaces    .obj   .off   .ply (ASCII / binary)   .stl (ASCII / binary)   .vtp (VTK XML PolyData)
//
// Readers throw tetcut::Error naming the file, the line (text formats) and the problem. Writers
// write to a temporary file beside the target and rename it into place when complete.

#include <tetcut/surface.hpp>
#include <tetcut/tet_mesh.hpp>

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace tetcut {

/// One value per tet, written as a cell array where the format has them (.vtu, .vtk).
struct CellField {
  std::string name;
  std::vector<double> values;
  bool integer = false;  ///< written as Int64 when true
};

struct TetMeshWriteOptions {
  /// Gmsh file version for .msh: 41 (4.1) or 22 (2.2).
  int gmsh_version = 41;
  /// Write current (deformed) positions instead of rest positions.
  bool current_positions = false;
  std::vector<CellField> cell_fields;
  /// Optional integer label per tet (e.g. its piece), written where a format has one: the Medit
  /// tetrahedron reference, and the Gmsh physical and elementary tags (label + 1, as Gmsh tags
  /// are positive; in 4.1 one volume entity per label). Empty: no labels.
  std::vector<Index> tet_labels;
};

struct SurfaceWriteOptions {
  /// PLY: binary little-endian instead of ASCII. STL: binary (single precision, as the format
  /// requires) instead of ASCII with full double precision.
  bool binary = false;
};

enum class FileKind { kTetMesh, kSurface, kUnknown };

/// What a path holds, judged by its extension.
FileKind file_kind(const std::filesystem::path& path);

/// Reads a tet mesh. For TetGen, `path` may name the .node or the .ele file; both are read.
TetMesh read_tet_mesh(const std::filesystem::path& path);
/// Reads the positions of a deformed configuration of `reference`: a tet mesh file with the same
/// node count and the same tets, whose positions are the deformed ones. Tets may be inverted there
/// (nothing checks their orientation). Throws Error(kInvalidInput) naming the file when the nodes or
/// tets differ or a coordinate is not finite.
Points read_deformed_positions(const std::filesystem::path& path, const TetMesh& reference);

/// Writes a tet mesh. For TetGen, both `stem.node` and `stem.ele` are written.
void write_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh, const TetMeshWriteOptions& options = {});

/// Reads a triangle surface. Polygons with more than three corners are split into a fan of
/// triangles around their first corner. STL vertices are shared where coordinates are
/// bit-for-bit equal (STL stores each triangle's corners separately).
TriangleSurface read_surface(const std::filesystem::path& path);
/// Reads a surface stored as `member` (its path inside the archive) of a .tar.gz archive, such
/// as the real scans Debian's libcgal-demo ships in /usr/share/doc/libcgal-dev/data.tar.gz.
TriangleSurface read_surface(const std::filesystem::path& archive, const std::string& member);
void write_surface(const std::filesystem::path& path, const TriangleSurface& surface,
                   const SurfaceWriteOptions& options = {});

/// One dataset of a time series (a ParaView collection, .pvd): its time and its file.
struct SeriesEntry {
  double time = 0;
  std::filesystem::path file;
};
/// Reads a .pvd collection in file order. Each entry's file is resolved against the .pvd's folder
/// (as ParaView does). Throws Error(kInvalidInput) naming the file and line for malformed XML, a
/// DataSet without a file or with a timestep that is not a finite number, or no DataSet at all.
std::vector<SeriesEntry> read_series(const std::filesystem::path& pvd);
/// Writes a .pvd collection; files are written as given (relative to the .pvd's folder, usually).
void write_series(const std::filesystem::path& pvd, const std::vector<SeriesEntry>& entries);

/// Writes text to `path` through a temporary file renamed into place, like every writer here.
void write_text_file(const std::filesystem::path& path, std::string_view text);

/// Reads polylines (cuts of a planar mesh), each as its points (|P| x 3): OBJ `l` elements (.obj),
/// legacy VTK POLYDATA LINES in ASCII (.vtk), VTK XML PolyData Lines (.vtp), or plain text (.txt,
/// .xy, .xyz): one point "x y" or "x y z" per line, a blank line between polylines, '#' comments.
/// A polyline closes by repeating its first point. Missing z coordinates are 0. Throws
/// Error(kInvalidInput) naming the file and line for a malformed or non-finite point, an index out
/// of range, a polyline of one point, or a file with no polyline at all.
std::vector<Points> read_polylines(const std::filesystem::path& path);
/// Writes segments (|S| x 2 ids into `points`) as OBJ `l` elements (.obj) or legacy VTK LINES (.vtk).
void write_polylines(const std::filesystem::path& path, const Points& points, const Edges& segments);
std::string supported_polyline_extensions();

/// Lists the extensions each kind accepts, for help texts.
std::string supported_tet_mesh_extensions();
std::string supported_surface_extensions();

}  // namespace tetcut
