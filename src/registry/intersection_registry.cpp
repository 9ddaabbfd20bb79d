#include "registry/intersection_registry.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <stdexcept>

namespace tetcut::registry {

using geometry::Plane;

namespace {

// -0.0 and 0.0 are the same coordinate; keys compare bit patterns, so fold them together.
double canonical_zero(double x) { return x + 0.0; }

bool lexicographically_less(const Vec3& a, const Vec3& b) {
  for (int k = 0; k < 3; ++k) {
    if (a[k] != b[k]) return a[k] < b[k];
  }
  return false;
}

}  // namespace

std::size_t IntersectionRegistry::KeyHash::operator()(const PointsKey& key) const {
  // 64-bit mix of the bit patterns (splitmix64 finaliser per word).
  std::uint64_t h = 0x9e3779b97f4a7c15ULL;
  for (const double x : key.coordinates) {
    std::uint64_t z = std::bit_cast<std::uint64_t>(x) + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    h ^= z ^ (z >> 31);
  }
  return static_cast<std::size_t>(h);
}

PlaneId IntersectionRegistry::add_plane(const Plane& plane) {
  planes_.push_back(plane);
  return static_cast<PlaneId>(planes_.size() - 1);
}

OrientedPlane IntersectionRegistry::triangle_plane(const Vec3& a, const Vec3& b, const Vec3& c) {
  std::array<Vec3, 3> sorted = {a, b, c};
  for (Vec3& p : sorted) p = p.unaryExpr(&canonical_zero);
  // Sort the three corners, counting transpositions: an odd permutation reverses the orientation.
  int sign = 1;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2 - i; ++j) {
      if (lexicographically_less(sorted[j + 1], sorted[j])) {
        std::swap(sorted[j], sorted[j + 1]);
        sign = -sign;
      }
    }
  }
  PointsKey key{};
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) key.coordinates[3 * i + k] = sorted[i][k];
  }
  const auto [it, inserted] = triangle_planes_.try_emplace(key, num_planes());
  if (inserted) add_plane(Plane::through(sorted[0], sorted[1], sorted[2]));
  return {it->second, sign};
}

OrientedPlane IntersectionRegistry::wall(const Vec3& p, const Vec3& q, int axis, const Vec3& inner) {
  Vec3 from = p.unaryExpr(&canonical_zero), to = q.unaryExpr(&canonical_zero);
  if (lexicographically_less(to, from)) std::swap(from, to);
  PointsKey key{};
  for (int k = 0; k < 3; ++k) {
    key.coordinates[k] = from[k];
    key.coordinates[3 + k] = to[k];
  }
  key.coordinates[6] = axis;
  const auto [it, inserted] = walls_.try_emplace(key, num_planes());
  if (inserted) add_plane(Plane::wall(from, to, axis));
  const int side = geometry::side_of_point(planes_[it->second], inner);
  if (side == 0) throw std::logic_error("registry: the inner point of a wall lies on it");
  return {it->second, side};
}

VertexId IntersectionRegistry::add_point(PlaneId a, PlaneId b, PlaneId c) {
  const int orientation = geometry::normal_determinant_sign(planes_[a], planes_[b], planes_[c]);
  if (orientation == 0) throw std::logic_error("registry: three planes of a point do not meet in one point");
  Vertex v;
  v.planes = {a, b, c};
  v.homogeneous = geometry::tpi_homogeneous(planes_[a], planes_[b], planes_[c]);
  v.orientation = static_cast<std::int8_t>(orientation);
  vertices_.push_back(v);
  return static_cast<VertexId>(vertices_.size() - 1);
}

VertexId IntersectionRegistry::add_node(Index node, PlaneId a, PlaneId b, PlaneId c) {
  Vertex v;
  v.planes = {a, b, c};
  v.homogeneous = geometry::explicit_homogeneous(rest_->row(node).transpose());
  v.orientation = 1;
  v.node = node;
  vertices_.push_back(v);
  return static_cast<VertexId>(vertices_.size() - 1);
}

const geometry::ExactPlane& IntersectionRegistry::exact_plane(PlaneId p) const {
  {
    const std::lock_guard<std::mutex> lock(exact_mutex_);
    if (exact_planes_.size() <= static_cast<std::size_t>(p)) exact_planes_.resize(planes_.size());
    if (exact_planes_[p]) return *exact_planes_[p];
  }
  // Computed outside the lock; if another thread stored it meanwhile, keep theirs.
  auto computed = std::make_unique<geometry::ExactPlane>(geometry::exact_plane(planes_[p]));
  const std::lock_guard<std::mutex> lock(exact_mutex_);
  if (!exact_planes_[p]) exact_planes_[p] = std::move(computed);
  return *exact_planes_[p];
}

