#pragma once
// A broken invariant inside the library: a bug, never the caller's fault. It reaches callers as the
// library's one exception type (Error, kind kInternal), which the CLI reports as an internal error
// (exit code 1) and Python as kind 'internal'.

#include <tetcut/error.hpp>

#include <string>
#include <string_view>

namespace tetcut {

/// Throws Error(kInternal, "<stage>: <what>").
[[noreturn]] inline void broken(std::string_view stage, std::string_view what) {
  throw Error(ErrorKind::kInternal, std::string(stage) + ": " + std::string(what));
}

}  // namespace tetcut
