#pragma once
// The one exception type the library throws. The library never prints and never exits: every
// failure reaches the caller as a tetcut::Error, which names the file and line where it can.

#include <cstdint>
#include <stdexcept>
#include <string>

namespace tetcut {

enum class ErrorKind {
  kInvalidInput,     ///< The data is malformed or violates an invariant (bad count, NaN, inverted tet).
  kIo,               ///< The file system refused: cannot open, read, write or rename.
  kUnsupported,      ///< Well-formed data in a variant we do not handle (e.g. binary Gmsh).
  kInvalidArgument,  ///< The caller passed a bad parameter (negative spacing, unknown extension).
  /// A broken invariant inside the library: a bug, never the caller's fault (report it with the
  /// input). The CLI exits with 1 for it, as for any unexpected failure.
  kInternal,
};

class Error : public std::runtime_error {
 public:
  /// `file` and `line` are optional context; line 0 means "no line" (binary formats, whole-file checks).
  Error(ErrorKind kind, std::string message, std::string file = {}, std::int64_t line = 0);

  ErrorKind kind() const noexcept { return kind_; }
  /// The message without the file and line prefix.
  const std::string& message() const noexcept { return message_; }
  const std::string& file() const noexcept { return file_; }
  std::int64_t line() const noexcept { return line_; }

 private:
  ErrorKind kind_;
  std::string message_;
  std::string file_;
  std::int64_t line_;
};

}  // namespace tetcut