const geometry::ExactPoint& IntersectionRegistry::exact_point(VertexId v) const {
  {
    const std::lock_guard<std::mutex> lock(exact_mutex_);
    if (exact_points_.size() <= static_cast<std::size_t>(v)) exact_points_.resize(vertices_.size());
    if (exact_points_[v]) return *exact_points_[v];
  }
  const Vertex& vertex = vertices_[v];
  auto computed = std::make_unique<geometry::ExactPoint>(
      vertex.node >= 0 ? geometry::exact_point(rest_->row(vertex.node).transpose())
                       : geometry::exact_tpi(exact_plane(vertex.planes[0]), exact_plane(vertex.planes[1]),
                                             exact_plane(vertex.planes[2])));
  const std::lock_guard<std::mutex> lock(exact_mutex_);
  if (!exact_points_[v]) exact_points_[v] = std::move(computed);
  return *exact_points_[v];
}

namespace {

bool defines(const Plane& plane, const Vec3& x) {
  for (int i = 0; i < plane.num_defining_points(); ++i) {
    if (plane.points()[i] == x) return true;
  }
  return false;
}

}  // namespace

bool IntersectionRegistry::on_plane_by_construction(VertexId v, PlaneId q) const {
  const Vertex& vertex = vertices_[v];
  const Plane& target = planes_[q];
  if (vertex.node >= 0) return defines(target, rest_->row(vertex.node).transpose());
  // Two of the point's planes through the same two distinct inputs a and b meet in line ab, which
  // holds the point; three through one input x meet only at x.
  for (int i = 0; i < 3; ++i) {
    const Plane& a = planes_[vertex.planes[i]];
    const Plane& b = planes_[vertex.planes[(i + 1) % 3]];
    const Plane& c = planes_[vertex.planes[(i + 2) % 3]];
    const Vec3* shared[3];
    int count = 0;
    for (int k = 0; k < a.num_defining_points(); ++k) {
      const Vec3& x = a.points()[k];
      if (defines(b, x)) {
        bool repeated = false;
        for (int m = 0; m < count; ++m) repeated = repeated || *shared[m] == x;
        if (!repeated) shared[count++] = &x;
      }
    }
    for (int m = 0; m < count; ++m) {
      if (!defines(target, *shared[m])) continue;
      if (defines(c, *shared[m])) return true;  // the point is that input
      for (int n = m + 1; n < count; ++n) {
        if (defines(target, *shared[n])) return true;  // the point is on the line through both
      }
    }
  }
  return false;
}

int IntersectionRegistry::compute_side(VertexId v, PlaneId q) const {
  const Vertex& vertex = vertices_[v];
  if (vertex.planes[0] == q || vertex.planes[1] == q || vertex.planes[2] == q) return 0;
  // q . (X, Y, Z, W) = det4 of the point's three planes and q (W = 1 for an input point).
  const auto& p = planes_[q].approx();
  const auto& h = vertex.homogeneous;
  const int s = geometry::certain_sign(p[0] * h[0] + p[1] * h[1] + p[2] * h[2] + p[3] * h[3]);
  if (s != 2) return s * vertex.orientation;
  if (on_plane_by_construction(v, q)) return 0;
  return geometry::exact_side(exact_plane(q), exact_point(v));
}

int IntersectionRegistry::side_of_input(PlaneId q, const Vec3& x) const {
  const auto& p = planes_[q].approx();
  using geometry::Approx;
  const int s = geometry::certain_sign(p[0] * Approx::exact(x[0]) + p[1] * Approx::exact(x[1]) +
                                       p[2] * Approx::exact(x[2]) + p[3]);
  if (s != 2) return s;
  if (defines(planes_[q], x)) return 0;
  return geometry::exact_side(exact_plane(q), geometry::exact_point(x));
}

int IntersectionRegistry::side(VertexId v, const Plane& q) const {
  const auto& p = q.approx();
  const Vertex& vertex = vertices_[v];
  const auto& h = vertex.homogeneous;
  const int s = geometry::certain_sign(p[0] * h[0] + p[1] * h[1] + p[2] * h[2] + p[3] * h[3]);
  if (s != 2) return s * vertex.orientation;
  return geometry::exact_side(geometry::exact_plane(q), exact_point(v));
}

