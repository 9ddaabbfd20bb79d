#include <tetcut/error.hpp>

#include <utility>

namespace tetcut {
namespace {

std::string format_what(const std::string& message, const std::string& file, std::int64_t line) {
  if (file.empty()) return message;
  if (line > 0) return file + ":" + std::to_string(line) + ": " + message;
  return file + ": " + message;
}

}  // namespace

Error::Error(ErrorKind kind, std::string message, std::string file, std::int64_t line)
    : std::runtime_error(format_what(message, file, line)),
      kind_(kind),
      message_(std::move(message)),
      file_(std::move(file)),
      line_(line) {}

}  // namespace tetcut
