#pragma once
// Contact of the material surface with itself and between pieces: the simulator's part of the
// SSIF07 idea that cut pieces collide through their detailed surface, not their tets.
//
// The surface's vertices are embedded points (a tet copy and barycentric weights), so every
// vertex-triangle and edge-edge pair is a function of at most 16 nodes. Each pair closer than
// the contact thickness dhat adds kappa b(d), with d the pair's unsigned distance and b the IPC
// barrier (Li et al. 2020):
//     b(d) = -(d - dhat)^2 ln(d / dhat)  for 0 < d < dhat,  0 beyond,
// C2 at dhat and unbounded as d -> 0, so that together with a line search that never lets a
// pair reach d = 0 (conservative continuous collision detection, ACCD of Li et al. 2021) no two
// primitives ever pass through each other: not an energy that pushes "usually hard enough", but
// a guarantee up to the step's accuracy. kappa is in N/m (b is an area).
//
// The energy is exact; its gradient too (d's gradient is w r / |r| per corner by the envelope
// theorem, collision/proximity.hpp). For the Newton matrix each pair gives the positive
// semi-definite part kappa b''(d) grad d grad d^T of its Hessian: the dropped part,
// kappa b'(d) d'', is negative semi-definite wherever d is convex in the corners (b' <= 0), so
// what is kept is a convex model of the energy, as projecting element Hessians is. In node terms
// a pair is one point y = sum_n alpha_n x_n (r as a combination of the nodes), so it is a soft
// constraint of the kind the integrator already takes (SimulatorState::for_each_constraint).
//
// Which pairs count. Excluded for good: pairs sharing a surface vertex, and pairs whose copies
// are one copy or share a node (neighbours in the material, within a tet of each other: their
// surfaces meet by construction), where a vertex's copies are its own (the one it is embedded in)
// and those of its triangles, an edge's those of its triangles: a pair counts if any of its
// copies' pairs is apart, as the crossing check counts any pair of triangles of copies apart. (By
// their own copies alone, a coil of Figure 8's slinky, thinner than a tet, shares nodes with the
// next where one embeds a vertex, and 2.5k vertex-triangle pairs within dhat went unseen whose
// triangles the check counted: the coils crossed in up to 32 pairs as they bunched.) But where
// a cut runs between two copies that share a node, their surfaces do not meet by construction:
// pairs of such copies are taken where their sides face each other across a two-sided cut in the
// material (the triangle, or a face around one edge, lies on a cut with material on both sides,
// and a triangle around the vertex, or around a corner of the other edge, on such a cut is turned
// more than 120 degrees against it: the two sides of the cut between them). Within
// kNeighbourReach dhat of each other in the material they are joined for good (left to the
// guards, below); farther apart, slid along each other, they count. Without them the folded
// flap's sides, pressed together where its cut ends, crossed in 18 pairs, and the slinky's
// neighbouring coils (tets of 0.5 against a pitch of 0.42, so that their copies share nodes around
// the axis) in up to 524 over 1.4 s. The other pairs of such copies, a surface and its own
// neighbours around a shared node, meet only where the surface folds onto itself within a tet or
// two: left to the crossing check (listed, they made 12M candidates on the slinky; and a hand's
// slice meets its skin at a sharp rim, whose faces, turned against each other, guards held as
// if they were two sides of a cut). An embedded model's carved surface is one-sided, so the femur
// and the hand cut in two list no such pair and keep their cost. Not seen: a coil's rim pressed
// into the next coil's face where they meet at right angles, within the thickness of each other
// in the material (neither faces the other; the slinky crossed in up to 15 such pairs over 1.4 s).
// Excluded for a while: pairs of copies "joined across a cut",
// whose surfaces a cut has just made coincide (both sides of a fresh cut are at distance 0, where
// the barrier is infinite), that touched in the material (within the guards' allowance delta, below;
// or touched when the list was built), or lay there on the two sides of one cut, apart along it by
// less than dhat (all four corners within delta of the plane of a triangle of one primitive, which
// a triangle of the other faces: the two sides' triangulations of one cut surface, whose vertices
// the guards hold to it; counted, their barrier pushed the sides along the cut from the start: most
// of the slinky's 645k pairs active at rest); the other pairs of joined copies, apart when the cut was
// made, count as any others (sticks sliding along each other while their cut faces still touch
// elsewhere, and faces of neighbouring sticks a sliver apart in the material: their barrier is
// finite there and starts active). When the surface is set after a cut, a pair of copies becomes joined
// when one of them changed in that cut and some pair of their primitives is within dhat both in
// rest space and now, and the two are copies of tets that were neighbours before the cut (or at
// distance 0 now: touching from the start; separate objects that merely start close are not
// joined). The join lasts until no
// pair of their primitives is within dhat any more (checked after every step); from then on the
// copies collide like any others.
//
// Guards. While joined, the two sides of a cut are not left free to pass through each other:
// each step, every vertex-triangle pair of joined copies within dhat at its start, whose vertex
// faces the triangle in the material (one of the vertex's triangles turned more than 120 degrees
// against it: the other side of the cut, not the triangle's own neighbour) gets a guard, a
// one-sided barrier on the vertex's signed distance g in front of the triangle's plane,
//     kappa b(g + delta; delta)  for -delta < g < 0,  0 for g >= 0,
// with the triangle's unit normal and the vertex's foot on its plane (barycentric coordinates,
// which may lie beside the triangle by up to its size: pressed together, both sides bulge and a
// vertex on the rim slips past the edge of the triangles it lay on) held for the step, so that g
// is linear in the nodes and the term is exact with a positive semi-definite Hessian. Its zero
// is the fresh cut itself (g = 0), and the allowance delta = dhat / 10 is how far one side may be
// pressed into the other. The barrier's wall stands at 0.75 delta (the rest is room for the
// triangle's turn within the step, which carries its own plane past the one held: corners pressed
// to the wall at the bottom of Figure 4's pile were 1.0003 delta behind their triangles at the
// step's end); conservative advancement keeps every guard's g above the wall in the line search,
// as it keeps the pairs' distances above 0, and max_step bounds each move so that no guarded side
// lies deeper behind its triangle's own plane than the allowance (the held plane's error is
// (n - n0) . r, bounded per guard from its triangle's corners and r over the move: guards_share).
// A vertex that does not face the triangle in the material (it lies on the triangle's rim there:
// a cut's rim beside the other side's outer face, or meeting it at an angle) gets the same guard
// once it has swung over the triangle (its foot inside it, not on its rim) and one of its own
// triangles has turned more than 120 degrees against it by their positions at the step's start:
// two sticks hinged about the line where they touched until their outer faces faced each other,
// and one's corner went 1.3 allowances into the other's outer face with nothing holding it (81
// sticks, on one path). Faces still side by side, or only turned a little, get none, so that the
// sides may turn about the line where they touch either way.
// A vertex found behind the whole allowance at a step's
// start, over its triangle, is guarded from where it is, its wall a hundredth of delta deeper, so
// that the barrier pushes it back out (left unguarded, such a corner of Figure 4 sank 18
// allowances into the other stick in four steps); so is an edge found crossed into the other
// side's material (below). A guard's g is measured from where its
// pair lay in the material when that was behind the plane, less a millionth of the allowance, so
// that no guard pushes at rest: where two cuts meet, a side's rim is triangulated apart from the
// other side's faces, and some edge pairs lay up to 0.66 of the allowance behind (13 guards on
// 36 sticks, which pushed them along the cuts from the first step, in free fall), and the sides
// that coincide up to rounding loaded 33k guards there at a billionth of the allowance, a matrix
// block each. Triangles too flat for a normal (height
// below 1e-6 of their longest edge, or of dhat: fans over collinear points) guard nothing.
// Edges too: every edge-edge pair of joined copies within dhat whose one edge lies on a face that
// a face around the other edge's corners faces gets the same guard on the vector between their
// closest points along that face's normal (its closest points held for the step), unless both
// ends of the other edge are guarded against that plane already (g is linear along the edge), or
// the closest point is an end of the edge whose own vertex guard holds that face's plane (on the
// face, or on a triangle of its copy in its plane in the material: the same guard),
// and none for an edge inside a flat polygon of either side (see flat_edge_).
// Found behind the whole allowance at a step's start, such a pair is guarded from where it is
// where the edges have crossed into the material (the closest points inside both edges, behind
// every face around the face's edge), and left alone elsewhere (round the rim, outside): two of
// Figure 4's sticks pivoting about a shared corner carried one's rim past the other's, 0.99
// allowances in at one frame and 6.7 at the next, 16 at the last, with no guard.
// A vertex guard lapses once its vertex is more than dhat from the faces it faced; in a pile,
// where joins last, a stick that slides and turns against its neighbour carries both ends of a
// side's edge past the neighbour's faces, and without edge guards the edge sagged through the
// neighbour's corner, all its pairs there touching in the material (36 sticks: up to 100 crossing
// pairs; Figure 4 over 0.35 s: 585; none with them, a piled step 3.4 times as long on 36 sticks).
// Pulled apart, guards exert no force (g > 0), and the join ends once no pair is within dhat.
// A cushion (Settings::cushion, 0 unless asked for) adds to each guard a spring of stiffness
// kappa pushing its side up to the cushion above the zero, 0.5 kappa (cushion - g)^2 for
// g < cushion, the cushion grown at a steady rate over kCushionSteps steps after the later of
// its copies' last cuts. Held a thickness apart, the sides slide along the cut as any surfaces
// do: pressed within the allowance, a side that slid a few centimetres meets the other side's
// rims and copies it was never joined with at a gap of about 0, where their barrier, counted,
// holds it (a ball sliced at 31 degrees kept its cap, frictionless). The spring only pushes: its
// energy is convex and C1, and the barrier below the zero keeps its wall. Grown at once, it
// sprang the sides apart; grown steadily, sides that follow it drift apart at about its rate
// where nothing else holds them. Joined pairs are not counted, so guards are made for them out
// to dhat plus the cushion at a step's start (joined_reach), and the list and its measures reach
// that far: when guards reached dhat only, a cushion near dhat held the sides at the edge of
// that reach, and 81 sticks crossed in 5 pairs at one frame with a cushion of dhat (in none with
// half of it).
// Why this should not miss a real collision for long, and where it does: copies are joined only
// while some of their surfaces are still touching where they were cut apart; a copy spans one
// tet, so only the two sides of a cut within a tet of each other are affected, and there they are
// guarded, not ignored; what goes unseen is edge-edge crossings of joined copies whose edges lie
// on no faces turned against each other in the material, and vertices that do not face
// the triangle they approach in the material (a cut's rim meeting the other side's outer surface)
// while none of their faces has turned against it by 120 degrees, bounded by the allowance while
// their neighbours are guarded, and counted by the exact check (count_surface_intersections) if
// they go deeper. Pieces that stay in contact (a pile of sticks)
// stay joined for good, and there the vertex guards alone lapsed (a vertex carried more than dhat
// past the face it faced) while the edge behind it sagged through the neighbour's corner: Figure
// 4's pile crossed in up to 1,147 pairs, most deeper than six allowances; the edge guards (above)
// hold those edges. What is still unseen is a face of joined copies sagging through a corner
// with every edge and vertex of it unguarded. Sutures (springs across an incision)
// take the pairs between their copies that were within dhat in the material out, guards
// included, while they hold: they are there to bring the two sides back together (and the pairs
// of neighbouring copies with corners in sutured copies on both sides: near the incision's end).
//
// Broad phase: per copy, a box around the primitives it owns (a vertex's copy, a triangle's, an
// edge's first triangle's); pairs of copies whose boxes come within the radius rho, neighbours
// left out unless two-sided triangles around their primitives face each other (those list only
// the primitives they own), then their
// primitives against each other (and the primitives the copies' triangles
// share with copies that neighbour the other copy: each such pair once). Most primitives near a given one are in
// its own or neighbouring copies and never listed, so the work goes with the pairs of copies that
// can really touch (per primitive queries were 100 times slower on a fine embedded surface). The
// candidates (all pairs within rho at the reference positions) serve every evaluation whose
// vertices have moved less than (rho - dhat) / 2 from there (a Verlet list), and every move of
// conservative advancement whose two ends have, and are rebuilt otherwise; a list made for a move
// is made around the move's end with room for the move back and as much again beyond (a piece
// sliding along another goes on the same way in the next move). Under them a coarser Verlet list
// of the pairs of copies, found within rho plus room for 10 dhat of motion by a self-join of a box
// hierarchy over the copies (refitted), serves
// several rebuilds. Motions are measured piece by piece (the mesh's connected parts), relative
// to each other: within a piece against its own centre, between two by their boxes of motion or
// by the difference of their fitted turns, between pieces that lie apart by more than they moved
// not at all (see PieceMotion); by the nodes first (O(nodes)), by the vertices
// where that bound is too loose (O(V)); a list kept with no candidates places no vertex. The
// trust region (max_step) counts the same way: only pieces that may meet over the move. O(V + F + copy pairs
// x their primitives) per rebuild, O(C log C + copy pairs) more when the pairs are found again,
// C copies; O(nodes + candidates) per evaluation; all parallel; results do not depend on the
// number of threads.

