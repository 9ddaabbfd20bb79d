#include "registry/intersection_registry.hpp"

#include "util/broken.hpp"

#include <algorithm>

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

WallKey wall_key(const Vec3& p, const Vec3& q, int axis, bool* swapped) {
  *swapped = lexicographically_less(q, p);
  const Vec3& from = *swapped ? q : p;
  const Vec3& to = *swapped ? p : q;
  WallKey key;
  for (int k = 0; k < 3; ++k) {
    key[k] = canonical_zero(from[k]);
    key[3 + k] = canonical_zero(to[k]);
  }
  key[6] = axis;
  return key;
}

PlaneId IntersectionRegistry::add_plane(const Plane& plane) {
  return static_cast<PlaneId>(planes_.push_back(plane) - planes_.begin());
}

VertexId IntersectionRegistry::push_vertex(Vertex vertex) {
  vertex.position = compute_position(vertex);
  return static_cast<VertexId>(vertices_.push_back(vertex) - vertices_.begin());
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
  std::array<double, 9> key;
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) key[3 * i + k] = sorted[i][k];
  }
  const auto [it, inserted] = triangle_planes_.try_emplace(key, num_planes());
  if (inserted) add_plane(Plane::through(sorted[0], sorted[1], sorted[2]));
  return {it->second, sign};
}

OrientedPlane IntersectionRegistry::wall(const Vec3& p, const Vec3& q, int axis, const Vec3& inner) {
  bool swapped = false;
  const WallKey key = wall_key(p, q, axis, &swapped);
  const auto [it, inserted] = walls_.try_emplace(key, num_planes());
  // The wall through the key's ends, zeros folded: the same plane however the edge was given.
  if (inserted) add_plane(Plane::wall(Vec3(key[0], key[1], key[2]), Vec3(key[3], key[4], key[5]), axis));
  const int side = geometry::side_of_point(planes_[it->second], inner);
  if (side == 0) broken("registry", "the inner point of a wall lies on it");
  return {it->second, side};
}

VertexId IntersectionRegistry::add_point(PlaneId a, PlaneId b, PlaneId c) {
  const int orientation = geometry::normal_determinant_sign(planes_[a], planes_[b], planes_[c]);
  if (orientation == 0) broken("registry", "three planes of a point do not meet in one point");
  Vertex v;
  v.planes = {a, b, c};
  v.homogeneous = geometry::tpi_homogeneous(planes_[a], planes_[b], planes_[c]);
  v.orientation = static_cast<std::int8_t>(orientation);
  return push_vertex(v);
}

