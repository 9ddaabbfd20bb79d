// The guards and joins of a cut's two sides (see surface_contact.hpp, "Guards"): which pairs of
// joined copies get a one-sided barrier on a plane each step, their walls, and when a join ends.

#include "sim/surface_contact.hpp"

#include "sim/block_sparse.hpp"
#include "sim/surface_contact_parts.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace tetcut::sim::detail {
namespace {

// Two guards of one vertex are on one plane when their unit normals' dot product is within this
// of 1 (coplanar triangles of one cut polygon: equal up to the rounding of their corners), and
// the vertex stands at least as high over the plane left out as over the one kept, less
// kSameHeight of the allowance: then the kept guard's promise (no deeper than its wall behind its
// plane) holds on the other too. The normals alone made parallel faces of two sticks side by side
// one plane: a vertex guarded on the higher counted as held on the lower and the other way round
// (see held in lag_guards). Asked both ways (heights within kSameHeight), the heights kept guards
// that kinks between a side's neighbouring copies make and that one way does not need: on the
// sliced ball 37k active terms a step against 30k by normals alone, a step 9% longer; one way,
// 31k.
constexpr double kSamePlane = 1e-6;
// Two triangles of one copy sharing an edge lie in one plane in the material when their unit
// normals' dot product is within this of 1 (an angle below 1.5e-6: the fans over one flat polygon,
// whose normals differ by rounding, 1e-15; a real fold that small moves a point of a polygon of
// size L by 1.5e-6 L from the plane, a ten-thousandth of the allowance on a surface of edges L).
constexpr double kFlatFold = 1e-12;
constexpr double kSameHeight = 0.05;
// A guard's vertex may lie beside its triangle by up to the triangle's size (its barycentric
// coordinates down to -1).
constexpr double kBeside = 1;
// A vertex that does not face a triangle in the material is guarded on it only over it, its foot
// inside by more than this (barycentric): not on its rim, where rounding puts a rim vertex's foot.
constexpr double kSwungInside = 1e-6;
// A guard's barrier stops this share of the allowance behind its zero: the plane it holds is its
// triangle's at the step's start, and a triangle that turns within the step carries its plane past
// the vertex held to the old one (corners pressed to the barrier's wall at the bottom of Figure
// 4's pile, 0.97 of the allowance behind the held plane, were 1.0003 behind their triangles' own
// at the step's end). The rest is room for that turn, so that what the crossing check allows (the
// whole allowance) is not passed. At 0.9 the room was too little in piles larger than Figure 4's
// (the same block cut into 81 and 144 sticks crossed in up to 2 and 4 pairs, 1.0 to 1.7
// allowances deep); at 0.75 they, Figure 4 and the colliding slinky cross in none.
constexpr double kGuardWall = 0.75;
// A guard whose pair is found at a step's start behind the wall (its triangle turned since the
// last start) is given a wall this share of the allowance deeper than where it is: little, so
// that the barrier pushes it back out rather than letting the load that pressed it there press it
// deeper (at the bottom of Figure 4's pile corners sat 0.03 of the allowance from the wall).
constexpr double kRecoverShare = 0.01;
// The same with a cushion. Made again at every lag (each step's start, and each move the guards'
// planes held back) a hundredth below where its side is, a guard whose side a steady load held
// within that hundredth of its wall crept deeper at each: on the colliding slinky with a cushion
// of 0.5, whose springs load the squeezed coils' pressed sides, to 5.85 allowances, its sides
// held 0.0026 of the allowance off their walls, and it crossed (docs/contact.md, twenty-first
// session). A thousandth puts the wall of a side held that far off it shallower, and the barrier
// pushes it out. Without a cushion the hundredth stays: run with a thousandth (twenty-second
// session), 81 sticks' Newton solves stopped unconverged at 74 of 150 steps against 28, the
// barriers of the pile's corners pressed just past their walls that much steeper; with a
// thousandth past the whole allowance only, the plain slinky's deepest guard went to 1.31
// allowances instead of 1.74 (a side held closer to its wall than the share creeps on at any
// share), and Figure 4 took another path, on which a stick's corner went round a neighbour's
// rim into it where no guard held it, 9.7 allowances deep within a step, and it crossed in 10
// pairs at one frame (a gap of the guards, not of this share: docs/contact.md).
constexpr double kCushionRecoverShare = 0.001;
// How far behind its zero a guard's wall stands, for a pair at g (from the zero) at the step's
// start: kGuardWall of the allowance delta, or `recover` of it deeper than the pair.
double guard_wall(double g, double delta, double recover) { return std::max(kGuardWall * delta, -g + recover * delta); }

}  // namespace