#include <tetcut/cutter.hpp>
#include <tetcut/sim.hpp>

#include "collision/proximity.hpp"
#include "spatial/box_tree.hpp"

#include <array>
#include <limits>
#include <cstdint>
#include <span>
#include <vector>

namespace tetcut::sim::detail {

/// The IPC barrier b(d) and its first two derivatives (0 beyond dhat, +inf at d <= 0).
double barrier(double d, double dhat);
double barrier_first(double d, double dhat);
double barrier_second(double d, double dhat);

/// A guard's energy in its gap g over its zero (see Guards): below the zero the barrier
/// kappa b(g + wall; wall), +inf at g <= -wall; with a cushion, below it as well the spring
/// 0.5 kappa (cushion - g)^2. Its first and second derivatives in g into *first and *second.
double guard_energy(double g, double wall, double cushion, double kappa, double* first, double* second);

/// A pair's energy kappa b(d) at corners y (point and triangle, or two segments when `edges`),
/// with its exact gradient and Hessian in the 12 corner coordinates when asked (for checks; the
/// simulator's Newton matrix takes the positive semi-definite part, see above).
double pair_energy(const std::array<Vec3, 4>& y, bool edges, double dhat, double kappa, collision::Vec12* gradient = nullptr,
                   collision::Mat12* hessian = nullptr);

/// Smoothed Coulomb friction of one pair over a step (IPC's lagged friction, Li et al. 2020):
/// with u the closest points' relative displacement since the step's start and u_T its part
/// across the (lagged) normal n, D = mu lambda f0(|u_T|), f0(y) = y beyond eps and
/// -y^3 / (3 eps^2) + y^2 / eps + eps / 3 below (C1: static friction as a stiff spring below
/// eps). Returns D; the exact gradient and Hessian in u when asked. The Newton system takes that
/// Hessian as it is, for surface pairs and for points pressed into obstacles alike: it is
/// positive semi-definite, mu lambda (f1'(y) s s^T + f1(y)/y (P - s s^T)) with s the slip's
/// direction and P = I - n n^T, where f1' >= 0 (0 once the force saturates). The matrix
/// mu lambda f1(y)/y P, stiffer along the slip than the energy, made sliding contact's Newton
/// converge only linearly.
double friction_energy(const Vec3& u, const Vec3& n, double normal_force, double mu, double eps, Vec3* gradient = nullptr,
                       Mat3* hessian = nullptr);

/// One pair as a soft constraint: r = sum_i coefficients[i] x_{nodes[i]} (count distinct nodes),
/// with r and |r| where it was made (lagged friction's start). Kept to what its readers
/// need (it held the whole Proximity, 104 bytes more): every evaluation writes thousands of them
/// on the sliced hand, and reads them again.
struct ContactTerm {
  std::array<Index, 16> nodes;
  std::array<double, 16> coefficients;
  int count = 0;
  Vec3 r = Vec3::Zero();
  double distance = 0;
};

/// A term of for_each_active with its energy and derivatives in r.
struct ActiveTerm {
  ActiveTerm() {}  // filled in place by SurfaceContact::collect_active: emplace_back() zeroes nothing
  ContactTerm term;
  double energy;
  Vec3 gradient;
  Mat3 hessian;
};

class SurfaceContact {
 public:
  struct Settings {
    double thickness = 0;  ///< dhat
    double stiffness = 0;  ///< kappa
    double friction = 0;   ///< Coulomb coefficient mu (0: none)
    double cushion = 0;    ///< how far above the cut the guards push its sides, once grown (m)
  };

