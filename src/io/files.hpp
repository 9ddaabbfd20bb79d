#pragma once
// Whole-file reads and atomic writes: an output is written to a temporary file beside its target
// and renamed into place only when complete, so a failure never leaves a half-written file.

#include <filesystem>
#include <fstream>
#include <string>

namespace tetcut::io {

/// The whole file as bytes; throws Error(kIo) naming the file when it cannot be read.
std::string read_file(const std::filesystem::path& path);

class AtomicOutput {
 public:
  explicit AtomicOutput(std::filesystem::path target, bool binary = false);
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;
  /// Removes the temporary file unless commit() succeeded.
  ~AtomicOutput();

  std::ostream& stream() { return out_; }
  /// Flushes, closes and renames the temporary file onto the target.
  void commit();

 private:
  std::filesystem::path target_;
  std::filesystem::path temp_;
  std::ofstream out_;
  bool committed_ = false;
};

/// Lower-case extension with the dot (".vtu"), or "" when there is none.
std::string extension_of(const std::filesystem::path& path);

}  // namespace tetcut::io
