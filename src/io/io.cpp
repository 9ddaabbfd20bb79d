#include <tetcut/error.hpp>
#include <tetcut/io.hpp>

#include "io/files.hpp"
#include "io/formats.hpp"

namespace tetcut {
namespace {

constexpr const char* kTetMeshExtensions[] = {".mesh", ".msh", ".node", ".ele", ".vtu", ".vtk"};
constexpr const char* kSurfaceExtensions[] = {".obj", ".off", ".ply", ".stl", ".vtp"};

std::string join(const char* const* begin, const char* const* end) {
  std::string out;
  for (const char* const* p = begin; p != end; ++p) {
    if (!out.empty()) out += ' ';
    out += *p;
  }
  return out;
}

[[noreturn]] void unknown_extension(const std::filesystem::path& path, const char* kind, const std::string& allowed) {
  throw Error(ErrorKind::kInvalidArgument,
              "cannot tell the " + std::string(kind) + " format from the extension '" + io::extension_of(path) +
                  "' (supported: " + allowed + ")",
              path.string());
}

const Points& positions(const TetMesh& mesh, const TetMeshWriteOptions& options) {
  return options.current_positions ? mesh.current() : mesh.rest();
}

}  // namespace

std::string supported_tet_mesh_extensions() {
  return join(std::begin(kTetMeshExtensions), std::end(kTetMeshExtensions));
}
std::string supported_surface_extensions() {
  return join(std::begin(kSurfaceExtensions), std::end(kSurfaceExtensions));
}

FileKind file_kind(const std::filesystem::path& path) {
  const std::string ext = io::extension_of(path);
  for (const char* e : kTetMeshExtensions) {
    if (ext == e) return FileKind::kTetMesh;
  }
  for (const char* e : kSurfaceExtensions) {
    if (ext == e) return FileKind::kSurface;
  }
  return FileKind::kUnknown;
}

namespace {

// Parses a tet mesh file by its extension, without building (and so without validating) a TetMesh.
io::TetMeshData parse_tet_mesh(const std::filesystem::path& path, std::string* source) {
  const std::string ext = io::extension_of(path);
  *source = path.string();
  if (ext == ".node" || ext == ".ele") {
    std::filesystem::path node_path = path, ele_path = path;
    node_path.replace_extension(".node");
    ele_path.replace_extension(".ele");
    io::TetgenNodes nodes = io::read_tetgen_nodes(io::read_file(node_path), node_path.string());
    *source = ele_path.string();
    return io::read_tetgen_elements(std::move(nodes), io::read_file(ele_path), ele_path.string());
  }
  const std::string bytes = io::read_file(path);
  if (ext == ".mesh") return io::read_medit(bytes, *source);
  if (ext == ".msh") return io::read_gmsh(bytes, *source);
  if (ext == ".vtu") return io::read_vtu(bytes, *source);
  if (ext == ".vtk") return io::read_vtk_legacy(bytes, *source);
  unknown_extension(path, "tet mesh", supported_tet_mesh_extensions());
}

}  // namespace

TetMesh read_tet_mesh(const std::filesystem::path& path) {
  std::string source;
  io::TetMeshData data = parse_tet_mesh(path, &source);
  return TetMesh(std::move(data.points), std::move(data.tets), source, data.tet_lines);
}

Points read_deformed_positions(const std::filesystem::path& path, const TetMesh& reference) {
  std::string source;
  io::TetMeshData data = parse_tet_mesh(path, &source);
  if (data.points.rows() != reference.num_nodes()) {
    throw Error(ErrorKind::kInvalidInput,
                "the deformed mesh has " + std::to_string(data.points.rows()) + " nodes, the mesh to cut " +
                    std::to_string(reference.num_nodes()),
                source);
  }
  if (data.tets.rows() != reference.num_tets()) {
    throw Error(ErrorKind::kInvalidInput,
                "the deformed mesh has " + std::to_string(data.tets.rows()) + " tets, the mesh to cut " +
                    std::to_string(reference.num_tets()),
                source);
  }
  for (Index t = 0; t < reference.num_tets(); ++t) {
    if (data.tets.row(t) != reference.tets().row(t)) {
      throw Error(ErrorKind::kInvalidInput,
                  "tet " + std::to_string(t) + " has other nodes than in the mesh to cut",
                  source, data.tet_lines.empty() ? 0 : data.tet_lines[t]);
    }
  }
  for (Index n = 0; n < data.points.rows(); ++n) {
    if (!data.points.row(n).allFinite()) {
      throw Error(ErrorKind::kInvalidInput, "node " + std::to_string(n) + " has a coordinate that is not finite", source);
    }
  }
  return std::move(data.points);
}

void write_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh, const TetMeshWriteOptions& options) {
  if (!options.tet_labels.empty() && static_cast<Index>(options.tet_labels.size()) != mesh.num_tets()) {
    throw Error(ErrorKind::kInvalidArgument, "tet labels: " + std::to_string(options.tet_labels.size()) +
                                                 " values for " + std::to_string(mesh.num_tets()) + " tets");
  }
  for (const CellField& field : options.cell_fields) {
    if (static_cast<Index>(field.values.size()) != mesh.num_tets()) {
      throw Error(ErrorKind::kInvalidArgument, "cell field '" + field.name + "' has " +
                                                   std::to_string(field.values.size()) + " values for " +
                                                   std::to_string(mesh.num_tets()) + " tets");
    }
  }
  const std::string ext = io::extension_of(path);
  const Points& points = positions(mesh, options);
  if (ext == ".node" || ext == ".ele") {
    std::filesystem::path node_path = path, ele_path = path;
    node_path.replace_extension(".node");
    ele_path.replace_extension(".ele");
    io::AtomicOutput node_out(node_path), ele_out(ele_path);
    io::write_tetgen_node(node_out.stream(), points);
    io::write_tetgen_ele(ele_out.stream(), mesh.tets());
    node_out.commit();
    ele_out.commit();
    return;
  }
  if (ext != ".mesh" && ext != ".msh" && ext != ".vtu" && ext != ".vtk") {
    unknown_extension(path, "tet mesh", supported_tet_mesh_extensions());
  }
  io::AtomicOutput out(path, ext == ".vtu");
  if (ext == ".mesh") io::write_medit(out.stream(), points, mesh.tets(), options.tet_labels);
  if (ext == ".msh") io::write_gmsh(out.stream(), points, mesh.tets(), options.gmsh_version, options.tet_labels);
  if (ext == ".vtu") io::write_vtu(out.stream(), points, mesh.tets(), options.cell_fields);
  if (ext == ".vtk") io::write_vtk_legacy(out.stream(), points, mesh.tets(), options.cell_fields);
  out.commit();
}