  bool enabled() const { return !triangles_.empty(); }
  const Settings& settings() const { return settings_; }

  /// Takes the surface (rest positions, its vertices embedded in the copies with `copy_nodes`)
  /// with the nodes' positions in the material (`rest`) and `now`; `changed`, per copy, whether
  /// the cuts since the last surface changed it (its joins are recomputed; the others' are
  /// kept). The settings are `options`, their zeros replaced by the defaults from the surface's
  /// mean edge length (and `youngs_modulus` for the stiffness). O(F log F + candidates).
  void set_surface(const MaterialSurface& surface, std::span<const std::array<Index, 4>> copy_nodes, const Points& rest, const Points& now,
                   std::span<const std::uint8_t> changed, const SurfaceContactOptions& options, double youngs_modulus);
  /// Drops the surface (a cut changes it; set it again), keeping the joins.
  void clear_surface();
  /// Forgets everything, joins included.
  void reset();

  /// Calls visit(term, energy, dE/dr, d2E/dr2) for every pair closer than dhat at node positions
  /// `at`, in a fixed order. Energy +inf (and zero derivatives) for a pair at distance 0.
  template <typename Visit>
  void for_each_active(const Points& at, Visit&& visit);
  /// The same terms, in fixed chunks whose concatenation is that order: for callers that take
  /// them in parallel. Valid until the next call that moves or changes the pairs.
  const std::vector<std::vector<ActiveTerm>>& active_chunks(const Points& at) {
    collect_active(at);
    return active_;
  }

  /// The largest t in (0, 1] such that moving the nodes from `from` along t * direction (3 per
  /// node) keeps every counted pair at a positive distance, with a margin: conservative
  /// advancement stops a pair at a tenth of its starting distance (each advance as far as the
  /// bound of its corners' relative speed allows, or as the pair stays apart along the direction
  /// between its closest points, whichever is further). 1 when nothing comes close. A direction
  /// moving parts of the surface more than two thicknesses relative to each other (their turns
  /// fitted and taken out where that shortens it) is taken in legs of that length (a trust
  /// region), each covered by its own candidate list, on to the next while nothing stops a leg
  /// short, at most kMaxLegs of them. Where guards hold the surface, the move stays within what
  /// their planes, held from the step's start, allow (guards_share).
  double max_step(const Points& from, const double* direction);

  /// Friction of the step starting at `start`: the pairs in contact there and the guards pressed
  /// (the two sides of a cut), each with its normal (the direction its barrier pushes) and normal
  /// force, held for the step (lagged). None when the friction coefficient is 0.
  void lag_friction(const Points& start);
  void drop_friction() { friction_.clear(); }
  /// Calls visit(term, energy, dE/du, d2E/du2) for each lagged pair at positions `at` (u the
  /// closest points' displacement since the start; the matrix takes mu lambda f1(y)/y (I - n n^T),
  /// positive semi-definite).
  template <typename Visit>
  void for_each_friction(const Points& at, Visit&& visit) const;

  /// After a step, at its final positions: joins whose copies have no pair within dhat end.
  void update_joins(const Points& at);

