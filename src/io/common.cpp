#include <tetcut/error.hpp>

#include <charconv>

#include "io/formats.hpp"

namespace tetcut::io {

void write_real(std::ostream& out, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.write(buffer, result.ptr - buffer);
}

Points to_points(const std::vector<double>& xyz) {
  Points points(static_cast<Eigen::Index>(xyz.size() / 3), 3);
  std::copy(xyz.begin(), xyz.end(), points.data());
  return points;
}

Tets to_tets(const std::vector<Index>& ids) {
  Tets tets(static_cast<Eigen::Index>(ids.size() / 4), 4);
  std::copy(ids.begin(), ids.end(), tets.data());
  return tets;
}

Triangles to_triangles(const std::vector<Index>& ids) {
  Triangles triangles(static_cast<Eigen::Index>(ids.size() / 3), 3);
  std::copy(ids.begin(), ids.end(), triangles.data());
  return triangles;
}

void check_count(std::int64_t count, std::size_t file_size, std::size_t min_bytes_per_item, const char* what,
                 const std::string& source, std::int64_t line) {
  if (count < 0) {
    throw Error(ErrorKind::kInvalidInput, std::string("negative ") + what + " count " + std::to_string(count), source,
                line);
  }
  if (static_cast<std::uint64_t>(count) * min_bytes_per_item > file_size) {
    throw Error(ErrorKind::kInvalidInput,
                std::string("the header announces ") + std::to_string(count) + " " + what +
                    ", more than a file of " + std::to_string(file_size) + " bytes can hold (truncated file?)",
                source, line);
  }
}

}  // namespace tetcut::io