using contact_parts::kFacing;
using contact_parts::PartTimer;
using contact_parts::unit_normal;

double SurfaceContact::recover_share() const { return settings_.cushion > 0 ? kCushionRecoverShare : kRecoverShare; }

double SurfaceContact::guard_depth(const Guard& guard) const {
  const double delta = guard_allowance();
  return std::max(delta, guard.wall + recover_share() * delta);
}

double SurfaceContact::guard_excess(const Points& at) const {
  Points y;
  place(at, &y);
  double excess = -std::numeric_limits<double>::infinity();
  for (const Guard& guard : guards_) {
    const Vec3 r = guard_vector(guard, y);
    const auto& tri = triangles_[static_cast<std::size_t>(guard.triangle)];
    const Vec3 a = y.row(tri[0]).transpose(), b = y.row(tri[1]).transpose(), c = y.row(tri[2]).transpose();
    const Vec3 n = (b - a).cross(c - a).normalized();
    const double allowed = guard_depth(guard);
    excess = std::max(excess, -(n.dot(r) - guard.zero) - allowed);
  }
  return excess;
}

double SurfaceContact::deepest_guard_wall() const {
  double deepest = 0;
  for (const Guard& guard : guards_) deepest = std::max(deepest, guard.wall);
  return deepest;
}

bool SurfaceContact::parallel_in_one_copy(std::size_t t, std::size_t u) const {
  return triangle_copy_[t] == triangle_copy_[u] && !rest_normals_[t].isZero() && !rest_normals_[u].isZero() &&
         rest_normals_[t].dot(rest_normals_[u]) > 1 - kFlatFold;
}

bool SurfaceContact::on_face_plane(Index t, Index face) const {
  if (t == face) return true;
  const auto a = static_cast<std::size_t>(t), b = static_cast<std::size_t>(face);
  if (!parallel_in_one_copy(a, b)) return false;
  // The same plane, not a parallel one: t's corners on face's plane within rounding.
  const Vec3 on = rest_y_.row(triangles_[b][0]).transpose();
  for (const Index corner : triangles_[a]) {
    if (!(std::abs(rest_normals_[b].dot(rest_y_.row(corner).transpose() - on)) <= kFlatFold * mean_edge_)) return false;
  }
  return true;
}

double SurfaceContact::guard_zero(const std::array<Index, 4>& corner, const std::array<double, 4>& w, Index triangle) const {
  const Vec3& rest_normal = rest_normals_[static_cast<std::size_t>(triangle)];
  const double slack = kGuardSlack * guard_allowance();
  if (rest_normal.isZero()) return -slack;
  Vec3 r = Vec3::Zero();
  for (int i = 0; i < 4; ++i) r += w[i] * rest_y_.row(corner[i]).transpose();
  return std::min(0.0, rest_normal.dot(r)) - slack;
}