  /// The guards of the joined pairs for the step starting at `start` (see "Guards" above): each
  /// vertex-triangle pair of joined copies within dhat there whose vertex lies over the triangle
  /// and not behind it by more than the allowance, with the triangle's normal and the vertex's
  /// foot on it held for the step; and each edge-edge pair of joined copies within dhat with one
  /// edge on a face the other's faces face, unless both ends of that edge are guarded against the
  /// plane already, and not behind it by more than the allowance unless crossed into the
  /// material (see "Guards" above). O(candidates), in parallel.
  void lag_guards(const Points& start);
  Index num_guards() const { return static_cast<Index>(guards_.size()); }
  /// For tests: how far the deepest guarded vertex or edge lies behind its triangle's own plane
  /// (not the plane its guard holds from the step's start) at node positions `at`, beyond what
  /// its guard allows (guard_depth: the allowance, or, where a guard was made behind its wall to
  /// push a side back out, a hair beyond that wall). At most 0 while every guard holds.
  /// O(V + guards).
  double guard_excess(const Points& at) const;
  /// For tests: the deepest wall among the guards (how far behind its zero a guard's barrier
  /// stops), 0 without guards.
  double deepest_guard_wall() const;
  /// Whether the last max_step ended its move where the guards' planes, held since they were
  /// made, allowed (guards_share): the caller may make them again where it stands (lag_guards)
  /// before its next Newton iteration, so that a step in which faces turn and slide far against
  /// each other is not held to what one set of planes allows.
  bool guards_held_back() const { return guards_held_; }
  /// The allowance: how far behind its guard's triangle a vertex may go (a tenth of dhat).
  double guard_allowance() const { return kGuardShare * settings_.thickness; }
  static constexpr double kGuardShare = 0.1;
  /// Over how many steps after a cut the guards' cushion grows from 0 to Settings::cushion
  /// (see Guards): so that the sides part gently, not sprung apart at once.
  static constexpr int kCushionSteps = 30;
  /// The cushion of a guard between the pair of copies `copies` (Candidate::copies):
  /// Settings::cushion times the share of kCushionSteps passed since the later of their last cuts.
  double guard_cushion(std::uint64_t copies) const;
  /// How far apart joined pairs are listed, measured and guarded: dhat plus the cushion. Held by
  /// the cushion near it, the sides of a cut would otherwise sit at the edge of the guards' reach,
  /// with pairs just beyond it neither guarded nor counted for a step (81 sticks crossed in 5
  /// pairs at one frame with a cushion of dhat when guards reached dhat only). dhat without one.
  double joined_reach() const { return settings_.thickness + settings_.cushion; }
  /// Pairs of neighbouring copies (sharing a node; see faces_across_cut) facing each other
  /// across a cut closer than this many thicknesses in the material are left to the guards:
  /// beyond dhat, so that none pushes at rest, and beyond it again, so that the two sides of a
  /// cut, squeezed along themselves, do not push where they lay side by side.
  static constexpr double kNeighbourReach = 2;
  /// How far apart in the material a pair across a cut may lie and still be left to the guards
  /// (kNeighbourReach dhat): what the crossing check lets graze by the allowance.
  double guarded_reach() const { return kNeighbourReach * settings_.thickness; }

  /// Sutures: copies held to others across an incision by springs (Simulator::add_spring), whose
  /// springs pull the two sides back into coincidence where the barrier would keep them apart:
  /// pairs within dhat of each other in the material with a corner in a sutured copy, and all
  /// pairs between two copies one spring joins, are not counted while the springs hold. Kept across surfaces; cleared with the springs.
  void suture(Index copy_a, Index copy_b);
  void clear_sutures();

  Index num_candidates() const { return static_cast<Index>(candidates_.size()); }
  /// The candidates as (edges, a, b): a vertex and a triangle (0), or two edges (1), by their
  /// indices in edge_list(); how many were found through a copy not their own; and per pair
  /// whether the barrier counts it (neither joined nor sutured). For checks.
  std::vector<std::array<Index, 3>> candidate_pairs(Index* listed_apart = nullptr, std::vector<std::uint8_t>* counted = nullptr) const;
  const std::vector<std::array<Index, 2>>& edge_list() const { return edges_; }
  /// Whether edge e (of edge_list()) lies inside a flat polygon and so has no guards (flat_edge_).
  bool flat_edge(Index e) const { return flat_edge_[static_cast<std::size_t>(e)] != 0; }
  Index num_joins() const { return static_cast<Index>(joins_.size()); }
  Index num_rebuilds() const { return rebuilds_; }
  /// How often the pairs of copies under the candidates were found again (see copy_pairs_).
  Index num_pair_rebuilds() const { return pair_rebuilds_; }
  /// Wall seconds spent so far in each part (for benchmarks): rebuilding the candidates, and,
  /// apart from the rebuilds they set off, conservative advancement (max_step), the active
  /// terms (collect_active, measuring the pairs included), the guards at a step's start and the
  /// joins at its end.
  struct PartSeconds {
    double rebuild = 0, ccd = 0, active = 0, guards = 0, joins = 0;
  };
  const PartSeconds& part_seconds() const { return part_seconds_; }
  /// Mean edge length of the surface (the defaults are derived from it).
  double mean_edge_length() const { return mean_edge_; }

