#pragma once
// What the tet scenes (scene.cpp) and the cloth scenes (cloth_scene.cpp) share: a JSON value that
// knows its key path, so that every error names it ("cuts[2].cylinder.radius: must be positive"),
// the keys both read, and pieces of their runs' output.

#include <tetcut/blade.hpp>
#include <tetcut/error.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/scene.hpp>
#include <tetcut/types.hpp>

#include "util/stopwatch.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

namespace tetcut::scene {

using Json = nlohmann::json;

// A JSON value and where it is in the file, for messages like "cuts[2].cylinder.radius: ...".
class Value {
 public:
  Value(const Json& json, std::string path, const std::string* file) : json_(&json), path_(std::move(path)), file_(file) {}

  [[noreturn]] void fail(const std::string& why) const {
    throw Error(ErrorKind::kInvalidInput, (path_.empty() ? std::string("the scene") : path_) + ": " + why, *file_);
  }
  const std::string& path() const { return path_; }

  // Objects: the keys allowed; any other is an error (a typo must not be ignored).
  void allow(std::initializer_list<const char*> keys) const {
    if (!json_->is_object()) fail("must be an object");
    for (const auto& [key, value] : json_->items()) {
      if (std::find_if(keys.begin(), keys.end(), [&](const char* k) { return key == k; }) == keys.end()) {
        std::string known;
        for (const char* k : keys) known += std::string(known.empty() ? "" : ", ") + k;
        fail("unknown key '" + key + "' (known: " + known + ")");
      }
    }
  }
  bool has(const char* key) const { return json_->is_object() && json_->contains(key); }
  bool is_object() const { return json_->is_object(); }
  Value at(const char* key) const {
    if (!has(key)) fail(std::string("missing key '") + key + "'");
    return Value((*json_)[key], join(key), file_);
  }
  std::optional<Value> get(const char* key) const {
    if (!has(key)) return std::nullopt;
    return Value((*json_)[key], join(key), file_);
  }
  std::vector<Value> array() const {
    if (!json_->is_array()) fail("must be an array");
    std::vector<Value> items;
    for (std::size_t i = 0; i < json_->size(); ++i) items.emplace_back((*json_)[i], path_ + "[" + std::to_string(i) + "]", file_);
    return items;
  }

  double number() const {
    if (!json_->is_number()) fail("must be a number");
    const double x = json_->get<double>();
    if (!std::isfinite(x)) fail("must be finite");
    return x;
  }
  double positive() const {
    const double x = number();
    if (!(x > 0)) fail("must be positive");
    return x;
  }
  double non_negative() const {
    const double x = number();
    if (x < 0) fail("must not be negative");
    return x;
  }
  int integer(int lowest) const {
    if (!json_->is_number_integer()) fail("must be an integer");
    const auto x = json_->get<std::int64_t>();
    if (x < lowest || x > 1'000'000'000) fail("must be an integer from " + std::to_string(lowest));
    return static_cast<int>(x);
  }
  bool boolean() const {
    if (!json_->is_boolean()) fail("must be true or false");
    return json_->get<bool>();
  }
  std::string string() const {
    if (!json_->is_string()) fail("must be a string");
    return json_->get<std::string>();
  }
  std::string choice(std::initializer_list<const char*> options) const {
    const std::string s = string();
    std::string known;
    for (const char* o : options) {
      if (s == o) return s;
      known += std::string(known.empty() ? "" : ", ") + o;
    }
    fail("'" + s + "' is not one of " + known);
  }
  std::vector<double> numbers(std::size_t count) const {
    if (!json_->is_array() || json_->size() != count) fail("must be an array of " + std::to_string(count) + " numbers");
    std::vector<double> out;
    for (const Value& v : array()) out.push_back(v.number());
    return out;
  }
  Vec3 vec3() const {
    const auto v = numbers(3);
    return Vec3(v[0], v[1], v[2]);
  }
  Vec3 direction() const {
    const Vec3 v = vec3();
    if (!(v.norm() > 0)) fail("must not be the zero vector");
    return v;
  }
  // A blade's pose, [ax, ay, az, bx, by, bz].
  BladePose pose() const {
    const auto ab = numbers(6);
    return {Vec3(ab[0], ab[1], ab[2]), Vec3(ab[3], ab[4], ab[5])};
  }
  // A blade moving through poses: at least two.
  std::vector<BladePose> poses() const {
    std::vector<BladePose> out;
    for (const Value& pose : array()) out.push_back(pose.pose());
    if (out.size() < 2) fail("needs at least 2 poses");
    return out;
  }
  Box box() const {
    const auto v = numbers(6);
    Box b{Vec3(v[0], v[1], v[2]), Vec3(v[3], v[4], v[5])};
    if (!((b.min.array() <= b.max.array()).all())) fail("its minimum corner must not exceed its maximum corner");
    return b;
  }

 private:
  std::string join(const char* key) const { return path_.empty() ? key : path_ + "." + key; }
  const Json* json_;
  std::string path_;
  const std::string* file_;
};

inline std::filesystem::path relative_to(const std::filesystem::path& scene, const std::string& path) {
  const std::filesystem::path p(path);
  return p.is_absolute() ? p : scene.parent_path() / p;
}

// "pin": [{"box": [...]}] at the top of a scene.
std::vector<Box> load_pins(const Value& root);
// "output": {"mesh", "surface", "picture": {"box", "azimuth", "elevation"}}.
void load_output(const Value& root, Scene* scene);
// Everything of a cloth scene (root has "cloth"): cloth_scene.cpp.
void load_cloth(const Value& root, const std::filesystem::path& path, Scene* scene);

// The frames a run writes, for the tet and the cloth runners: how many steps the scene's time asks
// for and after which a frame is written; after each frame the .pvd series listing the frames so
// far (mesh_NNNN with the runner's mesh extension, and surface_NNNN.vtp), its time in the output
// stage and the caller's progress; at the end the run's totals.
class FrameSeries {
 public:
  FrameSeries(const Scene& scene, double dt, std::filesystem::path directory, const SceneRunOptions& options,
              std::string mesh_extension);
  int steps() const { return steps_; }
  /// Whether a frame is written after step `step` (from 0).
  bool frame_after(int step) const { return (step + 1) % every_ == 0; }
  /// The number of the frame being written.
  int next() const { return static_cast<int>(times_.size()); }
  /// Frame next() is written, for simulated time `time`; writing it began at `start`.
  void written(double time, Clock::time_point start, SceneSummary* summary);
  /// Whether the frames asked for (SceneRunOptions::max_frames) are written.
  bool enough() const { return options_.max_frames >= 0 && next() - 1 >= options_.max_frames; }
  /// frames, simulated and wall seconds, seconds per frame, the median, p99 and largest of
  /// `step_ms` (per step), and the box of `nodes` at the end.
  void finish(const std::vector<double>& step_ms, const Points& nodes, Clock::time_point start, SceneSummary* summary) const;

 private:
  const Scene& scene_;
  double dt_;
  std::filesystem::path directory_;
  const SceneRunOptions& options_;
  std::string mesh_extension_;
  int steps_ = 1, every_ = 1, expected_ = 0;
  std::vector<double> times_;
};

double percentile(std::vector<double> v, double p);
// summary.json's "ms_per_step": the stages per step, and the median, p99 and largest step.
Json ms_per_step_json(const SceneSummary& summary);
// Runs a cloth scene: cloth_scene.cpp.
SceneSummary run_cloth_scene(const Scene& scene, const std::filesystem::path& directory, const SceneRunOptions& options);

}  // namespace tetcut::scene