void SurfaceContact::lag_guards(const Points& start) {
  const PartTimer timer(&part_seconds_.guards, &part_seconds_.rebuild);
  guards_.clear();
  guards_held_ = false;
  active_current_ = false;
  if (!enabled() || (joins_.empty() && group_facing_.empty())) return;
  cover(start, nullptr, 0);
  measure(kJoined);
  const double dhat = settings_.thickness, delta = guard_allowance(), reach = joined_reach(), recover = recover_share();
  // The cushion's spring pushes only pairs within dhat: those beyond it, guarded out to the reach
  // so that they cannot pass through each other (joined_reach), need no pushing apart. (Pushed
  // too, the cut block's upper half slid 15% less far than Coulomb says with friction: more
  // springs pushing against each other, each carrying friction.)
  const auto spring_cushion = [&](std::size_t k) { return distances_[k] < dhat ? guard_cushion(candidates_[k].copies) : 0.0; };
  struct Found {
    Index vertex;
    double inside;  // the smallest barycentric coordinate of the foot
    std::size_t k;  // the candidate
    std::array<double, 3> beta;
    Vec3 normal, r;  // r: the vertex less its foot (its friction's start)
    double height;   // the vertex's height over the triangle's plane (along normal)
    double zero, wall;
  };
  // Whether one of vertex v's triangles faces a triangle of unit normal `normal` now (turned more
  // than kFacing against it at the step's start).
  const auto swung_to_face = [&](Index v, const Vec3& normal) {
    for (Index i = vertex_triangle_start_[v]; i < vertex_triangle_start_[v + 1]; ++i) {
      const auto& tri = triangles_[static_cast<std::size_t>(vertex_triangles_[i])];
      const Vec3 n = unit_normal(y_.row(tri[0]).transpose(), y_.row(tri[1]).transpose(), y_.row(tri[2]).transpose(), dhat);
      if (n.dot(normal) < -kFacing) return true;
    }
    return false;
  };
  // Both scans below run in parallel over fixed chunks of the candidates, their findings joined
  // in chunk order: the guards do not depend on the number of threads.
  const auto K = static_cast<Index>(candidates_.size());
  std::vector<Found> found;
  append_chunks(K, kNodeChunk, &found, [&](Index begin, Index end, std::vector<Found>* out) {
    for (Index k = begin; k < end; ++k) {
      Candidate& c = candidates_[k];
      if (!c.joined || c.sutured || c.edges || !(distances_[k] < reach)) continue;
      // Only a vertex whose surface faces the triangle in the material: the other side of the cut
      // (one of the vertex's triangles turned against the triangle's), not a neighbour of the
      // triangle on its own side, which may lie beside it and below its plane; or one that has
      // swung over it since (below).
      if (!(c.faces & kFacesKnown)) c.faces = facing_faces(c);
      const bool faces_in_material = c.faces & 1;
      const std::array<Index, 4> corner = corners(c);
      const Vec3 p = y_.row(corner[0]).transpose(), a = y_.row(corner[1]).transpose(), b = y_.row(corner[2]).transpose(),
                 q = y_.row(corner[3]).transpose();
      const Vec3 normal = unit_normal(a, b, q, dhat);  // outward: the triangle's material is behind it
      if (normal.isZero()) continue;
      const Vec3 cross = (b - a).cross(q - a);
      const double area2 = cross.squaredNorm();
      // The vertex's foot on the triangle's plane in barycentric coordinates, also where it lies
      // beside the triangle (within dhat of it): on the rim of a cut, where both sides bulge as
      // they are pressed together, a vertex slips past the edge of the triangles it lay on.
      const Vec3 ap = p - a;
      const double beta_b = cross.dot(ap.cross(q - a)) / area2, beta_c = cross.dot((b - a).cross(ap)) / area2;
      const double beta_a = 1 - beta_b - beta_c;
      if (std::min({beta_a, beta_b, beta_c}) < -kBeside) continue;
      const double zero = guard_zero({corner[0], corner[1], corner[2], corner[3]}, {1, -beta_a, -beta_b, -beta_c}, c.b);
      const double g = normal.dot(p - (beta_a * a + beta_b * b + beta_c * q)) - zero;
      const double inside = std::min({beta_a, beta_b, beta_c});
      // A vertex that does not face the triangle in the material (on its rim there: a cut's rim
      // beside the other side's outer face, or meeting it at an angle) is guarded once it stands
      // over the triangle and one of its own faces has turned against it now: two sticks hinged
      // about the line where they touch until their outer faces faced each other, and one's corner
      // went 1.3 allowances into the other's face with nothing holding it. Over the triangle, not
      // on its rim: a rim vertex of faces side by side would be held to the other face's plane
      // while the sides turn about that line.
      if (!faces_in_material && !(inside > kSwungInside && swung_to_face(corner[0], normal))) continue;
      // Found behind the whole allowance, the vertex has passed what a guard allows: Figure 4's
      // pile left such a corner unguarded, and it sank 18 allowances into the other stick over
      // four steps. Over the triangle (not beside it, where it may have gone round the other
      // side's rim), within dhat of it, it is in the other side's material: guarded from where
      // it is, it is pushed back out.
      if (!(g > -delta) && !(inside >= 0)) continue;
      out->push_back({corner[0], inside, static_cast<std::size_t>(k), {beta_a, beta_b, beta_c}, normal,
                      p - (beta_a * a + beta_b * b + beta_c * q), g + zero, zero, guard_wall(g, delta, recover)});
    }
  });
  // One guard per vertex and plane: a vertex facing a fan of coplanar triangles (the other side
  // of its cut polygon) needs one, by the triangle it lies most inside; its planes differ only
  // where cuts or faces meet. Fewer terms, the same constraint: g is the same on coplanar
  // triangles. A plane is held by a kept guard where their normals agree and the vertex stands at
  // least as high over it as over the kept guard's plane (kSameHeight): of parallel faces at two
  // heights (two sticks side by side under a third), the lower one for the vertex needs a guard
  // of its own.
  const double same_height = kSameHeight * delta;
  // Whether a kept guard (its plane's normal, its vertex's height over it) holds the vertex on the
  // plane with this normal over which it stands this high.
  const auto covers = [&](const Vec3& kept_normal, double kept_height, const Vec3& normal, double height) {
    return kept_normal.dot(normal) > 1 - kSamePlane && height > kept_height - same_height;
  };
  std::vector<Index> guard_vertex;   // per vertex guard, its vertex (ascending)
  std::vector<double> guard_height;  // per vertex guard, its vertex's height over its plane
  std::sort(found.begin(), found.end(), [](const Found& x, const Found& y) {
    return x.vertex != y.vertex ? x.vertex < y.vertex : x.inside != y.inside ? x.inside > y.inside : x.k < y.k;
  });
  for (std::size_t i = 0; i < found.size();) {
    std::size_t end = i;
    while (end < found.size() && found[end].vertex == found[i].vertex) ++end;
    const std::size_t first_guard = guards_.size();
    for (std::size_t j = i; j < end; ++j) {
      bool covered = false;
      for (std::size_t h = first_guard; h < guards_.size() && !covered; ++h) {
        covered = covers(guards_[h].normal, guard_height[h], found[j].normal, found[j].height);
      }
      if (covered) continue;
      guards_.push_back({corners(candidates_[found[j].k]), {1.0, -found[j].beta[0], -found[j].beta[1], -found[j].beta[2]}, found[j].normal,
                         found[j].zero, found[j].wall, found[j].r, found[j].r.norm(), candidates_[found[j].k].b,
                         spring_cushion(found[j].k)});
      guard_vertex.push_back(found[j].vertex);
      guard_height.push_back(found[j].height);
    }
    i = end;
  }
  // Edges: a pair of edges of joined copies within dhat, one on a face the other's faces face (the
  // two sides of a cut, or a face meeting the cut at a rim and the other side), keeps the vector
  // between its closest points in front of that face's plane, the same one-sided barrier. A vertex
  // guard lapses once its vertex is beyond dhat of the face it faced; the edge behind it, whose
  // pairs all touch in the material, is held here (Figure 4's pile: a stick's side face sagging
  // through its neighbour's corner while both its ends are past the neighbour's faces).
  // Whether vertex v has a vertex guard on the plane with this normal. A vertex's guards are
  // contiguous (vertices ascending): each vertex's first is kept, so that this is O(its guards).
  // (A binary search of the vertex guards here, for each face of 6.8k edge pairs a step on the
  // sliced hand, was a large part of the edge scan.)
  first_vertex_guard_.assign(vertex_nodes_.size(), -1);
  for (std::size_t i = guard_vertex.size(); i-- > 0;) first_vertex_guard_[static_cast<std::size_t>(guard_vertex[i])] = static_cast<Index>(i);
  // Whether vertex v is held on the plane with this normal through point `on`: by a guard of its
  // own whose normal agrees and over whose plane v stands no higher (covers).
  // By normals alone, an edge of one piece lying across two others side by side, its ends
  // guarded on their parallel faces at two heights, counted as held on both planes, and the part
  // of it over the higher face had no guard on that face's plane
  // (AnEdgeAcrossParallelFacesAtTwoHeightsIsHeldOnEach).
  // Whether some vertex guard of v (its index i among the guards) satisfies pred(i).
  const auto any_guard_of = [&](Index v, const auto& pred) {
    const Index first_guard = first_vertex_guard_[static_cast<std::size_t>(v)];
    if (first_guard < 0) return false;
    for (auto i = static_cast<std::size_t>(first_guard); i < guard_vertex.size() && guard_vertex[i] == v; ++i) {
      if (pred(i)) return true;
    }
    return false;
  };
  const auto held = [&](Index v, const Vec3& normal, const Vec3& on) {
    const double height = normal.dot(y_.row(v).transpose() - on);
    return any_guard_of(v, [&](std::size_t i) { return covers(guards_[i].normal, guard_height[i], normal, height); });
  };
  // Whether vertex v has a vertex guard on face t or on a triangle of t's copy in t's plane in the
  // material. A copy moves affinely, so such a triangle stays in t's plane, turns as t does (the
  // turn guards_share bounds), and a pair's zero (its g in the material) is the same on it: the
  // guard holds v as an edge guard on t whose point is v would, up to rounding, but for the
  // barrier and friction counted once instead of twice. (Leaving the edge guard out wherever
  // `held` found the end held, on a nearby plane with its own zero and turn, let 81 sticks cross
  // in 4 pairs at one frame; this form crossed too until joined vertices swung over a face got
  // their guards, and since has not.)
  const auto guarded_on_face = [&](Index v, Index t) {
    return any_guard_of(v, [&](std::size_t i) { return on_face_plane(guards_[i].triangle, t); });
  };
  // Whether r, from a point on edge e, points behind every face around e that has a normal: into
  // the material there (the material is the intersection of those half-spaces where e is convex,
  // their union where it is not: behind all of them is inside either way).
  const auto behind_faces = [&](std::size_t e, const Vec3& r) {
    bool any = false;
    for (Index i = edge_triangle_start_[e]; i < edge_triangle_start_[e + 1]; ++i) {
      const auto& tri = triangles_[static_cast<std::size_t>(edge_triangles_[static_cast<std::size_t>(i)])];
      const Vec3 normal = unit_normal(y_.row(tri[0]).transpose(), y_.row(tri[1]).transpose(), y_.row(tri[2]).transpose(), dhat);
      if (normal.isZero()) continue;
      if (!(normal.dot(r) < 0)) return false;
      any = true;
    }
    return any;
  };
  append_chunks(K, kNodeChunk, &guards_, [&](Index begin, Index end, std::vector<Guard>* out) {
    for (Index k = begin; k < end; ++k) {
      Candidate& c = candidates_[k];
      if (!c.joined || c.sutured || !c.edges || !(distances_[k] < reach)) continue;
      // An edge inside a flat polygon needs no guard, nor do its faces give one: see flat_edge_.
      if (flat_edge_[static_cast<std::size_t>(c.a)] || flat_edge_[static_cast<std::size_t>(c.b)]) continue;
      if (!(c.faces & kFacesKnown)) c.faces = facing_faces(c);
      if (!(c.faces & ~kFacesKnown) && edge_triangle_start_[c.a + 1] - edge_triangle_start_[c.a] <= kFacesPerEdge &&
          edge_triangle_start_[c.b + 1] - edge_triangle_start_[c.b] <= kFacesPerEdge) {
        continue;  // no face of either edge faces the other's ends
      }
      const collision::Proximity& p = proximities_[k];
      const std::array<Index, 4> corner = corners(c);
      // The faces of edge (k0, k1), turned against a face around the other edge's corners; sign +1
      // when the faces are the second edge's (r points from them to the first edge), -1 otherwise.
      for (const auto& [first, second, sign] : {std::tuple{0, 2, 1.0}, std::tuple{2, 0, -1.0}}) {
        const auto edge = static_cast<std::size_t>(second == 0 ? c.a : c.b);
        const int bit = first == 0 ? 1 : 1 + kFacesPerEdge;
        for (Index i = edge_triangle_start_[edge]; i < edge_triangle_start_[edge + 1]; ++i) {
          const Index t = edge_triangles_[static_cast<std::size_t>(i)];
          const auto& tri = triangles_[static_cast<std::size_t>(t)];
          const Index face = i - edge_triangle_start_[edge];
          if (face < kFacesPerEdge ? !(c.faces & (1 << (bit + face))) : !ends_face(corner, first, t)) continue;
          const Vec3 normal = unit_normal(y_.row(tri[0]).transpose(), y_.row(tri[1]).transpose(), y_.row(tri[2]).transpose(), dhat);
          if (normal.isZero()) continue;
          // Both ends held to this plane by their own guards hold the edge (g is linear along it).
          const Vec3 on = y_.row(tri[0]).transpose();
          if (held(corner[static_cast<std::size_t>(first)], normal, on) && held(corner[static_cast<std::size_t>(first) + 1], normal, on)) continue;
          // Where the pair's point is an end of the edge (the other end's weight exactly 0) whose
          // own vertex guard lies on this face's plane in its copy, that guard is this guard: the
          // same plane, zero, wall and turn (see guarded_on_face). On the sliced ball the most
          // active terms in a step fell from 22.5k to 16.8k, on the hand's 9.9k to 7.7k.
          if (p.w[static_cast<std::size_t>(first) + 1] == 0 && guarded_on_face(corner[static_cast<std::size_t>(first)], t)) continue;
          if (p.w[static_cast<std::size_t>(first)] == 0 && guarded_on_face(corner[static_cast<std::size_t>(first) + 1], t)) continue;
          collision::Proximity foot = p;
          for (double& w : foot.w) w *= sign;
          const double zero = guard_zero(corner, foot.w, t);
          const double g = sign * normal.dot(p.r) - zero;
          // Found behind the whole allowance, the edges have passed what a guard allows (its wall
          // stands short of it, and the face turns within the step). Left unguarded, nothing held
          // them: at 1.2 s into Figure 4 a stick's rim passed its neighbour's this way, and was 6.7
          // allowances inside the neighbour one frame (5 steps) later, 16 at the last frame. Where
          // the first edge has crossed the other (the closest points inside both edges) into its
          // material (behind every face around it), it is guarded from where it is and pushed back
          // out, as a vertex found behind its triangle is; elsewhere (round the other edge's rim,
          // outside its material) it passed nothing.
          if (!(g > -delta) && !(p.free == 2 && behind_faces(edge, sign * p.r))) continue;
          // Its friction's start: r turned as the guard's (from the faces to the first edge).
          out->push_back({corner, foot.w, normal, zero, guard_wall(g, delta, recover), sign * p.r, p.distance, t, spring_cushion(k)});
        }
      }
    }
  });
  index_guard_triangles();
}

