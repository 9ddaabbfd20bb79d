#include "io/files.hpp"

#include <tetcut/error.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <random>
#include <system_error>

namespace tetcut::io {

std::string read_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw Error(ErrorKind::kIo, "is a directory, not a file", path.string());
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::kIo, std::string("cannot open for reading: ") + std::strerror(errno), path.string());
  std::string bytes;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw Error(ErrorKind::kIo, "cannot determine the file size", path.string());
  bytes.resize(static_cast<std::size_t>(size));
  in.seekg(0, std::ios::beg);
  in.read(bytes.data(), size);
  if (!in) throw Error(ErrorKind::kIo, "read failed", path.string());
  return bytes;
}

AtomicOutput::AtomicOutput(std::filesystem::path target, bool binary) : target_(std::move(target)) {
  std::random_device entropy;
  const std::string suffix = ".tmp" + std::to_string(entropy() % 1000000);
  temp_ = target_;
  temp_ += suffix;
  out_.open(temp_, std::ios::out | std::ios::trunc | (binary ? std::ios::binary : std::ios::openmode{}));
  if (!out_) {
    throw Error(ErrorKind::kIo, std::string("cannot open for writing: ") + std::strerror(errno), target_.string());
  }
}

AtomicOutput::~AtomicOutput() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
}

void AtomicOutput::commit() {
  out_.flush();
  out_.close();
  if (out_.fail()) throw Error(ErrorKind::kIo, "write failed (disk full?)", target_.string());
  std::error_code ec;
  std::filesystem::rename(temp_, target_, ec);
  if (ec) throw Error(ErrorKind::kIo, "cannot rename the finished file into place: " + ec.message(), target_.string());
  committed_ = true;
}

std::string extension_of(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace tetcut::io