int IntersectionRegistry::side_of_meet(PlaneId a, PlaneId b, PlaneId c, PlaneId q) const {
  const geometry::Homogeneous h = geometry::tpi_homogeneous(planes_[a], planes_[b], planes_[c]);
  const auto& p = planes_[q].approx();
  const int w = geometry::certain_sign(h[3]);
  const int s = geometry::certain_sign(p[0] * h[0] + p[1] * h[1] + p[2] * h[2] + p[3] * h[3]);
  if (w != 2 && w != 0 && s != 2) return s * w;
  return geometry::exact_side(exact_plane(q), geometry::exact_tpi(exact_plane(a), exact_plane(b), exact_plane(c)));
}

int IntersectionRegistry::side(VertexId v, PlaneId q) const {
  int slot = 0;
  while (slot < 4 && memo_planes_[slot] != q) ++slot;
  if (slot == 4) return compute_side(v, q);
  if (memo_vertex_stamp_.size() <= static_cast<std::size_t>(v)) {
    // Grow geometrically: vertices are added during an insertion.
    const std::size_t size = std::max(vertices_.size(), 2 * memo_vertex_stamp_.size());
    memo_vertex_stamp_.resize(size, 0);
    memo_sides_.resize(size);
  }
  if (memo_vertex_stamp_[v] != memo_stamp_) {
    memo_vertex_stamp_[v] = memo_stamp_;
    memo_sides_[v] = {kUnknown, kUnknown, kUnknown, kUnknown};
  }
  std::int8_t& memo = memo_sides_[v][slot];
  if (memo == kUnknown) memo = static_cast<std::int8_t>(compute_side(v, q));
  return memo;
}

void IntersectionRegistry::begin_memo(std::initializer_list<PlaneId> planes) {
  memo_planes_ = {-1, -1, -1, -1};
  int slot = 0;
  for (const PlaneId p : planes) {
    if (slot == 4) throw std::logic_error("registry: at most four memoised planes");
    memo_planes_[slot++] = p;
  }
  ++memo_stamp_;
  if (memo_stamp_ == 0) {
    // Wrapped after four billion insertions: forget every old stamp.
    std::fill(memo_vertex_stamp_.begin(), memo_vertex_stamp_.end(), 0);
    memo_stamp_ = 1;
  }
}

void IntersectionRegistry::end_memo() { memo_planes_ = {-1, -1, -1, -1}; }

void IntersectionRegistry::compute_position(VertexId v) const {
  const Vertex& vertex = vertices_[v];
  Vec3& x = positions_[v];
  if (vertex.node >= 0) {
    x = rest_->row(vertex.node).transpose();
  } else if (!geometry::rounded_coordinates(vertex.homogeneous, &x)) {
    // Ill-conditioned: round the exact coordinates. The exact point is computed here rather than
    // through the cache, since update_positions runs this in parallel.
    const geometry::ExactPoint exact = geometry::exact_tpi(geometry::exact_plane(planes_[vertex.planes[0]]),
                                                           geometry::exact_plane(planes_[vertex.planes[1]]),
                                                           geometry::exact_plane(planes_[vertex.planes[2]]));
    x = geometry::rounded_exact(exact);
  }
  has_position_[v] = 1;
}

const Vec3& IntersectionRegistry::position(VertexId v) const {
  if (positions_.size() < vertices_.size()) {
    positions_.resize(vertices_.size());
    has_position_.resize(vertices_.size(), 0);
  }
  if (!has_position_[v]) compute_position(v);
  return positions_[v];
}

std::array<mpq_class, 3> IntersectionRegistry::exact_position(VertexId v) const {
  // Computed afresh, without the caches, so that parallel measurements may call it.
  const Vertex& vertex = vertices_[v];
  if (vertex.node >= 0) return geometry::exact_coordinates(geometry::exact_point(rest_->row(vertex.node).transpose()));
  return geometry::exact_coordinates(geometry::exact_tpi(geometry::exact_plane(planes_[vertex.planes[0]]),
                                                         geometry::exact_plane(planes_[vertex.planes[1]]),
                                                         geometry::exact_plane(planes_[vertex.planes[2]])));
}

double IntersectionRegistry::position_tolerance() { return geometry::kCoordinateTolerance; }

void IntersectionRegistry::update_positions() const {
  if (positions_.size() < vertices_.size()) {
    positions_.resize(vertices_.size());
    has_position_.resize(vertices_.size(), 0);
  }
  tbb::parallel_for(tbb::blocked_range<VertexId>(positions_done_, num_vertices(), 1024), [&](const auto& range) {
    for (VertexId v = range.begin(); v != range.end(); ++v) {
      if (!has_position_[v]) compute_position(v);
    }
  });
  positions_done_ = num_vertices();
}

}  // namespace tetcut::registry