 private:
  struct Candidate {
    Index a, b;            // vertex and triangle, or two edges
    std::uint8_t edges;    // 0: vertex-triangle, 1: edge-edge
    std::uint8_t joined;      // of copies joined across a cut and rest_touching (not counted)
    std::uint8_t rest_close;  // within dhat in the material
    std::uint8_t rest_touching;  // within the guards' allowance in the material, or touching now, or
                                 // within dhat there on the two sides of one cut (across_one_cut)
    std::uint8_t sutured;     // rest_close between sutured copies (not counted)
    // Found through a copy that is not its primitive's own (see group_copy_): a vertex or an
    // edge whose own copy neighbours the other primitive's, listed by another copy around it.
    std::uint8_t listed_apart;
    // Of copies that share a node, facing each other across a cut (faces_across_cut): joined
    // for good where rest_touching (within kNeighbourReach dhat in the material, or touching now).
    std::uint8_t neighbouring;
    // Which of its faces guard it, by the material alone (see facing_faces): kFacesKnown once
    // found, the first time lag_guards asks; 0 before.
    std::uint8_t faces;
    std::uint64_t copies;     // the copy pair, (min << 32) | max
    // Its distance at reference_, where the list was made: at y_ it is at least this less
    // reference_relative_.
    double reference_distance;
  };
  /// Vertex v's share of the nodes' values: sum_i w_i node_value(n_i) over its copy's nodes (its
  /// position from the nodes' positions, its motion from theirs).
  template <typename NodeValue>
  Vec3 embedded(Index v, const NodeValue& node_value) const {
    Vec3 sum = Vec3::Zero();
    for (int i = 0; i < 4; ++i) sum += vertex_weights_[v][i] * node_value(vertex_nodes_[v][i]);
    return sum;
  }
  void place(const Points& at, Points* y) const;
  /// The active terms at `at` into active_: the counted pairs closer than dhat, in the
  /// candidates' order, then the guards' barriers where g < 0, in theirs. Made in parallel over
  /// fixed chunks (the terms and the barrier's logarithms, for about 4.5k pairs and 15k guards on
  /// the sliced hand, were a serial loop over the candidates each evaluation), visited in order.
  void collect_active(const Points& at);
  std::vector<std::vector<ActiveTerm>> active_;  // per chunk; kept, so that nothing is allocated
  // Whether active_ holds the terms at node positions active_at_: the last evaluation of a step
  // is where its end counts the active pairs.
  bool active_current_ = false;
  // Whether active_'s first active_pair_chunks_ chunks (the pairs' terms) hold at active_at_,
  // though the guards' may not: the guards are made again at each step's start, which is where
  // the last step's line search measured and collected the pairs (FirstGuess::kStart).
  bool active_pairs_current_ = false;
  Index active_pair_chunks_ = 0;
  Points active_at_;
  /// Makes the candidates cover positions `at` and, where given, the straight move from there to
  /// `move_end` (node positions), which moves near parts of the surface by at most
  /// `move_relative` relative to each other (max_step: the pieces that may meet over it).
  void cover(const Points& at, const Points* move_end, double move_relative);
  /// One leg of max_step's move: `share` of the nodes' `motion` from `from`, moving the parts that
  /// may meet by at most `relative` against each other. Covers it (move_end_ is its end) and
  /// returns the share of the leg that conservative advancement allows, for the pairs and guards.
  double leg_step(const Points& from, const Eigen::Map<const Points>& motion, double share, double relative);
  /// The largest share of the direction `motion` from `from` over which no guard's plane, held
  /// from the step's start, strays from its triangle's own by more than the guard's room.
  double guards_share(const Points& from, const Eigen::Map<const Points>& motion);
  /// guard_triangles_ and guard_triangle_slot_ for guards_.
  void index_guard_triangles();
  /// direction_move_: the vertices' motion along the direction, placed once a max_step call.
  void place_direction(const Eigen::Map<const Points>& motion);
  Points direction_move_, guard_from_;
  /// How a guard's triangle turns along a move (guards_share): its unit normal n and doubled area
  /// at the move's start, and the parts along and across n of its area vector's change, linear
  /// and quadratic in the move's share. The same for every guard of the triangle.
  struct TriangleTurn {
    Vec3 normal;
    double area, linear_along, square_along, linear_across, square_across;
  };
  /// The guards' triangles, each once, and each triangle's place among them (valid for those):
  /// made with the guards (a triangle holds 6 to 16 on the sliced hand).
  std::vector<Index> guard_triangles_, guard_triangle_slot_;
  std::vector<TriangleTurn> triangle_turns_;  // guards_share's scratch, by guard_triangles_
  bool direction_placed_ = false;
  bool guards_held_ = false;  // see guards_held_back
  // max_step's scratch: a leg's end (nodes), the direction's node motion (for place_direction)
  // and the vertices' motion over a leg.
  Points move_end_, node_move_, vertex_move_;
  Points leg_start_;                           // max_step's scratch: where a leg after the first starts
  std::vector<double> chunk_least_;  // max_step's scratch (min_chunks)
  /// How the surface moves, piece by piece (the mesh's connected parts, copies sharing nodes),
  /// when each node moves by some Vec3: per piece the centre of the box of its vertices' motions
  /// and the largest distance of one from it. Any point of the surface of piece p then moves
  /// relative to any of piece q by at most relative(p, q): twice the radius within one piece,
  /// the centres' distance and both radii between two. (One radius for the whole surface, as
  /// this was, made a piece falling away from another count as motion of every part against
  /// every other: the lists were made again every step, and each Newton move was cut to the
  /// trust region, so that a cut-off piece fell slower with self-collision on in the real-time
  /// solver, though nothing was near it. Smaller parts than pieces were measured and not kept:
  /// runs of 512 triangles in Morton order made the hanging femur's step 0.9 ms longer and saved
  /// 2 of its 41 rebuilds in 60 steps, for a turn of a part counts as motion as much as a fold.)
  struct PieceMotion {
    std::vector<Vec3> centre, half;  // the box's centre and half its extent
    std::vector<double> radius;
    // Where measured (piece_turn; else infinite and 0): the largest distance of a motion from
    // the least-squares fit of a translation and a turn, a + w x (x - c), and |w|. The turn moves
    // any two points across the line between them, so it brings no two closer: two points of
    // the piece come closer by at most twice `turned`.
    std::vector<double> turned, turn;
    // Where turned is finite: the fit as origin + rate x x, the box of the points it was made
    // about (the nodes), and a bound on a vertex's sum of |weights| over its nodes (the fit is
    // affine, so a vertex's fitted motion is its nodes' weighted by its weights).
    std::vector<Vec3> origin, rate;
    std::vector<spatial::Aabb> around;
    double weight_bound = 1;
    /// How much two points, of pieces p and q, come closer: between two pieces how far they move
    /// relative to each other (the distance of the centres and both radii, or of the farthest
    /// corners of their boxes, where that is less: a piece sliding along another while it sags),
    /// or, where both turns were fitted, fitted(p, q).closing where less; within one twice the
    /// radius or the turn's residual.
    double relative(Index p, Index q) const {
      const auto i = static_cast<std::size_t>(p), j = static_cast<std::size_t>(q);
      if (p == q) return 2 * std::min(radius[i], turned[i]);
      const double plain = moved_apart(i, j);
      return fits(i, j) ? std::min(plain, fitted(i, j).closing) : plain;
    }
    /// How far any point of piece i moves relative to any of piece j != i, from the boxes.
    double moved_apart(std::size_t i, std::size_t j) const {
      const Vec3 apart = (centre[i] - centre[j]).cwiseAbs();
      return std::min(apart.norm() + radius[i] + radius[j], (apart + half[i] + half[j]).norm());
    }
    bool fits(std::size_t i, std::size_t j) const { return std::isfinite(turned[i]) && std::isfinite(turned[j]); }
    /// From the two fits, for points x of p and y of q: their relative motion is
    /// F(x) + w_q x (x - y) + the residuals, F(x) = (o_p - o_q) + (w_p - w_q) x x (or the same
    /// with the pieces' roles swapped). The turn w_q moves x - y across itself, so it brings the
    /// two no closer: they close by at most |F| + both residuals (`closing`), |F| bounded over
    /// either piece's box (F is affine, so its norm is largest at a corner). Two pieces turning
    /// together, the halves of a cut block spinning, close by their residuals alone; counted by
    /// their whole relative motion, each Newton move was cut to the trust region. A pair that
    /// comes within dhat of each other starts within dhat + closing, so moves relative to each
    /// other by at most closing + |w| (dhat + closing), with w the turn of the piece whose box
    /// was not used (`turn`; max_step's list must reach that far). O(1).
    struct Fitted {
      double closing, turn;
    };
    Fitted fitted(std::size_t i, std::size_t j) const;
    /// At least relative(p, q) for any two pieces. O(pieces).
    double farthest() const;
  };
  /// Per piece, the box of its vertices at some positions, and the pieces by their boxes' low x
  /// (for for_near_pieces).
  struct PieceBoxes {
    std::vector<spatial::Aabb> boxes;
    std::vector<Index> by_low_x;
  };
  /// Elements (vertices or nodes) by piece, and work items over them: (piece, begin, end) into
  /// `elements`, at most kNodeChunk long, in order (so that per-piece results come out the same
  /// on any number of threads).
  struct PieceOrder {
    std::vector<Index> elements;
    std::vector<std::array<Index, 3>> items;
    bool identity = false;  // elements[k] == k (one piece's vertices)
    /// f(elements[k]) for first <= k < last; without reading them where they are k (the pass
    /// over the femur's vertices took 13% longer through them).
    template <typename F>
    void for_each(Index first, Index last, const F& f) const {
      if (identity) {
        for (Index k = first; k < last; ++k) f(k);
      } else {
        for (Index k = first; k < last; ++k) f(elements[static_cast<std::size_t>(k)]);
      }
    }
  };
  /// The pieces of copy_nodes_ that carry vertex_nodes_: pieces_, piece_vertices_, piece_nodes_.
  void find_pieces(Index nodes);
  /// Exactly, from the vertices: O(V), in parallel.
  template <typename NodeMotion>
  void vertex_motion(const NodeMotion& node_motion, PieceMotion* out) const;
  /// A bound from the nodes moving from `since` to `at` alone: a vertex moves by sum_i w_i d_i
  /// (the weights sum to 1), so from a centre c by at most sum_i |w_i| max_i |d_i - c|.
  /// O(surface nodes), 2.6k against 46k vertices on the femur; but loose after a cut, where
  /// nodes of copies with little material swing further than any vertex they carry.
  void node_motion(const Points& at, const Points& since, PieceMotion* out) const;
  /// Per piece the centre of its box of value(element), and `scale` times its half extent and
  /// the largest distance from the centre.
  template <typename Value>
  void piece_motion(const PieceOrder& order, const Value& value, double scale, PieceMotion* out) const;
  /// Fills out->turned and out->turn from value(element), the motions, and position(element),
  /// where the elements were: O(elements), two passes, in parallel.
  template <typename Value, typename Position>
  void piece_turn(const PieceOrder& order, const Value& value, const Position& position, double scale, PieceMotion* out) const;
  /// Per piece, the box of value(element) over its elements.
  template <typename Value>
  void item_boxes(const PieceOrder& order, const Value& value, std::vector<spatial::Aabb>* boxes) const;
  /// The pieces' boxes of position(v) over their vertices (none placed with one piece).
  template <typename Position>
  void piece_boxes(const Position& position, PieceBoxes* out) const;
  /// visit(p, q, gap) for every piece with itself (gap 0) and every two whose boxes lie within
  /// `within` of each other, until a visit returns false (then false).
  template <typename Visit>
  bool for_near_pieces(const PieceBoxes& boxes, double within, const Visit& visit) const;
  /// The pieces' motion from `since` (node positions, where the pieces lay in `boxes`) to `at`
  /// and, where given, to `move_end`. It holds where for every two pieces (and each with itself)
  /// the relative motion b, the larger at the two ends, has b + add <= limit, or their boxes lay
  /// apart by more than b + apart. `relative`: the largest b at `at` of the pieces whose boxes
  /// lay within `within` of each other. Each end from the nodes' bound first, from the vertices
  /// where that does not hold. O(near pairs of pieces) beyond the motions.
  struct MotionCheck {
    bool holds = false;
    double relative = 0;
  };
  MotionCheck check_motion(const Points& at, const Points* move_end, const Points& since, const PieceBoxes& boxes, double add,
                           double limit, double apart, double within) const;
  /// Lists the candidates within rho at reference_: made at y_ (`made_now`), or around a move's
  /// end, where whether a pair touches now is still measured at y_.
  void rebuild(double rho, bool made_now);
  /// Makes copy_pairs_ hold every pair of copies whose boxes (copy_boxes_) are within rho of each
  /// other: kept while the vertices' motion since it was made allows, else made again with room
  /// for kPairSlack * dhat more of it (on the hanging femur, 2 remade it at 75 of 105 rebuilds
  /// of the candidates, 10 at 26 and 30 at 10, whose longer list took longer to go through;
  /// 10 was fastest, and 3, 5 and 20 measured no better).
  void cover_copy_pairs(double rho);
  static constexpr double kPairSlack = 10;
  /// (copy, primitive) pairs, by primitive: the copies that list each vertex or edge.
  using Listing = std::vector<std::pair<Index, Index>>;
  /// Buckets the primitives by the copies that list them (group_copy_ and the CSR below it).
  void group_primitives(const Listing& vertices, const Listing& edges);
  /// set_surface's scratch, kept so that its memory is reused from one surface to the next: the
  /// femur's 93k triangles need about 12 MB of it, and touching that afresh after every cut (the
  /// pages faulted in one by one) took about 2 ms of the surface's 24 ms set-up for the edges'
  /// listing alone.
  struct EdgeChunk {
    struct Side {
      Index lower, higher, triangle, k;  // the edge's vertices, a triangle with it, its side there
    };
    std::vector<Side> sides;  // the chunk's vertices' sides, in (lower, higher, triangle, side) order
    Index edges = 0, first_edge = 0, first_side = 0;  // how many edges, where they and the sides start
    Listing listing;          // the chunk's part of the edges' listing
  };
  struct SurfaceScratch {
    std::vector<EdgeChunk> edge_chunks;
    std::vector<std::array<Index, 3>> triangle_edges;  // per triangle its edges, side k from corner k
    std::vector<double> edge_length;
    Listing edge_listing, vertex_listing;
    std::vector<Listing> vertex_chunks;
  } scratch_;
  /// The candidates' joined and sutured flags, from joins_ and sutured_.
  void mark_joined();
  /// proximities_ of the candidates at y_, in parallel, by kind (bits, which may be combined):
  /// those the barrier counts, the joined copies' vertex-triangle pairs (what the guards and the
  /// joins look at) or edge pairs, the others (sutured). Kinds measured at y_ already are kept,
  /// so that a step's end (the joins, then the count of active pairs) and the next step's start
  /// (the guards) measure each pair once; the kinds not asked for may hold anything. Right after
  /// a cut most of the list is joined pairs.
  enum Measure : unsigned { kCounted = 1, kJoinedVertexTriangle = 2, kJoinedEdges = 4, kJoined = 6, kOther = 8, kAll = 15 };
  static unsigned kind(const Candidate& c) {
    return c.joined ? (c.edges ? kJoinedEdges : kJoinedVertexTriangle) : c.sutured ? kOther : kCounted;
  }
  void measure(unsigned which = kAll);
  /// The positions changed, or which pairs count: nothing measured or collected holds.
  void forget_measures() {
    measured_ = 0;
    active_current_ = false;
    active_pairs_current_ = false;
  }
  collision::Proximity proximity(const Candidate& c, const Points& y) const;
  /// Whether a pair lies on the two sides of one cut in the material: all four corners within the
  /// guards' allowance of the plane of the second primitive's triangle or of one around its
  /// corners, which a triangle of the first faces (turned more than 120 degrees against it).
  /// O(triangles around its corners).
  bool across_one_cut(const Candidate& c) const;
  /// Whether the pair's sides face each other across a two-sided cut in the material: the
  /// triangle (or one around an edge) lies on such a cut, and a triangle around the vertex (or a
  /// corner of the other edge) on such a cut is turned more than 120 degrees against it. Not a
  /// face of the same material meeting a cut at a sharp rim (a hand's slice and its skin).
  bool faces_across_cut(const Candidate& c) const;
  /// Whether one of vertex v's triangles (of those on two-sided cuts, when asked) is turned more
  /// than 120 degrees against `normal` in the material (v on the other side of a cut from a
  /// triangle with that normal).
  bool vertex_faces(Index v, const Vec3& normal, bool on_two_sided_cut = false) const;
  /// Which faces of a pair a guard may hold it on, by the material alone, as Candidate::faces
  /// holds them: for a vertex and a triangle, bit 0 when the triangle has a normal there and the
  /// vertex faces it; for two edges, bit 1 + i when the i-th face around the second edge (i < 3)
  /// has a normal and an end of the first faces it, bit 4 + i the same with the edges' roles
  /// swapped; kFacesKnown always. The guards ask this of every joined pair each step (on the
  /// sliced ball, four times for each of 30k edge pairs), and the answer never changes.
  std::uint8_t facing_faces(const Candidate& c) const;
  /// Whether `triangle` has a normal in the material and an end of the edge at corner[first],
  /// corner[first + 1] faces it (the test behind facing_faces' bits for edges, asked directly
  /// of a face past the kFacesPerEdge-th).
  bool ends_face(const std::array<Index, 4>& corner, int first, Index triangle) const;
  static constexpr std::uint8_t kFacesKnown = 0x80;
  static constexpr int kFacesPerEdge = 3;
  /// The pair's four corners at vertex positions y (the vertex or first edge first).
  std::array<Vec3, 4> corner_positions(const Candidate& c, const Points& y) const;
  std::array<Index, 4> corners(const Candidate& c) const;
  /// The term of r = sum_i w_i corner_i in the nodes, into *t (its r and distance left as they are).
  void make_term(const std::array<Index, 4>& corner, const std::array<double, 4>& w, ContactTerm* t) const;
  bool neighbours(Index copy_a, Index copy_b) const;
  /// Whether two copies have corners at one rest point: copies of one tet, or of neighbours,
  /// before the cuts that separated them.
  bool rest_neighbours(Index copy_a, Index copy_b) const;

