#pragma once
// The distinct world planes of the cuts so far and their registry planes, shared by the 3D cutter
// (src/cutter/) and the planar one (src/planar/), for cuts in rest space and pulled back per copy.

#include <tetcut/types.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

#include "geometry/plane.hpp"
#include "registry/intersection_registry.hpp"

namespace tetcut::registry {

// The distinct planes of the cuts so far. Triangles on one plane (a straight blade sweeps a flat
// strip, batch after batch) share one plane, and in world space one pulled-back plane per copy, so
// that what one triangle leaves on the plane the next recognises by plane id instead of by exact
// arithmetic. Each plane gets a key unique over all batches (from the cut id of the first triangle
// on it), which names it to the registry's symbolic test of where two copies' pull-backs agree.
// Unlike the registry, which stores a triangle's plane once per set of corners, the book finds one
// plane through different corners (the next triangle of a strip), and it holds world-space planes,
// which the registry never sees; walls it keys as the registry does (wall_key).
class PlaneBook {
 public:
  struct Found {
    std::int64_t key;
    int sign;  // +1 when the stored plane has the orientation asked for
    const geometry::Plane* plane;
  };

  // The triangle plane `plane`, or an equal one seen before. O(1) expected: a hash of the rounded,
  // normalised coefficients proposes candidates, and equality is decided exactly.
  Found triangle_plane(const geometry::Plane& plane, std::int64_t fresh_key) {
    const std::array<std::int64_t, 4> cell = grid_cell(plane);
    auto& bucket = planes_[cell];
    for (const std::size_t index : bucket) {
      const Entry& e = entries_[index];
      const int alignment = geometry::plane_alignment(e.plane, plane);
      if (alignment != 0) return {e.key, alignment, &e.plane};
    }
    bucket.push_back(entries_.size());
    entries_.push_back({plane, fresh_key});
    return {fresh_key, 1, &entries_.back().plane};
  }

  // The wall through edge (p, q) along `axis`, oriented towards `inner`; one per edge and axis.
  // Keyed as the registry keys its walls (registry::wall_key).
  Found wall(const Vec3& p, const Vec3& q, int axis, const Vec3& inner, std::int64_t fresh_key) {
    bool swap = false;
    const WallKey key = wall_key(p, q, axis, &swap);
    auto it = walls_.find(key);
    if (it == walls_.end()) it = walls_.emplace(key, Entry{geometry::Plane::wall(swap ? q : p, swap ? p : q, axis), fresh_key}).first;
    return {it->second.key, geometry::side_of_point(it->second.plane, inner), &it->second.plane};
  }

  // A registry plane per key and copy (copy -1: rest space), made once by `make`.
  template <typename Make>
  PlaneId per_copy(std::int64_t key, Index copy, Make&& make) {
    const auto [it, inserted] = per_copy_.try_emplace({key, copy}, -1);
    if (inserted) it->second = make();
    return it->second;
  }
  // Pulled-back planes depend on the current positions: forget them when those change.
  void forget_pulled_back() {
    std::erase_if(per_copy_, [](const auto& entry) { return entry.first.second >= 0; });
  }

 private:
  // Normalised coefficients rounded to a grid of 2^-30: representations of one plane fall in one
  // cell unless they straddle a grid line, which costs a missed sharing, never correctness.
  static std::array<std::int64_t, 4> grid_cell(const geometry::Plane& plane) {
    Eigen::Vector4d c = plane.rounded();
    const double n = c.head<3>().norm();
    if (n > 0) c /= n;
    // One orientation for both: the first clearly non-zero coefficient positive. "Clearly": far
    // above the rounding of normalised coefficients, so that two representations of one plane
    // pick the same one (one that straddles the threshold only misses a sharing).
    constexpr double kClearlyNonZero = 1e-6;
    for (int k = 0; k < 4; ++k) {
      if (std::abs(c[k]) > kClearlyNonZero) {
        if (c[k] < 0) c = -c;
        break;
      }
    }
    std::array<std::int64_t, 4> cell;
    for (int k = 0; k < 4; ++k) cell[k] = std::llround(std::ldexp(c[k], 30));
    return cell;
  }
  struct Entry {
    geometry::Plane plane;
    std::int64_t key;
  };
  std::deque<Entry> entries_;  // a deque keeps the planes in place for the pointers handed out
  std::unordered_map<std::array<std::int64_t, 4>, std::vector<std::size_t>, WordsHash> planes_;
  std::unordered_map<WallKey, Entry, WordsHash> walls_;  // nodes stay put: pointers to their planes are handed out
  std::map<std::pair<std::int64_t, Index>, PlaneId> per_copy_;
};

}  // namespace tetcut::registry
