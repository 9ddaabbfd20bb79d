#include "common.hpp"

#include <tetcut/error.hpp>

#include <system_error>

namespace tetcut::cli {

void check_not_input(const fs::path& output, const fs::path& input) {
  std::error_code ec;
  if (fs::exists(output, ec) && fs::equivalent(output, input, ec)) {
    throw Error(ErrorKind::kInvalidArgument, "the output would overwrite the input file", output.string());
  }
}

void check_tet_mesh_output(const fs::path& path) {
  if (file_kind(path) != FileKind::kTetMesh) {
    throw Error(ErrorKind::kInvalidArgument,
                "output must be a tet mesh file (" + supported_tet_mesh_extensions() + ")", path.string());
  }
}

void check_surface_output(const fs::path& path) {
  if (file_kind(path) != FileKind::kSurface) {
    throw Error(ErrorKind::kInvalidArgument, "output must be a surface file (" + supported_surface_extensions() + ")",
                path.string());
  }
}

Box box_from(const std::vector<double>& corners) {
  Box box;
  box.min = Vec3(corners[0], corners[1], corners[2]);
  box.max = Vec3(corners[3], corners[4], corners[5]);
  return box;
}

}  // namespace tetcut::cli