  Settings settings_;
  // The surface: vertices as nodes and weights, triangles and edges with their copies.
  std::vector<std::array<Index, 4>> vertex_nodes_;
  std::vector<Eigen::Vector4d> vertex_weights_;
  std::vector<Index> vertex_copy_;
  std::vector<std::array<Index, 3>> triangles_;
  std::vector<Index> triangle_copy_;
  std::vector<std::array<Index, 2>> edges_;
  std::vector<Index> edge_copy_;
  std::vector<std::array<Index, 4>> copy_nodes_;
  Points node_rest_;
  double mean_edge_ = 0;
  // Joined copy pairs, sorted; sutured copies (per copy id); the surface's rest positions.
  std::vector<std::uint64_t> joins_;
  std::vector<std::uint8_t> sutured_;
  std::vector<std::uint64_t> suture_pairs_;  // the copy pairs springs join, sorted
  // Lagged friction: per pair in contact at the step's start, its term, normal, normal force and
  // closest-point offset there.
  struct FrictionPair {
    ContactTerm term;
    Vec3 normal, start;
    double normal_force;
  };
  std::vector<FrictionPair> friction_;
  // Guards of joined pairs for the current step: r = sum_i w_i corner_i (a vertex less its foot on
  // the triangle, the foot's barycentric coordinates held; or the vector between two edges'
  // closest points), g = normal . r. Kept small (about a third of a ContactTerm): there are up to
  // 40k of them a step, read by every evaluation and every move of CCD, and only the few pushed
  // behind their zero become terms (guard_term).
  struct Guard {
    std::array<Index, 4> corner;
    std::array<double, 4> w;
    Vec3 normal;
    double zero;  // where the barrier starts: the pair's g in the material if behind, less the slack
    // How far behind its zero the barrier's wall stands: 0.75 of the allowance, or a little deeper
    // than a pair found behind that at the step's start (see lag_guards).
    double wall;
    // The guard's r and its length at the step's start (its lagged friction's start; the
    // friction's normal is the plane's).
    Vec3 start_r;
    double start_distance;
    Index triangle;  // whose plane it holds (a vertex guard's triangle, or a face around an edge guard's second edge)
    // Up to how far above its zero its spring pushes (guard_cushion): the cushion that parts the
    // two sides of the cut, grown since the cut; 0 without one.
    double cushion;
  };
  /// Whether triangle t is `face` or a triangle of its copy in its plane in the material (rest
  /// normals within kFlatFold, corners on the plane within kFlatFold mean edges): one plane for
  /// good, since a copy moves affinely.
  bool on_face_plane(Index t, Index face) const;
  /// Whether triangles t and u are of one copy with rest normals within kFlatFold of each other
  /// (both with a normal): in one plane where they share an edge (flat_edge_), parallel elsewhere.
  bool parallel_in_one_copy(std::size_t t, std::size_t u) const;
  /// A guard's r = sum_i w_i corner_i at vertex positions (or motions) y.
  static Vec3 guard_vector(const Guard& guard, const Points& y);
  /// A guard's g at vertex positions y, less its zero.
  static double guard_gap(const Guard& guard, const Points& y);
  void guard_term(const Guard& guard, ContactTerm* t) const;
  /// A guard's zero: its g in the material where the pair lay behind the plane there (the rims of
  /// cuts that meet at a junction, whose faces were triangulated apart), so that no guard pushes
  /// at rest; less kGuardSlack of the allowance, so that sides that coincide up to rounding load
  /// none. The guard's term is r = sum_i w_i corner_i, its plane that of `triangle`.
  double guard_zero(const std::array<Index, 4>& corner, const std::array<double, 4>& w, Index triangle) const;
  /// How deep behind its triangle's own plane a guard lets its side go: the allowance, or, for a
  /// guard made where its side lay behind the wall already, a hair deeper than its wall.
  double guard_depth(const Guard& guard) const;
  /// How much deeper than its side a guard found past its wall gets its wall, in allowances
  /// (kRecoverShare, or kCushionRecoverShare with a cushion).
  double recover_share() const;
  static constexpr double kGuardSlack = 1e-6;
  std::vector<Guard> guards_;
  // Steps ended (update_joins), and per copy the count when a cut last changed it: the cushion's
  // age. Kept across surfaces, as the copies are.
  std::int64_t steps_ = 0;
  std::vector<std::int64_t> copy_cut_step_;
  std::vector<Index> first_vertex_guard_;  // lag_guards' scratch: per vertex its first guard, or -1
  bool sutures_changed_ = false;
  Points rest_y_;
  // Per triangle its unit normal in the material; per vertex its triangles (CSR).
  std::vector<Vec3> rest_normals_;
  std::vector<Index> vertex_triangle_start_, vertex_triangles_;
  // Per edge its triangles, ascending (CSR).
  std::vector<Index> edge_triangle_start_, edge_triangles_;
  // Per edge, whether it lies inside a flat polygon: its two triangles are of one copy and in one
  // plane in the material, so in one plane always (a copy moves affinely). The guards leave out
  // the pairs of such an edge. Why nothing is lost: a guard holds a side's points in front of
  // one plane of the other side, through one flat polygon Q of it. In front is an affine
  // condition on each flat polygon P of the side, so it holds on all of P over Q where it holds
  // at the corners of P over Q: P's corners over Q (vertex guards), Q's corners under P (the
  // other side's vertex guards, on P's plane: the same condition where the planes are parallel,
  // as the two sides of a cut are), and the crossings of P's rim with Q's (edge guards). A point
  // of an edge inside P or inside Q is none of those. On the sliced ball, 42% of the joined edge
  // pairs within dhat have such an edge (fans over the cut's polygons).
  std::vector<std::uint8_t> flat_edge_;
  // The Verlet list: candidates within rho_ of each other at vertex positions reference_.
  std::vector<Candidate> candidates_;
  std::vector<collision::Proximity> proximities_;
  // Their distances apart: the passes over the candidates that ask only which pairs are within
  // dhat read 8 bytes a pair, not a Proximity's 136 (on the sliced ball, 60k pairs several times
  // a step: most of those passes' time went to reading them).
  std::vector<double> distances_;
  Points reference_, y_, placed_;
  // The node positions y_ was placed from (see cover).
  Points y_nodes_;
  // The nodes' positions where the candidates were listed (reference_ is the vertices').
  Points reference_nodes_;
  // A bound of how far the vertices at y_ have moved from reference_ relative to each other,
  // where they may be listed (set by cover). A pair listed farther apart than dhat by more than
  // this is not measured: its distance is surely beyond dhat (most of a list, which reaches rho;
  // on the sliced hand 31k of the 34k counted pairs an evaluation measured were beyond dhat, and
  // this leaves 39% of them out: a list made around a move's end starts that move's sweep away).
  double reference_relative_ = std::numeric_limits<double>::infinity();
  // The share of dhat by which such a bound must clear what it decides (for rounding).
  static constexpr double kBoundSlack = 1e-6;
  // The largest sum of |weights| of a vertex.
  double weight_bound_ = 1;
  // The pieces, numbered by their first vertex, and their vertices and the nodes that carry them.
  Index pieces_ = 0;
  PieceOrder piece_vertices_, piece_nodes_;
  // Each vertex's piece.
  std::vector<Index> vertex_piece_;
  // The pieces' boxes at reference_, and at the vertices of pairs_reference_.
  PieceBoxes reference_boxes_, pairs_boxes_;
  // Scratch of the motions, and max_step's: the move's motion, the motion since the list, the
  // pieces' boxes where the move starts.
  mutable std::vector<spatial::Aabb> item_boxes_, piece_scratch_;
  mutable std::vector<double> item_largest_;
  mutable PieceMotion motion_scratch_;
  // piece_turn's: per item the sums of a piece's count, |x|^2, x, d, x x d and x x^T; per piece
  // the fit's centre, translation and turn; the nodes' turns while the vertices are measured.
  struct TurnSums {
    double count = 0, squares = 0;
    Vec3 position = Vec3::Zero(), motion = Vec3::Zero(), cross = Vec3::Zero();
    Mat3 outer = Mat3::Zero();
    spatial::Aabb around;  // of the positions
  };
  mutable std::vector<TurnSums> turn_sums_, piece_turn_sums_;
  mutable std::vector<Vec3> turn_centre_, turn_motion_, turn_rate_;
  mutable std::vector<double> nodes_turned_, nodes_turn_;
  PieceMotion move_motion_, from_motion_;
  PieceBoxes from_boxes_;
  // The kinds of candidates proximities_ hold at y_ (Measure bits).
  unsigned measured_ = 0;
  double rho_ = -1;
  // The primitives by copy (CSR over group_copy_, the copies that own primitives, ascending), and
  // a box hierarchy over each copy's primitives. A vertex is listed by its own copy and by the
  // copies of its other triangles, an edge by the copies of all its triangles (its own, the
  // first's, first): see set_surface.
  std::vector<Index> group_copy_;
  std::vector<Index> copy_group_;  // per copy its group, or -1
  // Per triangle: on a two-sided cut (a cut triangle with material on both sides somewhere; not
  // an embedded model's carved surface). Per group (CSR): the rest normals of such triangles
  // around the primitives it owns. Pairs of copies that share a node are listed too
  // (copy_pairs_) where two of those normals are turned against each other.
  std::vector<std::uint8_t> two_sided_triangle_;
  std::vector<Index> group_facing_start_;
  std::vector<Vec3> group_facing_;
  std::vector<Index> vertex_start_, group_vertices_, triangle_start_, group_triangles_, edge_start_, group_edges_;
  std::vector<spatial::Aabb> copy_boxes_;  // at reference_
  // A second, coarser list under the candidates: the pairs of copies (group indices g < h, not
  // neighbours unless group_facing_ says they may face each other) whose boxes came within
  // pairs_radius_ of each other at pairs_reference_. It
  // outlasts several rebuilds of the candidates, which then look only at these pairs instead of
  // querying the hierarchy once per copy (on the hanging femur that was most of a rebuild: about
  // 18 copies met per query, of which all but a few were the copy itself or its neighbours).
  std::vector<std::array<Index, 2>> copy_pairs_;
  Points pairs_reference_;
  double pairs_radius_ = -1;
  spatial::BoxTree copy_tree_;
  bool tree_built_ = false;
  Index rebuilds_ = 0, pair_rebuilds_ = 0;
  PartSeconds part_seconds_;
};

template <typename Visit>
void SurfaceContact::for_each_active(const Points& at, Visit&& visit) {
  if (!enabled()) return;
  collect_active(at);
  for (const std::vector<ActiveTerm>& chunk : active_) {
    for (const ActiveTerm& a : chunk) visit(a.term, a.energy, a.gradient, a.hessian);
  }
}

template <typename Visit>
void SurfaceContact::for_each_friction(const Points& at, Visit&& visit) const {
  // The smoothing: slips below a hundredth of the thickness per step are held as by a spring.
  const double eps = 0.01 * settings_.thickness;
  for (const FrictionPair& f : friction_) {
    Vec3 u = -f.start;
    for (int a = 0; a < f.term.count; ++a) u += f.term.coefficients[a] * at.row(f.term.nodes[a]).transpose();
    Vec3 g;
    Mat3 matrix;
    const double energy = friction_energy(u, f.normal, f.normal_force, settings_.friction, eps, &g, &matrix);
    visit(f.term, energy, g, matrix);
  }
}

}  // namespace tetcut::sim::detail