void SurfaceContact::index_guard_triangles() {
  // O(guards): the slots of the triangles met before are read back from the slot array, which is
  // valid for the triangles listed only (sized once for the surface).
  guard_triangle_slot_.resize(triangles_.size());
  guard_triangles_.clear();
  for (const Guard& guard : guards_) {
    const auto t = static_cast<std::size_t>(guard.triangle);
    const Index slot = guard_triangle_slot_[t];
    if (slot < static_cast<Index>(guard_triangles_.size()) && slot >= 0 && guard_triangles_[static_cast<std::size_t>(slot)] == guard.triangle) continue;
    guard_triangle_slot_[t] = static_cast<Index>(guard_triangles_.size());
    guard_triangles_.push_back(guard.triangle);
  }
}

double SurfaceContact::guard_cushion(std::uint64_t copies) const {
  if (!(settings_.cushion > 0)) return 0;
  const auto cut_step = [&](std::uint64_t copy) { return copy < copy_cut_step_.size() ? copy_cut_step_[copy] : steps_; };
  const auto age = static_cast<double>(steps_ - std::max(cut_step(copies >> 32), cut_step(copies & 0xffffffffu)));
  // Grown at a steady rate: sides that follow it part at cushion / kCushionSteps a step, and go
  // on at that speed once it stops where nothing else holds them (its spring only pushes).
  return settings_.cushion * std::clamp(age / kCushionSteps, 0.0, 1.0);
}