void write_text_file(const std::filesystem::path& path, std::string_view text) {
  io::AtomicOutput out(path);
  out.stream() << text;
  out.commit();
}

std::vector<SeriesEntry> read_series(const std::filesystem::path& pvd) {
  std::vector<SeriesEntry> entries = io::read_pvd(io::read_file(pvd), pvd.string());
  for (SeriesEntry& entry : entries) {
    if (entry.file.is_relative()) entry.file = pvd.parent_path() / entry.file;
  }
  return entries;
}

void write_series(const std::filesystem::path& pvd, const std::vector<SeriesEntry>& entries) {
  io::AtomicOutput out(pvd);
  io::write_pvd(out.stream(), entries);
  out.commit();
}

namespace io {

TriangleSurface read_surface_bytes(std::string_view bytes, const std::filesystem::path& name, const std::string& source) {
  if (file_kind(name) != FileKind::kSurface) unknown_extension(name, "surface", supported_surface_extensions());
  const std::string ext = extension_of(name);
  if (ext == ".obj") return read_obj(bytes, source);
  if (ext == ".off") return read_off(bytes, source);
  if (ext == ".ply") return read_ply(bytes, source);
  if (ext == ".stl") return read_stl(bytes, source);
  return read_vtp(bytes, source);
}

}  // namespace io

TriangleSurface read_surface(const std::filesystem::path& path) {
  if (file_kind(path) != FileKind::kSurface) unknown_extension(path, "surface", supported_surface_extensions());
  return io::read_surface_bytes(io::read_file(path), path, path.string());
}

void write_surface(const std::filesystem::path& path, const TriangleSurface& surface, const SurfaceWriteOptions& options) {
  const std::string ext = io::extension_of(path);
  if (file_kind(path) != FileKind::kSurface) unknown_extension(path, "surface", supported_surface_extensions());
  io::AtomicOutput out(path, options.binary);
  if (ext == ".obj") io::write_obj(out.stream(), surface);
  if (ext == ".off") io::write_off(out.stream(), surface);
  if (ext == ".ply") io::write_ply(out.stream(), surface, options.binary);
  if (ext == ".stl") io::write_stl(out.stream(), surface, options.binary);
  if (ext == ".vtp") io::write_vtp(out.stream(), surface.vertices, surface.triangles);
  out.commit();
}

}  // namespace tetcut
