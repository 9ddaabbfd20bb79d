#pragma once
// Scene files written for a test, and the error a scene's loading gives.

#include <tetcut/error.hpp>
#include <tetcut/scene.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "support/temp_dir.hpp"

namespace tetcut::testing {

inline std::filesystem::path write_file(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  const std::filesystem::path path = dir / name;
  std::ofstream(path) << text;
  return path;
}

/// The message load_scene gives for a scene file holding `text`, or "no error".
inline std::string load_error(const std::string& text) {
  TempDir dir;
  try {
    load_scene(write_file(dir.path(), "scene.json", text));
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace tetcut::testing
