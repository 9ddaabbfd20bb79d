// Members of .tar.gz archives (POSIX ustar, GNU long names), read by streaming through zlib: the
// archive is decompressed up to the member and no further, nothing is unpacked to disk. Debian
// ships real scanned meshes this way (libcgal-demo's data.tar.gz), and a scene may point into one.

#include <tetcut/error.hpp>
#include <tetcut/io.hpp>

#include <zlib.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "io/formats.hpp"

namespace tetcut {
namespace io {
namespace {

constexpr std::size_t kBlock = 512;

struct GzCloser {
  void operator()(gzFile_s* file) const { gzclose(file); }
};

// A header's numeric field: octal digits ended by NUL or space (GNU's base-256 form for sizes
// over 8 GiB is refused: no mesh is that large).
bool octal_field(const char* field, std::size_t width, std::uint64_t& value) {
  value = 0;
  std::size_t i = 0;
  while (i < width && field[i] == ' ') ++i;
  for (; i < width && field[i] >= '0' && field[i] <= '7'; ++i) value = value * 8 + static_cast<std::uint64_t>(field[i] - '0');
  return i == width || field[i] == '\0' || field[i] == ' ';
}

std::string field_string(const char* field, std::size_t width) {
  std::size_t n = 0;
  while (n < width && field[n] != '\0') ++n;
  return std::string(field, n);
}

}  // namespace

std::string read_archive_member(const std::filesystem::path& archive, const std::string& member) {
  const std::string where = archive.string();
  std::unique_ptr<gzFile_s, GzCloser> in(gzopen(where.c_str(), "rb"));
  if (!in) throw Error(ErrorKind::kIo, "cannot open the archive", where);
  gzbuffer(in.get(), 1 << 16);
  const auto read = [&](char* out, std::size_t bytes) {
    const int got = gzread(in.get(), out, static_cast<unsigned>(bytes));
    if (got < 0 || static_cast<std::size_t>(got) != bytes) {
      throw Error(ErrorKind::kInvalidInput, "truncated or corrupt .tar.gz archive (looking for " + member + ")", where);
    }
  };
  std::array<char, kBlock> header{};
  std::string long_name;
  // Each entry: a 512-byte header, then its data padded to whole blocks. O(archive up to the member).
  for (;;) {
    read(header.data(), kBlock);
    if (header[0] == '\0') break;  // the two zero blocks that end an archive
    std::uint64_t size = 0;
    if (!octal_field(header.data() + 124, 12, size)) throw Error(ErrorKind::kInvalidInput, "a tar header with a malformed size", where);
    std::string name = field_string(header.data(), 100);
    if (field_string(header.data() + 257, 6) == "ustar") {
      const std::string prefix = field_string(header.data() + 345, 155);
      if (!prefix.empty()) name = prefix + "/" + name;
    }
    if (!long_name.empty()) name = std::move(long_name), long_name.clear();
    const char type = header[156];
    const std::uint64_t padded = (size + kBlock - 1) / kBlock * kBlock;
    const bool wanted = (type == '0' || type == '\0') && (name == member || name == "./" + member);
    if (type == 'L' || wanted) {
      if (size > (std::uint64_t{1} << 32)) throw Error(ErrorKind::kInvalidInput, "a tar member over 4 GiB: " + name, where);
      std::string data(static_cast<std::size_t>(padded), '\0');
      read(data.data(), data.size());
      data.resize(static_cast<std::size_t>(size));
      if (wanted) return data;
      long_name = field_string(data.data(), data.size());
      continue;
    }
    if (padded > 0 && gzseek(in.get(), static_cast<z_off_t>(padded), SEEK_CUR) < 0) {
      throw Error(ErrorKind::kInvalidInput, "truncated or corrupt .tar.gz archive (looking for " + member + ")", where);
    }
  }
  throw Error(ErrorKind::kInvalidInput, "the archive holds no file " + member, where);
}

}  // namespace io

TriangleSurface read_surface(const std::filesystem::path& archive, const std::string& member) {
  const std::string bytes = io::read_archive_member(archive, member);
  return io::read_surface_bytes(bytes, member, archive.string() + ": " + member);
}

}  // namespace tetcut