VertexId IntersectionRegistry::add_node(Index node, PlaneId a, PlaneId b, PlaneId c) {
  Vertex v;
  v.planes = {a, b, c};
  v.homogeneous = geometry::explicit_homogeneous(rest_->row(node).transpose());
  v.orientation = 1;
  v.node = node;
  return push_vertex(v);
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

namespace {

// Whether two pulled-back planes of the same world plane move the input point x alike: x is a
// rest corner of both tets, with the same current position in both.
bool moved_alike(const Plane::PullBack& a, const Plane::PullBack& b, const Vec3& x) {
  for (int i = 0; i < 4; ++i) {
    if (a.rest[i] != x) continue;
    for (int j = 0; j < 4; ++j) {
      if (b.rest[j] == x) return a.current[i] == b.current[j];
    }
  }
  return false;
}

bool same_motion(const Plane::PullBack& a, const Plane::PullBack& b) { return a.rest == b.rest && a.current == b.current; }

// Inputs that two planes both pass through by definition (at most two kept: two distinct ones fix
// the line the planes meet in).
struct Shared {
  const Vec3* points[2];
  int count = 0;
};
Shared shared_inputs(const Plane& a, const Plane& b) {
  Shared s;
  for (int k = 0; k < a.num_defining_points() && s.count < 2; ++k) {
    const Vec3& x = a.points()[k];
    if (defines(b, x) && (s.count == 0 || *s.points[0] != x)) s.points[s.count++] = &x;
  }
  return s;
}

// The point where a, b and c meet lies on `target` by the inputs defining them: two of the planes
// through the same two distinct inputs meet in the line through them, which holds the point; three
// through one input meet only there.
bool on_plane_by_inputs(const std::array<const Plane*, 3>& p, const Plane& target) {
  for (int i = 0; i < 3; ++i) {
    const Shared s = shared_inputs(*p[i], *p[(i + 1) % 3]);
    for (int m = 0; m < s.count; ++m) {
      if (!defines(target, *s.points[m])) continue;
      if (defines(*p[(i + 2) % 3], *s.points[m])) return true;
      if (s.count == 2 && defines(target, *s.points[1 - m])) return true;
    }
  }
  return false;
}

// The same for pulled-back planes, where the rules above hold one level up:
//  - through one copy's motion, pulling back keeps incidence, so planes all pulled back through
//    the same motion follow the rules of their world planes;
//  - pull-backs of one world plane agree wherever their tets' motions agree: on a face or an edge
//    of input points both tets have, with the same current positions. A point on one of them that
//    lies by construction on such a face (one of its planes passes through three inputs) or edge
//    (two of its planes share two inputs) is on the other.
bool on_pulled_back_plane(const std::array<const Plane*, 3>& p, const Plane& target) {
  const Plane::PullBack* to = target.pull_back();
  if (to == nullptr) return false;
  if (p[0]->pull_back() && p[1]->pull_back() && p[2]->pull_back() && same_motion(*p[0]->pull_back(), *to) &&
      same_motion(*p[1]->pull_back(), *to) && same_motion(*p[2]->pull_back(), *to)) {
    if (on_plane_by_inputs({&p[0]->pull_back()->world, &p[1]->pull_back()->world, &p[2]->pull_back()->world}, to->world)) {
      return true;
    }
  }
  if (to->world_key < 0) return false;
  for (int i = 0; i < 3; ++i) {
    const Plane::PullBack* from = p[i]->pull_back();
    if (from == nullptr || from->world_key != to->world_key) continue;
    for (int j = 1; j < 3; ++j) {
      const Plane& other = *p[(i + j) % 3];
      if (other.kind() == Plane::Kind::kThroughPoints && moved_alike(*from, *to, other.points()[0]) &&
          moved_alike(*from, *to, other.points()[1]) && moved_alike(*from, *to, other.points()[2])) {
        return true;
      }
    }
    const Shared line = shared_inputs(*p[(i + 1) % 3], *p[(i + 2) % 3]);
    if (line.count == 2 && moved_alike(*from, *to, *line.points[0]) && moved_alike(*from, *to, *line.points[1])) {
      return true;
    }
  }
  return false;
}

// When the point where a, b and c meet is an input point x by construction, the side of any plane
// there is its side at x, a cheap exact test. That is so when two of the planes pass through x by
// definition and the third contains x. For planes pulled back through one motion the same holds one
// level up, with the world planes and the world point. Returns the side, or 2 when not known.
int side_at_input(const std::array<const Plane*, 3>& p, const Plane& target) {
  const Plane* level[3] = {p[0], p[1], p[2]};
  const Plane* q = &target;
  const Plane::PullBack* motion = p[0]->pull_back();
  if (motion != nullptr) {
    // All four pulled back through the same motion: work with their world planes.
    for (const Plane* plane : {p[1], p[2], &target}) {
      if (plane->pull_back() == nullptr || !same_motion(*plane->pull_back(), *motion)) return 2;
    }
    for (int i = 0; i < 3; ++i) level[i] = &p[i]->pull_back()->world;
    q = &target.pull_back()->world;
  } else if (p[1]->pull_back() || p[2]->pull_back() || target.pull_back()) {
    return 2;
  }
  for (int i = 0; i < 3; ++i) {
    const Plane& a = *level[i];
    const Plane& b = *level[(i + 1) % 3];
    const Plane& c = *level[(i + 2) % 3];
    for (int k = 0; k < a.num_defining_points(); ++k) {
      const Vec3& x = a.points()[k];
      if (defines(b, x) && (defines(c, x) || geometry::side_of_point(c, x) == 0)) {
        // A pulled-back plane has its world plane's sign at the image point, unless flipped itself.
        const int s = geometry::side_of_point(*q, x);
        return motion != nullptr && target.is_flipped() ? -s : s;
      }
    }
  }
  return 2;
}

}  // namespace

bool IntersectionRegistry::on_plane_by_construction(VertexId v, PlaneId q) const {
  const Vertex& vertex = vertices_[v];
  const Plane& target = planes_[q];
  if (vertex.node >= 0) return defines(target, rest_->row(vertex.node).transpose());
  const std::array<const Plane*, 3> p = {&planes_[vertex.planes[0]], &planes_[vertex.planes[1]], &planes_[vertex.planes[2]]};
  return on_plane_by_inputs(p, target) || on_pulled_back_plane(p, target);
}

int IntersectionRegistry::compute_side(VertexId v, PlaneId q) const {
  const Vertex& vertex = vertices_[v];
  if (vertex.planes[0] == q || vertex.planes[1] == q || vertex.planes[2] == q) return 0;
  // q . (X, Y, Z, W) = det4 of the point's three planes and q (W = 1 for an input point).
  const auto& p = planes_[q].approx();
  const auto& h = vertex.homogeneous;
  const int s = geometry::dot4_sign(p, h);
  if (s != 2) return s * vertex.orientation;
  if (on_plane_by_construction(v, q)) return 0;
  if (vertex.node < 0) {
    const int at_input = side_at_input({&planes_[vertex.planes[0]], &planes_[vertex.planes[1]], &planes_[vertex.planes[2]]}, planes_[q]);
    if (at_input != 2) return at_input;
  }
  return geometry::exact_side(exact_plane(q), exact_point(v));
}

int IntersectionRegistry::normal_alignment(PlaneId a, PlaneId b) const {
  const auto& p = planes_[a].approx();
  const auto& q = planes_[b].approx();
  const int s = geometry::certain_sign(p[0] * q[0] + p[1] * q[1] + p[2] * q[2]);
  if (s != 2) return s;
  const geometry::ExactPlane& ea = exact_plane(a);
  const geometry::ExactPlane& eb = exact_plane(b);
  return sgn(mpz_class(ea[0] * eb[0] + ea[1] * eb[1] + ea[2] * eb[2]));
}

int IntersectionRegistry::side_of_input(PlaneId q, const Vec3& x) const {
  const auto& p = planes_[q].approx();
  const int s = geometry::dot4_sign(p, geometry::explicit_homogeneous(x));
  if (s != 2) return s;
  if (defines(planes_[q], x)) return 0;
  return geometry::exact_side(exact_plane(q), geometry::exact_point(x));
}

int IntersectionRegistry::side(VertexId v, const Plane& q) const {
  const auto& p = q.approx();
  const Vertex& vertex = vertices_[v];
  const auto& h = vertex.homogeneous;
  const int s = geometry::dot4_sign(p, h);
  if (s != 2) return s * vertex.orientation;
  return geometry::exact_side(geometry::exact_plane(q), exact_point(v));
}

int IntersectionRegistry::side_of_meet(PlaneId a, PlaneId b, PlaneId c, PlaneId q) const {
  const geometry::Homogeneous h = geometry::tpi_homogeneous(planes_[a], planes_[b], planes_[c]);
  const auto& p = planes_[q].approx();
  const int w = geometry::certain_sign(h[3]);
  const int s = geometry::dot4_sign(p, h);
  if (w != 2 && w != 0 && s != 2) return s * w;
  const std::array<const Plane*, 3> meeting = {&planes_[a], &planes_[b], &planes_[c]};
  if (on_plane_by_inputs(meeting, planes_[q]) || on_pulled_back_plane(meeting, planes_[q])) return 0;
  const int at_input = side_at_input(meeting, planes_[q]);
  if (at_input != 2) return at_input;
  return geometry::exact_side(exact_plane(q), geometry::exact_tpi(exact_plane(a), exact_plane(b), exact_plane(c)));
}

int IntersectionRegistry::side(VertexId v, PlaneId q, SideMemo* memo) const {
  if (memo == nullptr || memo->owner_ != this) return compute_side(v, q);
  int slot = 0;
  while (slot < 4 && memo->planes_[slot] != q) ++slot;
  if (slot == 4) return compute_side(v, q);
  if (memo->vertex_stamp_.size() <= static_cast<std::size_t>(v)) {
    // Grow geometrically: vertices are added during an insertion.
    const std::size_t size = std::max<std::size_t>(vertices_.size(), 2 * memo->vertex_stamp_.size());
    memo->vertex_stamp_.resize(size, 0);
    memo->sides_.resize(size);
  }
  if (memo->vertex_stamp_[v] != memo->stamp_) {
    memo->vertex_stamp_[v] = memo->stamp_;
    memo->sides_[v] = {SideMemo::kUnknown, SideMemo::kUnknown, SideMemo::kUnknown, SideMemo::kUnknown};
  }
  std::int8_t& side = memo->sides_[v][slot];
  if (side == SideMemo::kUnknown) side = static_cast<std::int8_t>(compute_side(v, q));
  return side;
}

void IntersectionRegistry::SideMemo::begin(const IntersectionRegistry& registry, std::initializer_list<PlaneId> planes) {
  owner_ = &registry;
  planes_ = {-1, -1, -1, -1};
  int slot = 0;
  for (const PlaneId p : planes) {
    if (slot == 4) broken("registry", "at most four memoised planes");
    planes_[slot++] = p;
  }
  ++stamp_;
  if (stamp_ == 0) {
    // Wrapped after four billion insertions: forget every old stamp.
    std::fill(vertex_stamp_.begin(), vertex_stamp_.end(), 0);
    stamp_ = 1;
  }
}

Vec3 IntersectionRegistry::compute_position(const Vertex& vertex) const {
  if (vertex.node >= 0) return rest_->row(vertex.node).transpose();
  Vec3 x;
  if (geometry::rounded_coordinates(vertex.homogeneous, &x)) return x;
  // Ill-conditioned: round the exact coordinates. The exact point is computed here rather than
  // through the cache, which would keep it for a point that needs it only once.
  return geometry::rounded_exact(geometry::exact_tpi(geometry::exact_plane(planes_[vertex.planes[0]]),
                                                     geometry::exact_plane(planes_[vertex.planes[1]]),
                                                     geometry::exact_plane(planes_[vertex.planes[2]])));
}

geometry::ExactPoint IntersectionRegistry::exact_homogeneous(VertexId v) const {
  // Computed afresh, without the caches, so that parallel measurements may call it.
  const Vertex& vertex = vertices_[v];
  if (vertex.node >= 0) return geometry::exact_point(rest_->row(vertex.node).transpose());
  return geometry::exact_tpi(geometry::exact_plane(planes_[vertex.planes[0]]), geometry::exact_plane(planes_[vertex.planes[1]]),
                             geometry::exact_plane(planes_[vertex.planes[2]]));
}

double IntersectionRegistry::position_tolerance() { return geometry::kCoordinateTolerance; }

}  // namespace tetcut::registry