void SurfaceContact::update_joins(const Points& at) {
  ++steps_;
  if (!enabled() || joins_.empty()) return;
  const PartTimer timer(&part_seconds_.joins, &part_seconds_.rebuild);
  cover(at, nullptr, 0);
  // Every pair of joined copies is measured: the next step's guards, which start here, look at
  // them all. A join touches while any of its pairs (vertex-triangle or edges) is within dhat.
  measure(kJoined);
  // In parallel, each chunk listing the joins it found touching.
  const auto join_of = [&](const Candidate& c) {
    return static_cast<std::size_t>(std::lower_bound(joins_.begin(), joins_.end(), c.copies) - joins_.begin());
  };
  std::vector<std::size_t> found;
  append_chunks(static_cast<Index>(candidates_.size()), kNodeChunk, &found, [&](Index begin, Index end, std::vector<std::size_t>* out) {
    for (Index k = begin; k < end; ++k) {
      const Candidate& c = candidates_[static_cast<std::size_t>(k)];
      if (c.joined && !c.neighbouring && distances_[k] < settings_.thickness) out->push_back(join_of(c));
    }
  });
  std::vector<std::uint8_t> touching(joins_.size(), 0);
  for (const std::size_t join : found) touching[join] = 1;
  std::size_t kept = 0;
  for (std::size_t j = 0; j < joins_.size(); ++j) {
    if (touching[j]) joins_[kept++] = joins_[j];
  }
  if (kept == joins_.size()) return;
  joins_.resize(kept);
  // The pairs that count from now on were measured here as joined pairs, and none is within dhat
  // (a join ends only then): what was measured, and the active terms at these positions, hold.
  const unsigned measured = measured_;
  const bool active = active_current_, active_pairs = active_pairs_current_;
  mark_joined();
  measured_ = measured;
  active_current_ = active;
  active_pairs_current_ = active_pairs;
}

}  // namespace tetcut::sim::detail
