// Surface contact (see surface_contact.hpp): the surface taken from a cut, its candidate pairs
// (a Verlet list over box hierarchies), the barrier's terms, conservative advancement, and the
// joins of copies a cut has just separated.

#include "sim/surface_contact.hpp"

#include "sim/block_sparse.hpp"
#include "util/stopwatch.hpp"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace tetcut::sim::detail {
namespace {

// Conservative advancement stops a pair once it would come closer than this share of the
// distance it started the move at (Li et al. 2021 use 0.1 too): the line search then starts from a
// point the barrier can still see, and no pair is ever brought to 0.
constexpr double kKeepShare = 0.1;
// Each advance covers this share of the distance left over the motion bound: a margin for the
// rounding of the distance computed.
constexpr double kAdvanceShare = 0.9;
// Conservative advancement gives up refining after this many advances and keeps the safe time
// reached (the next Newton iteration goes on).
constexpr int kMaxAdvances = 64;
// The farthest one leg of a Newton step may move the surface's parts that may meet over it from
// the middle of their motions (relative to each other: twice this), in contact thicknesses: a
// longer direction is taken in legs of that length, each checked by continuous collision
// detection in turn (a trust region; pieces that stay apart over the whole move do not count).
// A leg's candidate list covers that leg (radius 2 dhat + its relative motion), and its pairs
// grow as the cube of the leg: one list for a wild direction on Figure 4's pile (500 to 700 dhat)
// ran out of 16 GB, and 10 dhat still took 12 GB there. At 2, the scenes' ordinary steps take one
// leg (the flap's needed more 41 times in 150 steps, 36 sticks' twice).
constexpr double kMaxSweep = 2;
// The most legs one Newton move may take (see max_step): 64 thicknesses of relative motion where
// each leg is the trust region's length, more where legs grow (kMaxLegGrowth).
constexpr int kMaxLegs = 16;
// How long a leg may grow where the lists of the legs before it came out empty, in trust regions:
// so that no list reaches far (a leg's list covers twice its relative motion and 2 dhat), where a
// doubling leg would reach across a gap to another piece and list every pair of their faces.
constexpr double kMaxLegGrowth = 4;
// Bisections for the share of a move a guard allows (guards_share): to 2^-30 of the move.
constexpr int kGuardBisections = 30;
// The largest turn (radians, of the linear fit to a piece's motion) one Newton move may take where
// the trust region takes the turn out. A list made at the move's end then bounds how much its
// pairs were closer at the move's start (a turn along a straight move stretches pairs, by up to
// |w|^2 / 2 of their length) by the move's own bound: at a half, with room to spare.
constexpr double kMaxTurn = 0.5;
// A triangle whose height is below this share of its longest edge, or of the contact thickness
// where that is longer, has no normal a guard could use: fans over the surface's polygons make
// triangles of collinear points and of points a rounding apart (exactly, in the material), whose
// rounded corners give them a normal in any direction.
constexpr double kFlat = 1e-6;
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

// Adds a scope's wall time to *total, less what *rebuild (the rebuilds' total) grew by within it:
// the rebuilds a part sets off are counted apart.
class PartTimer {
 public:
  PartTimer(double* total, const double* rebuild) : total_(total), rebuild_(rebuild), rebuild_start_(rebuild ? *rebuild : 0.0) {}
  PartTimer(const PartTimer&) = delete;
  PartTimer& operator=(const PartTimer&) = delete;
  ~PartTimer() { *total_ += seconds_since(start_) - (rebuild_ ? *rebuild_ - rebuild_start_ : 0.0); }

 private:
  double* total_;
  const double* rebuild_;
  double rebuild_start_;
  Clock::time_point start_ = Clock::now();
};

// The unit normal of triangle (a, b, c), or zero where it is flat for a scale of `length`.
Vec3 unit_normal(const Vec3& a, const Vec3& b, const Vec3& c, double length) {
  const Vec3 n = (b - a).cross(c - a);
  const double longest = std::sqrt(std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()}));
  return n.norm() > kFlat * longest * std::max(longest, length) ? Vec3(n.normalized()) : Vec3::Zero();
}

// A guard's vertex faces its triangle when one of its triangles' normals makes an angle of more
// than 120 degrees with the triangle's in the material (the two sides of a cut: 180).
constexpr double kFacing = 0.5;

// A lower bound of the distance between a pair's two primitives (the vertex, or the first edge,
// against the rest): how far apart their boxes are along the axis that separates them most.
// About a tenth of an exact distance's cost, and most listed pairs are farther apart than the
// thickness (on a hand cut in two, sliding: 5k of 29k within it), so the exact distance is taken
// only where this cannot decide.
double gap_between(const std::array<Vec3, 4>& y, bool edges) {
  const int split = edges ? 2 : 1;
  double gap = 0;
  for (int k = 0; k < 3; ++k) {
    double lo_a = y[0][k], hi_a = y[0][k], lo_b = y[split][k], hi_b = y[split][k];
    for (int i = 1; i < split; ++i) lo_a = std::min(lo_a, y[i][k]), hi_a = std::max(hi_a, y[i][k]);
    for (int i = split + 1; i < 4; ++i) lo_b = std::min(lo_b, y[i][k]), hi_b = std::max(hi_b, y[i][k]);
    gap = std::max({gap, lo_b - hi_a, lo_a - hi_b});
  }
  return gap;
}

// The proximity of a pair at its corner positions (vertex and triangle, or two segments).
collision::Proximity proximity_at(const std::array<Vec3, 4>& y, bool edges) {
  return edges ? collision::segment_segment(y[0], y[1], y[2], y[3]) : collision::point_triangle(y[0], y[1], y[2], y[3]);
}

// The same into *p where the boxes come within `reach` of each other; beyond, only p's distance,
// set to infinity (the readers ask only whether a pair is within reach).
void measure_within(const std::array<Vec3, 4>& y, bool edges, double reach, collision::Proximity* p) {
  if (gap_between(y, edges) < reach) {
    *p = proximity_at(y, edges);
  } else {
    p->distance = std::numeric_limits<double>::infinity();
  }
}

std::uint64_t copy_pair(Index a, Index b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
  return lo << 32 | hi;
}

}  // namespace

double barrier(double d, double dhat) {
  if (d >= dhat) return 0;
  if (!(d > 0)) return std::numeric_limits<double>::infinity();
  return -(d - dhat) * (d - dhat) * std::log(d / dhat);
}

double barrier_first(double d, double dhat) {
  if (d >= dhat || !(d > 0)) return 0;
  return -2 * (d - dhat) * std::log(d / dhat) - (d - dhat) * (d - dhat) / d;
}

double barrier_second(double d, double dhat) {
  if (d >= dhat || !(d > 0)) return 0;
  const double q = (d - dhat) / d;
  return -2 * std::log(d / dhat) - 4 * q + q * q;
}

double guard_energy(double g, double wall, double cushion, double kappa, double* first, double* second) {
  *first = *second = 0;
  if (!(g < cushion) && !(g < 0)) return 0;
  const double height = g + wall;
  if (!(height > 0)) return std::numeric_limits<double>::infinity();
  double energy = 0;
  // The cushion: a spring pushing the side up to `cushion` above the zero.
  if (cushion > 0 && g < cushion) {
    const double under = cushion - g;
    energy = 0.5 * kappa * under * under;
    *first = -kappa * under;
    *second = kappa;
  }
  // Below the zero the barrier, which holds the side above its wall.
  if (g < 0) {
    energy += kappa * barrier(height, wall);
    *first += kappa * barrier_first(height, wall);
    *second += kappa * barrier_second(height, wall);
  }
  return energy;
}

double pair_energy(const std::array<Vec3, 4>& y, bool edges, double dhat, double kappa, collision::Vec12* gradient,
                   collision::Mat12* hessian) {
  const collision::Proximity p = proximity_at(y, edges);
  const double d = p.distance;
  const bool active = d < dhat && d > 0;
  if (gradient) *gradient = active ? collision::Vec12(kappa * barrier_first(d, dhat) * collision::distance_gradient(p)) : collision::Vec12::Zero();
  if (hessian) {
    if (active) {
      const collision::Vec12 g = collision::distance_gradient(p);
      *hessian = kappa * (barrier_second(d, dhat) * g * g.transpose() + barrier_first(d, dhat) * collision::distance_hessian(p, y));
    } else {
      hessian->setZero();
    }
  }
  return kappa * barrier(d, dhat);
}

double friction_energy(const Vec3& u, const Vec3& n, double normal_force, double mu, double eps, Vec3* gradient, Mat3* hessian) {
  const Mat3 P = Mat3::Identity() - n * n.transpose();
  const Vec3 ut = P * u;
  const double y = ut.norm(), scale = mu * normal_force;
  double f0, g, dg;  // f0(y); g = f1(y) / y and its derivative in y
  if (y < eps) {
    f0 = -y * y * y / (3 * eps * eps) + y * y / eps + eps / 3;
    g = 2 / eps - y / (eps * eps);
    dg = -1 / (eps * eps);
  } else {
    f0 = y;
    g = 1 / y;
    dg = -1 / (y * y);
  }
  if (gradient) *gradient = scale * g * ut;
  if (hessian) {
    *hessian = scale * g * P;
    if (y > 0) *hessian += scale * dg / y * ut * ut.transpose();
  }
  return scale * f0;
}

void SurfaceContact::lag_friction(const Points& start) {
  friction_.clear();
  if (!enabled() || !(settings_.friction > 0)) return;
  // A term's normal is the direction its barrier pushes the first primitive, -dE / |dE| (b' < 0):
  // r / |r| for a pair, the plane's normal for a guard. Taken from a guard's own r, it left the
  // vertex guards without friction (their r was stored as 0) and gave edge guards a normal
  // rounded from a gap of almost 0 between the coincident sides of a cut: a block's upper half
  // resting on its lower half across their cut, tilted 20 degrees with mu = 0.5, slid 4.5 cm in
  // 0.3 s (5 mm now, the smoothing's creep).
  for_each_active(start, [&](const ContactTerm& t, double, const Vec3& dE, const Mat3&) {
    const double force = dE.norm();
    if (!(force > 0)) return;
    friction_.push_back({t, -dE / force, t.r, force});
  });
}

void SurfaceContact::reset() {
  clear_surface();
  joins_.clear();
  copy_cut_step_.clear();
  steps_ = 0;
  sutured_.clear();
  suture_pairs_.clear();
}

void SurfaceContact::clear_surface() {
  vertex_nodes_.clear();
  vertex_weights_.clear();
  vertex_copy_.clear();
  triangles_.clear();
  triangle_copy_.clear();
  edges_.clear();
  edge_copy_.clear();
  edge_triangle_start_.assign(1, 0);
  edge_triangles_.clear();
  copy_nodes_.clear();
  pieces_ = 0;
  vertex_piece_.clear();
  piece_vertices_ = {};
  piece_nodes_ = {};
  candidates_.clear();
  proximities_.clear();
  distances_.clear();
  friction_.clear();
  guards_.clear();
  rho_ = -1;
  y_nodes_.resize(0, 3);
  forget_measures();
  tree_built_ = false;
  pairs_radius_ = -1;
  group_copy_.clear();
  group_facing_start_.clear();
  group_facing_.clear();
  two_sided_triangle_.clear();
}

bool SurfaceContact::neighbours(Index a, Index b) const {
  if (a == b) return true;
  const auto& p = copy_nodes_[static_cast<std::size_t>(a)];
  const auto& q = copy_nodes_[static_cast<std::size_t>(b)];
  for (const Index n : p) {
    if (std::find(q.begin(), q.end(), n) != q.end()) return true;
  }
  return false;
}

bool SurfaceContact::rest_neighbours(Index a, Index b) const {
  for (const Index p : copy_nodes_[static_cast<std::size_t>(a)]) {
    for (const Index q : copy_nodes_[static_cast<std::size_t>(b)]) {
      if (node_rest_.row(p) == node_rest_.row(q)) return true;
    }
  }
  return false;
}

void SurfaceContact::set_surface(const MaterialSurface& surface, std::span<const std::array<Index, 4>> copy_nodes, const Points& rest,
                                 const Points& now, std::span<const std::uint8_t> changed, const SurfaceContactOptions& options,
                                 double youngs_modulus) {
  node_rest_ = rest;
  clear_surface();
  const TriangleSurface& s = surface.surface;
  const auto V = static_cast<std::size_t>(s.num_vertices()), F = static_cast<std::size_t>(s.num_triangles());
  copy_nodes_.assign(copy_nodes.begin(), copy_nodes.end());
  // The cushion grows anew between copies a cut made or changed.
  copy_cut_step_.resize(copy_nodes_.size(), steps_);
  for (std::size_t copy = 0; copy < std::min(changed.size(), copy_cut_step_.size()); ++copy) {
    if (changed[copy]) copy_cut_step_[copy] = steps_;
  }
  vertex_nodes_.resize(V);
  vertex_weights_.resize(V);
  vertex_copy_.resize(V);
  weight_bound_ = 1;
  for (std::size_t v = 0; v < V; ++v) {
    vertex_copy_[v] = surface.vertex_tet[v];
    vertex_nodes_[v] = copy_nodes_[static_cast<std::size_t>(vertex_copy_[v])];
    vertex_weights_[v] = surface.vertex_weights.row(static_cast<Index>(v)).transpose();
    weight_bound_ = std::max(weight_bound_, vertex_weights_[v].cwiseAbs().sum());
  }

  triangles_.resize(F);
  triangle_copy_.assign(surface.triangle_tet.begin(), surface.triangle_tet.end());
  for (std::size_t t = 0; t < F; ++t) {
    for (int k = 0; k < 3; ++k) triangles_[t][k] = s.triangles(static_cast<Index>(t), k);
  }
  // Each vertex's triangles, ascending (CSR): for the edges below, the guards (lag_guards) and
  // the listing of vertices. O(V + F).
  incidence<3>(static_cast<Index>(V), triangles_, &vertex_triangle_start_, &vertex_triangles_);
  // Edges, each once, ascending by (lower, higher) vertex, each with its triangles ascending and
  // the copy of the first: found around each edge's lower vertex, among that vertex's triangles.
  // O(F) with a small sort per vertex. (A sort of all 3F sides was a third of the surface's set-up
  // after each cut of the femur, 93k triangles: about 25 ms of 70.) In parallel over fixed chunks
  // of the vertices: each chunk finds its vertices' sides, then, placed after the chunks before
  // it, writes its edges; the same edges in the same order as one pass over the vertices (the
  // serial pass was 7.3 ms of the about 24 ms each cut of the femur spent here, its reads of the
  // triangles scattered).
  const auto list_once = [](Listing* listing, std::size_t first, Index copy, Index primitive) {
    const auto listed = [&](const auto& entry) { return entry.first == copy; };
    if (std::none_of(listing->begin() + static_cast<std::ptrdiff_t>(first), listing->end(), listed)) listing->emplace_back(copy, primitive);
  };
  Listing& edge_listing = scratch_.edge_listing;
  Listing& vertex_listing = scratch_.vertex_listing;
  edge_listing.clear();
  vertex_listing.clear();
  std::vector<std::array<Index, 3>>& triangle_edges = scratch_.triangle_edges;
  triangle_edges.resize(F);
  using Side = EdgeChunk::Side;
  const auto vertex_count = static_cast<Index>(V);
  std::vector<EdgeChunk>& edge_chunks = scratch_.edge_chunks;
  edge_chunks.resize(static_cast<std::size_t>((vertex_count + kNodeChunk - 1) / kNodeChunk));
  for_chunks(vertex_count, kNodeChunk, [&](Index begin, Index end, Index chunk) {
    EdgeChunk& mine = edge_chunks[static_cast<std::size_t>(chunk)];
    mine.sides.clear();
    mine.listing.clear();
    mine.edges = 0;
    for (Index a = begin; a < end; ++a) {
      const std::size_t first = mine.sides.size();
      for (Index i = vertex_triangle_start_[a]; i < vertex_triangle_start_[a + 1]; ++i) {
        const Index t = vertex_triangles_[static_cast<std::size_t>(i)];
        if (i > vertex_triangle_start_[a] && vertex_triangles_[static_cast<std::size_t>(i) - 1] == t) continue;  // a repeated corner
        const auto& c = triangles_[static_cast<std::size_t>(t)];
        for (int k = 0; k < 3; ++k) {
          const Index p = c[static_cast<std::size_t>(k)], q = c[static_cast<std::size_t>((k + 1) % 3)];
          if (std::min(p, q) == a) mine.sides.push_back({a, std::max(p, q), t, k});
        }
      }
      // Met in (triangle, side) order: a stable insertion sort by the other vertex (a dozen
      // sides) leaves them in (higher, triangle, side) order.
      for (std::size_t i = first + 1; i < mine.sides.size(); ++i) {
        const Side side = mine.sides[i];
        std::size_t j = i;
        for (; j > first && mine.sides[j - 1].higher > side.higher; --j) mine.sides[j] = mine.sides[j - 1];
        mine.sides[j] = side;
      }
      for (std::size_t i = first; i < mine.sides.size(); ++i) {
        if (i == first || mine.sides[i].higher != mine.sides[i - 1].higher) ++mine.edges;
      }
    }
  });
  Index edge_total = 0, side_total = 0;
  for (EdgeChunk& chunk : edge_chunks) {
    chunk.first_edge = edge_total;
    chunk.first_side = side_total;
    edge_total += chunk.edges;
    side_total += static_cast<Index>(chunk.sides.size());
  }
  edges_.resize(static_cast<std::size_t>(edge_total));
  edge_copy_.resize(static_cast<std::size_t>(edge_total));
  edge_triangles_.resize(static_cast<std::size_t>(side_total));
  edge_triangle_start_.resize(static_cast<std::size_t>(edge_total) + 1);
  std::vector<double>& edge_length = scratch_.edge_length;
  edge_length.resize(static_cast<std::size_t>(edge_total));
  for_chunks(static_cast<Index>(edge_chunks.size()), 1, [&](Index chunk, Index, Index) {
    EdgeChunk& mine = edge_chunks[static_cast<std::size_t>(chunk)];
    Index e = mine.first_edge - 1;
    std::size_t first_listing = 0;
    for (std::size_t i = 0; i < mine.sides.size(); ++i) {
      const Side& side = mine.sides[i];
      const Index a = side.lower, b = side.higher;
      if (i == 0 || b != mine.sides[i - 1].higher || a != mine.sides[i - 1].lower) {
        ++e;
        edges_[static_cast<std::size_t>(e)] = {a, b};
        edge_copy_[static_cast<std::size_t>(e)] = triangle_copy_[static_cast<std::size_t>(side.triangle)];
        edge_length[static_cast<std::size_t>(e)] = (s.vertices.row(a) - s.vertices.row(b)).norm();
        first_listing = mine.listing.size();
      }
      const auto at = static_cast<std::size_t>(mine.first_side) + i;
      list_once(&mine.listing, first_listing, triangle_copy_[static_cast<std::size_t>(side.triangle)], e);
      edge_triangles_[at] = side.triangle;
      edge_triangle_start_[static_cast<std::size_t>(e) + 1] = static_cast<Index>(at) + 1;
      triangle_edges[static_cast<std::size_t>(side.triangle)][static_cast<std::size_t>(side.k)] = e;
    }
  });
  double length = 0;  // summed in the edges' order, as one pass would
  for (const double l : edge_length) length += l;
  for (const EdgeChunk& chunk : edge_chunks) edge_listing.insert(edge_listing.end(), chunk.listing.begin(), chunk.listing.end());
  mean_edge_ = edges_.empty() ? 0.0 : length / static_cast<double>(edges_.size());
  // The defaults follow the surface (SurfaceContactOptions).
  settings_.thickness = options.thickness > 0 ? options.thickness : 0.1 * mean_edge_;
  settings_.stiffness = options.stiffness > 0 ? options.stiffness : youngs_modulus * mean_edge_;
  settings_.friction = options.friction;
  settings_.cushion = options.cushion * settings_.thickness;
  rest_y_ = s.vertices;
  find_pieces(static_cast<Index>(rest.rows()));
  // Rest normals, for the guards (lag_guards).
  rest_normals_.resize(F);
  for_chunks(static_cast<Index>(F), kNodeChunk, [&](Index begin, Index end, Index) {
    for (auto t = static_cast<std::size_t>(begin); t < static_cast<std::size_t>(end); ++t) {
      const auto& c = triangles_[t];
      rest_normals_[t] = unit_normal(rest_y_.row(c[0]).transpose(), rest_y_.row(c[1]).transpose(), rest_y_.row(c[2]).transpose(), settings_.thickness);
    }
  });
  // The edges inside a flat polygon: two triangles of one copy, in one plane in the material
  // (normals within kFlatFold), which its one affine map keeps in one plane.
  flat_edge_.assign(edges_.size(), 0);
  for_chunks(edge_total, kNodeChunk, [&](Index begin, Index end, Index) {
    for (auto e = static_cast<std::size_t>(begin); e < static_cast<std::size_t>(end); ++e) {
      if (edge_triangle_start_[e + 1] - edge_triangle_start_[e] != 2) continue;
      const auto t = static_cast<std::size_t>(edge_triangles_[static_cast<std::size_t>(edge_triangle_start_[e])]);
      const auto u = static_cast<std::size_t>(edge_triangles_[static_cast<std::size_t>(edge_triangle_start_[e]) + 1]);
      if (parallel_in_one_copy(t, u)) flat_edge_[e] = 1;
    }
  });
  append_chunks(vertex_count, kNodeChunk, &vertex_listing, &scratch_.vertex_chunks, [&](Index begin, Index end, Listing* out) {
    for (Index v = begin; v < end; ++v) {
      const std::size_t first_listing = out->size();
      list_once(out, first_listing, vertex_copy_[static_cast<std::size_t>(v)], v);
      for (Index i = vertex_triangle_start_[v]; i < vertex_triangle_start_[v + 1]; ++i) {
        list_once(out, first_listing, triangle_copy_[static_cast<std::size_t>(vertex_triangles_[i])], v);
      }
    }
  });
  group_primitives(vertex_listing, edge_listing);
  // The cuts with material on both sides: a cut triangle's pieces, all in its plane, face both
  // ways.
  {
    // Per cut triangle (by source), the first of its pieces with a normal, then whether another
    // is turned against that one: tables over the sources, O(F + sources). (A sort of the pieces
    // by source was 6 ms of each cut's set-up on the femur, whose whole surface is one cut's.)
    std::int64_t sources = 0;
    for (const std::int64_t source : surface.triangle_source) sources = std::max(sources, source + 1);
    std::vector<Index> first_piece(static_cast<std::size_t>(sources), -1);
    std::vector<std::uint8_t> both(static_cast<std::size_t>(sources), 0);
    const auto counted = [&](std::size_t t) { return surface.triangle_source[t] >= 0 && !rest_normals_[t].isZero(); };
    for (std::size_t t = 0; t < F; ++t) {
      if (!counted(t)) continue;
      Index& first = first_piece[static_cast<std::size_t>(surface.triangle_source[t])];
      if (first < 0) first = static_cast<Index>(t);
      else if (rest_normals_[t].dot(rest_normals_[static_cast<std::size_t>(first)]) < 0) both[static_cast<std::size_t>(surface.triangle_source[t])] = 1;
    }
    two_sided_triangle_.assign(F, 0);
    for (std::size_t t = 0; t < F; ++t) {
      if (counted(t) && both[static_cast<std::size_t>(surface.triangle_source[t])]) two_sided_triangle_[t] = 1;
    }
    // Per copy, the normals of the two-sided triangles around the primitives it owns (its
    // triangles, and those around its vertices and edges): a pair of neighbouring copies can
    // have a pair facing across a cut only where two of these are turned against each other.
    const auto group_of = [&](Index copy) { return static_cast<std::size_t>(copy_group_[static_cast<std::size_t>(copy)]); };
    std::vector<std::pair<std::size_t, Index>> listed;  // (group, triangle)
    for (std::size_t t = 0; t < F; ++t) {
      if (!two_sided_triangle_[t]) continue;
      const auto& c = triangles_[t];
      listed.emplace_back(group_of(triangle_copy_[t]), static_cast<Index>(t));
      for (int k = 0; k < 3; ++k) {
        listed.emplace_back(group_of(vertex_copy_[static_cast<std::size_t>(c[k])]), static_cast<Index>(t));
        listed.emplace_back(group_of(edge_copy_[static_cast<std::size_t>(triangle_edges[t][static_cast<std::size_t>(k)])]), static_cast<Index>(t));
      }
    }
    std::sort(listed.begin(), listed.end());
    listed.erase(std::unique(listed.begin(), listed.end()), listed.end());
    group_facing_start_.assign(group_copy_.size() + 1, 0);
    group_facing_.clear();
    for (const auto& [g, t] : listed) {
      ++group_facing_start_[g + 1];
      group_facing_.push_back(rest_normals_[static_cast<std::size_t>(t)]);
    }
    for (std::size_t g = 0; g < group_copy_.size(); ++g) group_facing_start_[g + 1] += group_facing_start_[g];
  }
  if (!enabled() || !(settings_.thickness > 0)) return;

  // Joins: the old ones of copies this cut left alone, and new ones where a changed copy's
  // surface touches another's in the material and now.
  const auto was_changed = [&](Index copy) { return static_cast<std::size_t>(copy) < changed.size() && changed[copy] != 0; };
  std::erase_if(joins_, [&](std::uint64_t key) {
    return was_changed(static_cast<Index>(key >> 32)) || was_changed(static_cast<Index>(key & 0xffffffffu));
  });
  cover(now, nullptr, 0);
  measure();
  const double dhat = settings_.thickness;
  for (std::size_t k = 0; k < candidates_.size(); ++k) {
    const Candidate& c = candidates_[k];
    if (c.neighbouring || !(distances_[k] < dhat)) continue;
    if (!was_changed(static_cast<Index>(c.copies >> 32)) && !was_changed(static_cast<Index>(c.copies & 0xffffffffu))) continue;
    // Across a cut: close in the material, and copies of tets that were neighbours before any
    // cut (a cut's new nodes keep their sources' rest positions, so such copies have corners at
    // one rest point). Separate objects that merely start close are not joined: the barrier
    // holds them apart from the start. Only pairs touching now are joined whatever they are
    // (at distance 0 the barrier is infinite).
    if (proximities_[k].distance > 0 &&
        (!(proximity(c, rest_y_).distance < dhat) || !rest_neighbours(static_cast<Index>(c.copies >> 32), static_cast<Index>(c.copies & 0xffffffffu)))) {
      continue;
    }
    joins_.push_back(c.copies);
  }
  std::sort(joins_.begin(), joins_.end());
  joins_.erase(std::unique(joins_.begin(), joins_.end()), joins_.end());
  mark_joined();
}

void SurfaceContact::group_primitives(const Listing& vertices, const Listing& edges) {
  // The copies that own primitives, ascending, and each one's vertices, triangles and edges.
  // Marked in a table over the copies, then numbered in ascending order: O(V + F + copies).
  copy_group_.assign(copy_nodes_.size(), -1);
  for (const std::vector<Index>* owners : {&vertex_copy_, &triangle_copy_, &edge_copy_}) {
    for (const Index copy : *owners) copy_group_[static_cast<std::size_t>(copy)] = 0;
  }
  group_copy_.clear();
  for (std::size_t copy = 0; copy < copy_group_.size(); ++copy) {
    if (copy_group_[copy] < 0) continue;
    copy_group_[copy] = static_cast<Index>(group_copy_.size());
    group_copy_.push_back(static_cast<Index>(copy));
  }
  const auto group_of = [&](Index copy) { return copy_group_[static_cast<std::size_t>(copy)]; };
  const auto G = static_cast<Index>(group_copy_.size());
  // Each copy's items in ascending order.
  const auto bucket = [&](const Listing& listing, std::vector<Index>* start, std::vector<Index>* items) {
    start->assign(static_cast<std::size_t>(G) + 1, 0);
    for (const auto& [copy, item] : listing) ++(*start)[static_cast<std::size_t>(group_of(copy)) + 1];
    for (Index g = 0; g < G; ++g) (*start)[g + 1] += (*start)[g];
    items->resize(listing.size());
    std::vector<Index> fill(start->begin(), start->end() - 1);
    for (const auto& [copy, item] : listing) (*items)[static_cast<std::size_t>(fill[static_cast<std::size_t>(group_of(copy))]++)] = item;
  };
  bucket(vertices, &vertex_start_, &group_vertices_);
  Listing triangle_listing(triangle_copy_.size());
  for (std::size_t t = 0; t < triangle_copy_.size(); ++t) triangle_listing[t] = {triangle_copy_[t], static_cast<Index>(t)};
  bucket(triangle_listing, &triangle_start_, &group_triangles_);
  bucket(edges, &edge_start_, &group_edges_);
  tree_built_ = false;
  pairs_radius_ = -1;
}

void SurfaceContact::place(const Points& at, Points* y) const {
  const auto V = static_cast<Index>(vertex_nodes_.size());
  y->resize(V, 3);
  for_chunks(V, kNodeChunk, [&](Index begin, Index end, Index) {
    for (Index v = begin; v < end; ++v) {
      y->row(v) = embedded(v, [&](Index n) { return Vec3(at.row(n).transpose()); }).transpose();
    }
  });
}

std::array<Index, 4> SurfaceContact::corners(const Candidate& c) const {
  if (c.edges) {
    const auto& e = edges_[static_cast<std::size_t>(c.a)];
    const auto& f = edges_[static_cast<std::size_t>(c.b)];
    return {e[0], e[1], f[0], f[1]};
  }
  const auto& t = triangles_[static_cast<std::size_t>(c.b)];
  return {c.a, t[0], t[1], t[2]};
}

std::array<Vec3, 4> SurfaceContact::corner_positions(const Candidate& c, const Points& y) const {
  const std::array<Index, 4> k = corners(c);
  std::array<Vec3, 4> at;
  for (int i = 0; i < 4; ++i) at[i] = y.row(k[i]).transpose();
  return at;
}

bool SurfaceContact::vertex_faces(Index v, const Vec3& normal, bool on_two_sided_cut) const {
  for (Index i = vertex_triangle_start_[v]; i < vertex_triangle_start_[v + 1]; ++i) {
    const auto t = static_cast<std::size_t>(vertex_triangles_[i]);
    if ((!on_two_sided_cut || two_sided_triangle_[t]) && rest_normals_[t].dot(normal) < -kFacing) return true;
  }
  return false;
}

std::uint8_t SurfaceContact::facing_faces(const Candidate& c) const {
  const std::array<Index, 4> corner = corners(c);
  std::uint8_t faces = kFacesKnown;
  if (!c.edges) {
    const Vec3& facing = rest_normals_[static_cast<std::size_t>(c.b)];
    if (!facing.isZero() && vertex_faces(corner[0], facing)) faces |= 1;
    return faces;
  }
  // The first edge's ends against the second edge's faces (bits 1 to 3), then the other way.
  for (const auto& [first, edge, bit] : {std::tuple{0, c.b, 1}, std::tuple{2, c.a, 1 + kFacesPerEdge}}) {
    const auto e = static_cast<std::size_t>(edge);
    for (Index i = edge_triangle_start_[e]; i < std::min(edge_triangle_start_[e + 1], edge_triangle_start_[e] + kFacesPerEdge); ++i) {
      if (ends_face(corner, first, edge_triangles_[static_cast<std::size_t>(i)])) {
        faces |= static_cast<std::uint8_t>(1 << (bit + (i - edge_triangle_start_[e])));
      }
    }
  }
  return faces;
}

bool SurfaceContact::ends_face(const std::array<Index, 4>& corner, int first, Index triangle) const {
  const Vec3& facing = rest_normals_[static_cast<std::size_t>(triangle)];
  return !facing.isZero() && (vertex_faces(corner[static_cast<std::size_t>(first)], facing) ||
                              vertex_faces(corner[static_cast<std::size_t>(first) + 1], facing));
}

bool SurfaceContact::faces_across_cut(const Candidate& c) const {
  // Whether triangle t, on a two-sided cut, is faced by one around vertex v on a two-sided cut.
  const auto faced = [&](Index v, std::size_t t) {
    return two_sided_triangle_[t] && !rest_normals_[t].isZero() && vertex_faces(v, rest_normals_[t], true);
  };
  const std::array<Index, 4> k = corners(c);
  if (!c.edges) return faced(k[0], static_cast<std::size_t>(c.b));
  // A face of either edge that a corner of the other faces.
  for (const auto& [first, second] : {std::pair{0, 2}, std::pair{2, 0}}) {
    const auto a = static_cast<std::size_t>(k[static_cast<std::size_t>(second)]);
    const Index b = k[static_cast<std::size_t>(second) + 1];
    for (Index i = vertex_triangle_start_[a]; i < vertex_triangle_start_[a + 1]; ++i) {
      const auto t = static_cast<std::size_t>(vertex_triangles_[i]);
      if (std::find(triangles_[t].begin(), triangles_[t].end(), b) == triangles_[t].end()) continue;
      if (faced(k[static_cast<std::size_t>(first)], t) || faced(k[static_cast<std::size_t>(first) + 1], t)) return true;
    }
  }
  return false;
}

bool SurfaceContact::across_one_cut(const Candidate& c) const {
  // A triangle around the second primitive's corners (its own, for a triangle) in whose plane
  // all four corners lie in the material, within the allowance, and a triangle around the first
  // primitive's corners turned against it: the other side of the cut. Around the corners, not
  // only the primitive's own: a flat triangle (a fan over collinear points) has no plane, its
  // neighbours do.
  const std::array<Index, 4> k = corners(c);
  const double delta = guard_allowance();
  const auto in_plane_of = [&](Index t) {
    const Vec3& n = rest_normals_[static_cast<std::size_t>(t)];
    if (n.isZero()) return false;
    const Vec3 on = rest_y_.row(triangles_[static_cast<std::size_t>(t)][0]).transpose();
    for (const Index v : k) {
      if (!(std::abs(n.dot(rest_y_.row(v).transpose() - on)) < delta)) return false;
    }
    return true;
  };
  const auto faced_by_first = [&](Index t) {
    const Vec3& n = rest_normals_[static_cast<std::size_t>(t)];
    return vertex_faces(k[0], n) || (c.edges && vertex_faces(k[1], n));
  };
  for (int corner = c.edges ? 2 : 1; corner < 4; ++corner) {
    const auto v = static_cast<std::size_t>(k[corner]);
    for (Index i = vertex_triangle_start_[v]; i < vertex_triangle_start_[v + 1]; ++i) {
      const Index t = vertex_triangles_[i];
      if (in_plane_of(t) && faced_by_first(t)) return true;
    }
  }
  return false;
}

collision::Proximity SurfaceContact::proximity(const Candidate& c, const Points& y) const { return proximity_at(corner_positions(c, y), c.edges); }

void SurfaceContact::make_term(const std::array<Index, 4>& k, const std::array<double, 4>& w, ContactTerm* t) const {
  t->count = 0;
  // Per corner, the slot each of its copy's four nodes went to (-1: none, its coefficient was 0).
  // Corners embedded in one copy share its nodes in one order (vertex_nodes_ is the copy's), so a
  // corner whose copy an earlier corner had takes that corner's slots without searching: most
  // pairs span two copies, 8 nodes, not 16 searched among each other. Nodes are met in the same
  // order, and each coefficient summed in the same order, as by searching.
  std::array<std::array<int, 4>, 4> slot_of;
  for (int corner = 0; corner < 4; ++corner) {
    slot_of[corner].fill(-1);
    if (w[corner] == 0) continue;
    const Index v = k[corner];
    int same = -1;
    for (int earlier = 0; earlier < corner && same < 0; ++earlier) {
      if (w[earlier] != 0 && vertex_copy_[k[earlier]] == vertex_copy_[v]) same = earlier;
    }
    for (int i = 0; i < 4; ++i) {
      const double coefficient = w[corner] * vertex_weights_[v][i];
      if (coefficient == 0) continue;
      int slot = same >= 0 ? slot_of[same][i] : -1;
      if (slot < 0) {
        const Index node = vertex_nodes_[v][i];
        slot = 0;
        while (slot < t->count && t->nodes[slot] != node) ++slot;
        if (slot == t->count) {
          t->nodes[t->count] = node;
          t->coefficients[t->count++] = 0;
        }
      }
      slot_of[corner][i] = slot;
      t->coefficients[slot] += coefficient;
    }
  }
}

Vec3 SurfaceContact::guard_vector(const Guard& guard, const Points& y) {
  Vec3 r = Vec3::Zero();
  for (int i = 0; i < 4; ++i) r += guard.w[i] * y.row(guard.corner[i]).transpose();
  return r;
}

double SurfaceContact::guard_gap(const Guard& guard, const Points& y) { return guard.normal.dot(guard_vector(guard, y)) - guard.zero; }

void SurfaceContact::guard_term(const Guard& guard, ContactTerm* t) const {
  make_term(guard.corner, guard.w, t);
  t->r = guard.start_r;
  t->distance = guard.start_distance;
}

void SurfaceContact::collect_active(const Points& at) {
  const PartTimer timer(&part_seconds_.active, &part_seconds_.rebuild);
  cover(at, nullptr, 0);
  const bool same_place = active_at_.rows() == at.rows() && active_at_ == at;
  if (active_current_ && same_place) return;
  measure(kCounted);
  const double dhat = settings_.thickness, kappa = settings_.stiffness;
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  const auto K = static_cast<Index>(candidates_.size()), guard_count = static_cast<Index>(guards_.size());
  const Index pair_chunks = (K + kNodeChunk - 1) / kNodeChunk, guard_chunks = (guard_count + kNodeChunk - 1) / kNodeChunk;
  // Only the guards changed since the terms were collected here: the pairs' chunks stand.
  const bool pairs_hold = active_pairs_current_ && same_place && active_pair_chunks_ == pair_chunks;
  active_.resize(static_cast<std::size_t>(pair_chunks + guard_chunks));
  for (std::size_t c = pairs_hold ? static_cast<std::size_t>(pair_chunks) : 0; c < active_.size(); ++c) active_[c].clear();
  for_chunks(pair_chunks + guard_chunks, 1, [&](Index chunk, Index, Index) {
    std::vector<ActiveTerm>& out = active_[static_cast<std::size_t>(chunk)];
    if (chunk < pair_chunks) {
      if (pairs_hold) return;
      for (Index k = chunk * kNodeChunk; k < std::min(K, (chunk + 1) * kNodeChunk); ++k) {
        if (candidates_[k].joined || candidates_[k].sutured || !(distances_[k] < dhat)) continue;
        const collision::Proximity& p = proximities_[k];
        ActiveTerm& a = out.emplace_back();
        make_term(corners(candidates_[k]), p.w, &a.term);
        a.term.r = p.r;
        a.term.distance = p.distance;
        if (!(p.distance > 0)) {
          a.energy = kInfinity;
          a.gradient.setZero();
          a.hessian.setZero();
          continue;
        }
        const Vec3 n = p.r / p.distance;
        a.energy = kappa * barrier(p.distance, dhat);
        a.gradient = kappa * barrier_first(p.distance, dhat) * n;
        a.hessian = kappa * barrier_second(p.distance, dhat) * n * n.transpose();
      }
      return;
    }
    // The guards: guard_energy, zero while g >= max(cushion, 0).
    const Index first = (chunk - pair_chunks) * kNodeChunk;
    for (Index k = first; k < std::min(guard_count, first + kNodeChunk); ++k) {
      const Guard& guard = guards_[static_cast<std::size_t>(k)];
      const double g = guard_gap(guard, y_);  // y_: the vertices at `at` (cover)
      if (g >= guard.cushion) continue;
      ActiveTerm& a = out.emplace_back();
      guard_term(guard, &a.term);
      double first_derivative = 0, second_derivative = 0;
      a.energy = guard_energy(g, guard.wall, guard.cushion, kappa, &first_derivative, &second_derivative);
      a.gradient = first_derivative * guard.normal;
      a.hessian = second_derivative * guard.normal * guard.normal.transpose();
    }
  });
  active_at_ = at;
  active_current_ = true;
  active_pairs_current_ = true;
  active_pair_chunks_ = pair_chunks;
}

void SurfaceContact::measure(unsigned which) {
  const unsigned missing = which & ~measured_;
  if (missing == 0) return;
  measured_ |= missing;
  proximities_.resize(candidates_.size());
  distances_.resize(candidates_.size());
  for_chunks(static_cast<Index>(candidates_.size()), kNodeChunk, [&](Index begin, Index end, Index) {
    for (Index k = begin; k < end; ++k) {
      const Candidate& c = candidates_[k];
      if (!(kind(c) & missing)) continue;
      // Every reader asks only whether a pair is within the thickness: those surely beyond it
      // (listed beyond it by more than the vertices can have moved since, or with boxes apart by
      // more) are left at infinity unmeasured.
      // (Joined pairs out to the guards' reach: see joined_reach.)
      const double reach = kind(c) & kJoined ? joined_reach() : settings_.thickness;
      if (c.reference_distance - reference_relative_ > (1 + kBoundSlack) * reach) {
        proximities_[k].distance = distances_[k] = std::numeric_limits<double>::infinity();
        continue;
      }
      measure_within(corner_positions(c, y_), c.edges, reach, &proximities_[k]);
      distances_[k] = proximities_[k].distance;
    }
  });
}

void SurfaceContact::find_pieces(Index nodes) {
  // Union-find over the nodes, joined through the copies' corners: two copies that share a node
  // are one piece. O(copies alpha).
  std::vector<Index> parent(static_cast<std::size_t>(nodes));
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](Index n) {
    while (parent[static_cast<std::size_t>(n)] != n) {
      parent[static_cast<std::size_t>(n)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(n)])];
      n = parent[static_cast<std::size_t>(n)];
    }
    return n;
  };
  for (const std::array<Index, 4>& corners : copy_nodes_) {
    for (int i = 1; i < 4; ++i) {
      const Index a = root(corners[0]), b = root(corners[static_cast<std::size_t>(i)]);
      if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    }
  }
  // Pieces numbered by their first vertex; the vertices and the nodes that carry them by piece,
  // ascending within each (with one piece, the vertices' own order), and work items over both.
  const auto V = static_cast<Index>(vertex_nodes_.size());
  std::vector<Index> piece_of_root(static_cast<std::size_t>(nodes), -1), vertex_piece(static_cast<std::size_t>(V));
  std::vector<Index> node_piece(static_cast<std::size_t>(nodes), -1);
  pieces_ = 0;
  for (Index v = 0; v < V; ++v) {
    Index& piece = piece_of_root[static_cast<std::size_t>(root(vertex_nodes_[v][0]))];
    if (piece < 0) piece = pieces_++;
    vertex_piece[static_cast<std::size_t>(v)] = piece;
    for (const Index n : vertex_nodes_[v]) node_piece[static_cast<std::size_t>(n)] = piece;
  }
  const auto order = [&](const std::vector<Index>& piece_of, PieceOrder* out) {
    std::vector<Index> start(static_cast<std::size_t>(pieces_) + 1, 0);
    for (const Index p : piece_of) {
      if (p >= 0) ++start[static_cast<std::size_t>(p) + 1];
    }
    std::partial_sum(start.begin(), start.end(), start.begin());
    out->elements.resize(static_cast<std::size_t>(start.back()));
    std::vector<Index> next(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < piece_of.size(); ++k) {
      if (piece_of[k] >= 0) out->elements[static_cast<std::size_t>(next[static_cast<std::size_t>(piece_of[k])]++)] = static_cast<Index>(k);
    }
    out->identity = true;
    for (std::size_t k = 0; k < out->elements.size(); ++k) out->identity = out->identity && out->elements[k] == static_cast<Index>(k);
    out->items.clear();
    for (Index p = 0; p < pieces_; ++p) {
      for (Index b = start[static_cast<std::size_t>(p)]; b < start[static_cast<std::size_t>(p) + 1]; b += kNodeChunk) {
        out->items.push_back({p, b, std::min(b + kNodeChunk, start[static_cast<std::size_t>(p) + 1])});
      }
    }
  };
  order(vertex_piece, &piece_vertices_);
  vertex_piece_ = std::move(vertex_piece);
  order(node_piece, &piece_nodes_);
}

// Work items (of up to kNodeChunk elements) per parallel task: the surface nodes' motions (a
// few thousand, several times a step) went faster on one thread than dispatched item by item.
constexpr Index kItemsPerTask = 8;

template <typename Value>
void SurfaceContact::item_boxes(const PieceOrder& order, const Value& value, std::vector<spatial::Aabb>* boxes) const {
  item_boxes_.resize(order.items.size());
  for_chunks(static_cast<Index>(order.items.size()), kItemsPerTask, [&](Index begin, Index end, Index) {
    for (Index i = begin; i < end; ++i) {
      const auto& [piece, first, last] = order.items[static_cast<std::size_t>(i)];
      spatial::Aabb box;  // kept in registers
      order.for_each(first, last, [&](Index e) { box.extend(value(e)); });
      item_boxes_[static_cast<std::size_t>(i)] = box;
    }
  });
  boxes->assign(static_cast<std::size_t>(pieces_), spatial::Aabb{});
  for (std::size_t i = 0; i < order.items.size(); ++i) (*boxes)[static_cast<std::size_t>(order.items[i][0])].extend(item_boxes_[i]);
}

template <typename Value>
void SurfaceContact::piece_motion(const PieceOrder& order, const Value& value, double scale, PieceMotion* out) const {
  // Two passes over the elements, in parallel, nothing allocated once warm; per piece the same
  // bits on any number of threads.
  item_boxes(order, value, &piece_scratch_);
  out->centre.resize(static_cast<std::size_t>(pieces_));
  out->half.resize(static_cast<std::size_t>(pieces_));
  for (std::size_t p = 0; p < piece_scratch_.size(); ++p) {
    out->centre[p] = 0.5 * (piece_scratch_[p].min + piece_scratch_[p].max);
    out->half[p] = scale * 0.5 * (piece_scratch_[p].max - piece_scratch_[p].min);
  }
  item_largest_.resize(order.items.size());
  for_chunks(static_cast<Index>(order.items.size()), kItemsPerTask, [&](Index begin, Index end, Index) {
    for (Index i = begin; i < end; ++i) {
      const auto& [piece, first, last] = order.items[static_cast<std::size_t>(i)];
      const Vec3 centre = out->centre[static_cast<std::size_t>(piece)];
      double largest = 0;
      order.for_each(first, last, [&](Index e) { largest = std::max(largest, (value(e) - centre).squaredNorm()); });
      item_largest_[static_cast<std::size_t>(i)] = largest;
    }
  });
  out->radius.assign(static_cast<std::size_t>(pieces_), 0.0);
  for (std::size_t i = 0; i < order.items.size(); ++i) {
    double& r = out->radius[static_cast<std::size_t>(order.items[i][0])];
    r = std::max(r, item_largest_[i]);
  }
  for (double& r : out->radius) r = scale * std::sqrt(r);
  out->turned.assign(static_cast<std::size_t>(pieces_), std::numeric_limits<double>::infinity());
  out->turn.assign(static_cast<std::size_t>(pieces_), 0.0);
}

template <typename Value, typename Position>
void SurfaceContact::piece_turn(const PieceOrder& order, const Value& value, const Position& position, double scale, PieceMotion* out) const {
  // The fit: c and a the mean position and motion, (sum |y|^2 I - y y^T) w = sum y x d with
  // y = x - c, from sums about the origin in one pass (their rounding only loosens the fit,
  // never the bound, which the second pass measures from whatever w came out); then the largest
  // distance of a motion from the fit. A vertex's residual is its nodes' weighted by its
  // weights (the fit is affine), so `scale` bounds it from the nodes'.
  turn_sums_.assign(order.items.size(), TurnSums{});
  for_chunks(static_cast<Index>(order.items.size()), kItemsPerTask, [&](Index begin, Index end, Index) {
    for (Index i = begin; i < end; ++i) {
      const auto& [piece, first, last] = order.items[static_cast<std::size_t>(i)];
      TurnSums sums;
      order.for_each(first, last, [&](Index e) {
        const Vec3 x = position(e), d = value(e);
        sums.count += 1;
        sums.squares += x.squaredNorm();
        sums.position += x;
        sums.motion += d;
        sums.cross += x.cross(d);
        sums.outer += x * x.transpose();
        sums.around.extend(x);
      });
      turn_sums_[static_cast<std::size_t>(i)] = sums;
    }
  });
  piece_turn_sums_.assign(static_cast<std::size_t>(pieces_), TurnSums{});
  for (std::size_t i = 0; i < order.items.size(); ++i) {
    TurnSums& to = piece_turn_sums_[static_cast<std::size_t>(order.items[i][0])];
    const TurnSums& from = turn_sums_[i];
    to.count += from.count;
    to.squares += from.squares;
    to.position += from.position;
    to.motion += from.motion;
    to.cross += from.cross;
    to.outer += from.outer;
    to.around.extend(from.around);
  }
  turn_centre_.resize(static_cast<std::size_t>(pieces_));
  turn_motion_.resize(static_cast<std::size_t>(pieces_));
  turn_rate_.resize(static_cast<std::size_t>(pieces_));
  out->origin.resize(static_cast<std::size_t>(pieces_));
  out->rate.resize(static_cast<std::size_t>(pieces_));
  out->around.resize(static_cast<std::size_t>(pieces_));
  out->weight_bound = scale;
  for (std::size_t p = 0; p < piece_turn_sums_.size(); ++p) {
    const TurnSums& sums = piece_turn_sums_[p];
    const Vec3 c = sums.position / sums.count, a = sums.motion / sums.count;
    const Mat3 normal = (sums.squares - sums.count * c.squaredNorm()) * Mat3::Identity() - (sums.outer - sums.count * c * c.transpose());
    const Vec3 w = normal.ldlt().solve(sums.cross - sums.count * c.cross(a));
    turn_centre_[p] = c;
    turn_motion_[p] = a;
    turn_rate_[p] = w.allFinite() ? w : Vec3::Zero();
    out->rate[p] = turn_rate_[p];
    out->origin[p] = a - turn_rate_[p].cross(c);
    out->around[p] = sums.around;
  }
  item_largest_.resize(order.items.size());
  for_chunks(static_cast<Index>(order.items.size()), kItemsPerTask, [&](Index begin, Index end, Index) {
    for (Index i = begin; i < end; ++i) {
      const auto& [piece, first, last] = order.items[static_cast<std::size_t>(i)];
      const auto k = static_cast<std::size_t>(piece);
      const Vec3 c = turn_centre_[k], a = turn_motion_[k], w = turn_rate_[k];
      double largest = 0;
      order.for_each(first, last, [&](Index e) { largest = std::max(largest, (value(e) - a - w.cross(position(e) - c)).squaredNorm()); });
      item_largest_[static_cast<std::size_t>(i)] = largest;
    }
  });
  out->turned.assign(static_cast<std::size_t>(pieces_), 0.0);
  for (std::size_t i = 0; i < order.items.size(); ++i) {
    double& r = out->turned[static_cast<std::size_t>(order.items[i][0])];
    r = std::max(r, item_largest_[i]);
  }
  out->turn.resize(static_cast<std::size_t>(pieces_));
  for (std::size_t p = 0; p < out->turned.size(); ++p) {
    out->turned[p] = scale * std::sqrt(out->turned[p]);
    out->turn[p] = turn_rate_[p].norm();
  }
}

template <typename NodeMotion>
void SurfaceContact::vertex_motion(const NodeMotion& node_motion, PieceMotion* out) const {
  piece_motion(piece_vertices_, [&](Index v) { return embedded(v, node_motion); }, 1.0, out);
}

void SurfaceContact::node_motion(const Points& at, const Points& since, PieceMotion* out) const {
  piece_motion(piece_nodes_, [&](Index n) { return Vec3((at.row(n) - since.row(n)).transpose()); }, weight_bound_, out);
}

template <typename Position>
void SurfaceContact::piece_boxes(const Position& position, PieceBoxes* out) const {
  // With one piece no gap is ever asked for: nothing to place.
  if (pieces_ == 1) {
    out->boxes.assign(1, spatial::Aabb{});
  } else {
    item_boxes(piece_vertices_, position, &out->boxes);
  }
  out->by_low_x.resize(static_cast<std::size_t>(pieces_));
  std::iota(out->by_low_x.begin(), out->by_low_x.end(), 0);
  std::sort(out->by_low_x.begin(), out->by_low_x.end(), [&](Index a, Index b) {
    return std::tie(out->boxes[static_cast<std::size_t>(a)].min.x(), a) < std::tie(out->boxes[static_cast<std::size_t>(b)].min.x(), b);
  });
}

template <typename Visit>
bool SurfaceContact::for_near_pieces(const PieceBoxes& boxes, double within, const Visit& visit) const {
  // Sweep and prune along x: each piece against those that start, in x, before it ends plus
  // `within`; O(C log C) for the order (made with the boxes) plus the pairs that overlap in x.
  const std::vector<Index>& order = boxes.by_low_x;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Index p = order[i];
    const spatial::Aabb& a = boxes.boxes[static_cast<std::size_t>(p)];
    if (!visit(p, p, 0.0)) return false;
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const Index q = order[j];
      const spatial::Aabb& b = boxes.boxes[static_cast<std::size_t>(q)];
      if (b.min.x() - a.max.x() > within) break;
      const double gap = a.gap(b);
      if (gap <= within && !visit(p, q, gap)) return false;
    }
  }
  return true;
}

SurfaceContact::PieceMotion::Fitted SurfaceContact::PieceMotion::fitted(std::size_t i, std::size_t j) const {
  const Vec3 o = origin[i] - origin[j], w = rate[i] - rate[j];
  const auto largest = [&](const spatial::Aabb& box) {
    double most = 0;
    for (int k = 0; k < 8; ++k) {
      const Vec3 x((k & 1 ? box.max : box.min).x(), (k & 2 ? box.max : box.min).y(), (k & 4 ? box.max : box.min).z());
      most = std::max(most, (o + w.cross(x)).squaredNorm());
    }
    return weight_bound * std::sqrt(most);
  };
  // Over p's box with q's turn, or over q's with p's: the smaller.
  const double over_i = largest(around[i]), over_j = largest(around[j]);
  const double residuals = turned[i] + turned[j];
  return over_i <= over_j ? Fitted{over_i + residuals, rate[j].norm()} : Fitted{over_j + residuals, rate[i].norm()};
}

double SurfaceContact::PieceMotion::farthest() const {
  // The largest relative motion of any two pieces: their centres lie in the box of all
  // centres, so no two are further apart than its diagonal.
  spatial::Aabb all;
  double radius_max = 0;
  for (std::size_t c = 0; c < centre.size(); ++c) {
    all.extend(centre[c]);
    radius_max = std::max(radius_max, radius[c]);
  }
  return centre.empty() ? 0.0 : (all.max - all.min).norm() + 2 * radius_max;
}

SurfaceContact::MotionCheck SurfaceContact::check_motion(const Points& at, const Points* move_end, const Points& since,
                                                         const PieceBoxes& boxes, double add, double limit, double apart,
                                                         double within) const {
  // A pair of pieces holds at b when b + add <= limit or gap - b > apart: the larger b falls, so
  // the check at the larger of the two ends' motions is the check at each end. Pairs whose boxes
  // lay apart by more than any two pieces moved relative to each other, and `apart`, hold.
  const auto holds_at = [&](const PieceMotion& motion, double* relative) {
    const double farthest = motion.farthest();
    return for_near_pieces(boxes, std::max(farthest + apart, relative ? within : 0.0), [&](Index p, Index q, double gap) {
      const double b = motion.relative(p, q);
      if (!(b + add <= limit) && !(gap - b > apart)) return false;
      if (relative && gap <= within) *relative = std::max(*relative, b);
      return true;
    });
  };
  // Each end by the nodes' bound, then with each piece's turn taken out of it (from the nodes:
  // two passes over a few thousand), then by the vertices (keeping the nodes' turns), where those
  // do not hold. (Turns from the vertices too were measured and not kept: two more passes over
  // them wherever the rest failed, and on the swinging femur they saved too few lists.)
  const auto holds = [&](const Points& to, double* relative) {
    const auto moved = [&](Index n) { return Vec3((to.row(n) - since.row(n)).transpose()); };
    const auto again = [&]() {
      if (relative) *relative = 0;
      return holds_at(motion_scratch_, relative);
    };
    node_motion(to, since, &motion_scratch_);
    if (again()) return true;
    piece_turn(piece_nodes_, moved, [&](Index n) { return Vec3(since.row(n).transpose()); }, weight_bound_, &motion_scratch_);
    if (again()) return true;
    nodes_turned_ = motion_scratch_.turned;
    nodes_turn_ = motion_scratch_.turn;
    vertex_motion(moved, &motion_scratch_);
    motion_scratch_.turned.swap(nodes_turned_);
    motion_scratch_.turn.swap(nodes_turn_);
    return again();
  };
  MotionCheck result;
  result.holds = holds(at, &result.relative) && (!move_end || holds(*move_end, nullptr));
  return result;
}

void SurfaceContact::cover(const Points& at, const Points* move_end, double move_relative) {
  if (sutures_changed_) mark_joined();
  // Asked again at the node positions y_ was placed from under this list: y_ stands, and with no
  // move the list holds there (it held, or was made with room, for them). A step's end, the next
  // step's start and CCD's first move from an evaluated point look at one position several
  // times, and each placed every vertex and measured their motion again.
  const bool placed_at = rho_ >= 0 && y_nodes_.rows() == at.rows() && y_nodes_ == at;
  if (placed_at && !move_end) return;
  // The list holds every pair within the thickness, and the joined pairs within the guards' reach
  // beyond it (joined_reach; the same without a cushion).
  const double reach = joined_reach();
  // How far the vertices moved relative to each other since the list was built, piece by piece,
  // at `at` and at the move's end: a motion common to a piece changes no distance within it, so
  // falling pieces keep their list, and two pieces whose boxes lay apart by more than their
  // relative motion and dhat have no pair to list (a piece falling away from another). Along the
  // move two vertices' relative motion from the reference is affine in the move's parameter, so
  // at most the larger of the two ends'. Tighter than the motion so far plus the move's when the
  // move goes on where the last went.
  if (rho_ >= 0 && reference_nodes_.rows() == at.rows()) {
    const MotionCheck moved = check_motion(at, move_end, reference_nodes_, reference_boxes_, reach, rho_, reach, rho_);
    if (moved.holds) {
      // The list holds: the vertices are placed only where there are candidates to measure or
      // guards to read them (a guard's g is taken from the placed vertices).
      if (candidates_.empty() && guards_.empty()) {
        forget_measures();
        reference_relative_ = std::numeric_limits<double>::infinity();
        return;
      }
      reference_relative_ = moved.relative;
      if (placed_at) return;
      place(at, &placed_);
      y_nodes_ = at;
      if (placed_.rows() != y_.rows() || placed_ != y_) {
        y_.swap(placed_);
        forget_measures();
      }
      return;
    }
  }
  place(at, &y_);
  y_nodes_ = at;
  forget_measures();
  // The list is made around the move's end, with room for the whole move back to `at` and for
  // as much again beyond it, and dhat / 2 more (more slack, for one more move like this one, was
  // measured slower on the hanging femur: its larger lists cost more than the rebuilds they
  // saved). A piece sliding along another moves on the same way in the next move, which then
  // needs no new list: on the hand cut in two, whose upper part slides down the cut 2 to 4 dhat a
  // step, 62 rebuilds in its first 60 steps became 30 (the list was made around the move's start,
  // and each step's second move, the Newton step after the first guess CCD had shortened, went
  // past it); the folded flap 89 in 60 steps became 39, the hanging femur 78 in 60 became 41.
  // (Pieces that max_step found apart over the whole move may move more than move_relative
  // against each other; they stay beyond dhat over it, which is all the skip in measure needs.)
  if (move_end) {
    reference_nodes_ = *move_end;
    place(reference_nodes_, &reference_);
    reference_relative_ = move_relative;  // from the move's end back to `at`
  } else {
    reference_ = y_;
    reference_nodes_ = at;
    reference_relative_ = 0;
  }
  rebuild(2 * reach + move_relative, move_end == nullptr);
}

void SurfaceContact::rebuild(double rho, bool made_now) {
  const PartTimer timer(&part_seconds_.rebuild, nullptr);
  rho_ = rho;
  forget_measures();
  ++rebuilds_;
  const Points& y = reference_;
  const auto corner = [&](Index v) { return Vec3(y.row(v).transpose()); };
  // Each copy's box: its vertices and its triangles' corners (an edge is a side of a triangle the
  // same copy owns). O(V + F).
  const auto G = static_cast<Index>(group_copy_.size());
  copy_boxes_.assign(static_cast<std::size_t>(G), spatial::Aabb{});
  for_chunks(G, kNodeChunk, [&](Index begin, Index end, Index) {
    for (Index g = begin; g < end; ++g) {
      spatial::Aabb& box = copy_boxes_[static_cast<std::size_t>(g)];
      for (Index k = vertex_start_[g]; k < vertex_start_[g + 1]; ++k) box.extend(corner(group_vertices_[k]));
      for (Index k = triangle_start_[g]; k < triangle_start_[g + 1]; ++k) {
        for (const Index v : triangles_[static_cast<std::size_t>(group_triangles_[k])]) box.extend(corner(v));
      }
    }
  });
  piece_boxes(corner, &reference_boxes_);
  cover_copy_pairs(rho);
  // The pairs of copies whose boxes come within rho, then their primitives against each other.
  // Per fixed chunk of pairs, joined in chunk order: the pairs are in (g, h) order, and so are
  // the candidates.
  constexpr Index kChunk = 64;
  candidates_.clear();
  append_chunks(static_cast<Index>(copy_pairs_.size()), kChunk, &candidates_, [&](Index begin, Index end, std::vector<Candidate>* found) {
    std::vector<Candidate>& out = *found;
    const auto consider = [&](Candidate c, Index copy_a, Index copy_b, bool near) {
      // A primitive listed by a copy other than its own: wanted here only where its own copy and
      // the other primitive's neighbour each other (else the pair is found through those), and
      // then perhaps found more than once (through each of its copies apart from the other's):
      // kept once, below.
      const Index own_a = c.edges ? edge_copy_[static_cast<std::size_t>(c.a)] : vertex_copy_[static_cast<std::size_t>(c.a)];
      const Index own_b = c.edges ? edge_copy_[static_cast<std::size_t>(c.b)] : triangle_copy_[static_cast<std::size_t>(c.b)];
      // Such pairs, and those of neighbouring copies, may be found twice (edges in either order).
      c.listed_apart = !near && (own_a != copy_a || own_b != copy_b) ? 1 : 0;
      if (c.listed_apart && !neighbours(own_a, own_b)) return;
      c.neighbouring = near ? 1 : 0;
      if ((c.listed_apart || c.neighbouring) && c.edges && c.b < c.a) std::swap(c.a, c.b);
      const std::array<Index, 4> k = corners(c);
      const bool shared = c.edges ? (k[0] == k[2] || k[0] == k[3] || k[1] == k[2] || k[1] == k[3]) : (k[0] == k[1] || k[0] == k[2] || k[0] == k[3]);
      if (shared) return;
      // Of neighbouring copies, only pairs whose sides face each other across a two-sided cut: the
      // two sides of a cut between them (a slinky's coils), held by the guards where they touch
      // and by the barrier where they have slid along each other. The others, most of them, are a
      // surface and its own neighbours around a shared node: near in the material, they would only
      // be joined; farther, they meet only where the surface folds onto itself within a tet or two
      // (left to the crossing check). Kept, on Figure 8's slinky, they made a list of 12M pairs.
      if (near && !faces_across_cut(c)) return;
      const double apart = proximity(c, y).distance;
      if (!(apart <= rho)) return;
      c.reference_distance = apart;
      // A pair touching now counts as touching in the material too: joined, it is left out (the
      // barrier is infinite at distance 0), as the joins of surfaces touching from the start are.
      // Now is y_, not a move's end the list was made around (where a move not yet shortened by
      // CCD may have brought pairs to 0).
      bool touching = !(apart > 0);
      if (!made_now) {
        const std::array<Vec3, 4> at = corner_positions(c, y_);
        touching = !(gap_between(at, c.edges) > 0) && !(proximity_at(at, c.edges).distance > 0);
      }
      // Only closeness within dhat matters there: a pair whose boxes lay farther apart is not
      // measured (a piece sliding along a cut meets primitives far from its own in the material).
      // Of neighbouring copies, only pairs apart in the material by more than kNeighbourReach dhat
      // count; the closer ones are joined (see mark_joined).
      const double reach = near ? guarded_reach() : settings_.thickness;
      collision::Proximity rest;
      measure_within(corner_positions(c, rest_y_), c.edges, reach, &rest);
      c.rest_close = rest.distance < settings_.thickness || touching ? 1 : 0;
      c.rest_touching = near ? (rest.distance < reach || touching ? 1 : 0)
                             : (rest.distance < guard_allowance() || touching || (c.rest_close && across_one_cut(c)) ? 1 : 0);
      out.push_back(c);
    };
    // The primitives of one copy that reach another's box, with their boxes: most pairs of nearby
    // copies have none (boxes of tets that share no node overlap often in a BCC lattice).
    using Near = std::vector<std::pair<Index, spatial::Aabb>>;
    Near near_vertices, near_triangles, near_edges_g, near_edges_h;
    // A vertex that copy g lists but does not own is wanted against copy h only where its own
    // copy neighbours h (see consider); triangles are listed by their own copies only, and an
    // edge's two copies are known only with the other edge.
    // Of neighbouring copies, each lists only the primitives it owns: the pair is found once,
    // through its own copies.
    const auto gather = [&](const std::vector<Index>& start, const std::vector<Index>& items, Index g, Index h, const spatial::Aabb& reach,
                            const auto& box_of, int kind, bool near, Near* into) {
      into->clear();
      for (Index k = start[g]; k < start[g + 1]; ++k) {
        if (kind != 1) {
          const auto item = static_cast<std::size_t>(items[k]);
          const Index own = kind == 0 ? vertex_copy_[item] : edge_copy_[item];
          if (own != group_copy_[g] && (near || (kind == 0 && !neighbours(own, group_copy_[h])))) continue;
        }
        const spatial::Aabb box = box_of(items[k]);
        if (reach.meets(box)) into->emplace_back(items[k], box);
      }
    };
    const auto vertex_box = [&](Index v) {
      spatial::Aabb b;
      b.extend(corner(v));
      return b;
    };
    const auto triangle_box = [&](Index t) {
      spatial::Aabb b;
      for (const Index v : triangles_[static_cast<std::size_t>(t)]) b.extend(corner(v));
      return b;
    };
    const auto edge_box = [&](Index e) {
      spatial::Aabb b;
      for (const Index v : edges_[static_cast<std::size_t>(e)]) b.extend(corner(v));
      return b;
    };
    const auto box = [&](Index g) -> const spatial::Aabb& { return copy_boxes_[static_cast<std::size_t>(g)]; };
    // The primitives of copy g (vertices or edges) near those of copy h (triangles or edges).
    const auto primitive_pairs = [&](const std::vector<Index>& start_g, const std::vector<Index>& items_g, const auto& box_g, Near* near_g,
                                     const std::vector<Index>& start_h, const std::vector<Index>& items_h, const auto& box_h, Near* near_h,
                                     Index g, Index h, std::uint8_t edges, std::uint64_t key, bool near) {
      gather(start_g, items_g, g, h, box(h).grown(rho), box_g, edges == 0 ? 0 : 2, near, near_g);
      if (near_g->empty()) return;
      gather(start_h, items_h, h, g, box(g).grown(rho), box_h, edges == 0 ? 1 : 2, near, near_h);
      for (const auto& [a, a_box] : *near_g) {
        const spatial::Aabb reach = a_box.grown(rho);
        for (const auto& [b, b_box] : *near_h) {
          if (reach.meets(b_box)) consider({a, b, edges, 0, 0, 0, 0, 0, 0, 0, key, 0.0}, group_copy_[g], group_copy_[h], near);
        }
      }
    };
    for (Index i = begin; i < end; ++i) {
      const auto [g, h] = copy_pairs_[static_cast<std::size_t>(i)];
      if (!box(g).grown(rho).meets(box(h))) continue;
      const std::uint64_t key = copy_pair(group_copy_[g], group_copy_[h]);
      const bool near = neighbours(group_copy_[g], group_copy_[h]);
      for (const auto& [from, to] : {std::pair{g, h}, std::pair{h, g}}) {
        primitive_pairs(vertex_start_, group_vertices_, vertex_box, &near_vertices, triangle_start_, group_triangles_, triangle_box,
                        &near_triangles, from, to, 0, key, near);
      }
      primitive_pairs(edge_start_, group_edges_, edge_box, &near_edges_g, edge_start_, group_edges_, edge_box, &near_edges_h, g, h, 1, key,
                      near);
    }
  });
  // The pairs found through other copies last, each once (through the first of its copy pairs),
  // so that the others keep their order. Rare: primitives on the rims between copies, near the
  // surface of a copy that neighbours one of them (a slinky's coils, a tet apart in the material).
  // The pairs of neighbouring copies go there too: such a pair is listed apart as well where
  // other copies around its corners are apart, and then counts as found that way.
  const auto apart = std::stable_partition(candidates_.begin(), candidates_.end(),
                                           [](const Candidate& c) { return !c.listed_apart && !c.neighbouring; });
  const auto same_pair = [](const Candidate& p, const Candidate& q) { return p.edges == q.edges && p.a == q.a && p.b == q.b; };
  std::sort(apart, candidates_.end(), [](const Candidate& p, const Candidate& q) {
    return std::tie(p.edges, p.a, p.b, p.neighbouring, p.copies) < std::tie(q.edges, q.a, q.b, q.neighbouring, q.copies);
  });
  candidates_.erase(std::unique(apart, candidates_.end(), same_pair), candidates_.end());
  mark_joined();
}

std::vector<std::array<Index, 3>> SurfaceContact::candidate_pairs(Index* listed_apart, std::vector<std::uint8_t>* counted) const {
  std::vector<std::array<Index, 3>> pairs;
  pairs.reserve(candidates_.size());
  if (listed_apart) *listed_apart = 0;
  if (counted) counted->clear();
  for (const Candidate& c : candidates_) {
    pairs.push_back({c.edges, c.a, c.b});
    if (listed_apart) *listed_apart += c.listed_apart;
    if (counted) counted->push_back(!c.joined && !c.sutured ? 1 : 0);
  }
  return pairs;
}

void SurfaceContact::cover_copy_pairs(double rho) {
  const double dhat = settings_.thickness;
  // Valid while no gap between two copies' boxes can have shrunk from more than the list's
  // radius to rho or less: boxes move with their vertices, and those of pieces that lay apart
  // by more than their relative motion and rho meet no copy of the other (see check_motion).
  if (pairs_radius_ >= 0 && pairs_reference_.rows() == reference_nodes_.rows() &&
      check_motion(reference_nodes_, nullptr, pairs_reference_, pairs_boxes_, rho, pairs_radius_, rho, rho).holds) {
    return;
  }
  pairs_reference_ = reference_nodes_;
  pairs_boxes_ = reference_boxes_;
  pairs_radius_ = rho + 2 * kPairSlack * dhat;
  ++pair_rebuilds_;
  const double radius = pairs_radius_;
  if (!tree_built_) {
    copy_tree_ = spatial::BoxTree(copy_boxes_);
    tree_built_ = true;
  } else {
    copy_tree_.mutable_boxes() = copy_boxes_;  // same count: no allocation
    copy_tree_.refit();
  }
  // Each pair once (g < h), neighbours left out unless they may face each other across a cut
  // (group_facing_), sorted: the candidates come in their order.
  const auto may_face = [&](Index g, Index h) {
    for (Index i = group_facing_start_[static_cast<std::size_t>(g)]; i < group_facing_start_[static_cast<std::size_t>(g) + 1]; ++i) {
      for (Index j = group_facing_start_[static_cast<std::size_t>(h)]; j < group_facing_start_[static_cast<std::size_t>(h) + 1]; ++j) {
        if (group_facing_[static_cast<std::size_t>(i)].dot(group_facing_[static_cast<std::size_t>(j)]) < -kFacing) return true;
      }
    }
    return false;
  };
  tbb::enumerable_thread_specific<std::vector<std::array<Index, 2>>> found;
  copy_tree_.self_join(radius, [&](Index g, Index h) {
    if (g == h) return;
    if (!neighbours(group_copy_[g], group_copy_[h]) || may_face(g, h)) found.local().push_back({std::min(g, h), std::max(g, h)});
  });
  copy_pairs_.clear();
  for (const auto& mine : found) copy_pairs_.insert(copy_pairs_.end(), mine.begin(), mine.end());
  std::sort(copy_pairs_.begin(), copy_pairs_.end());
}

void SurfaceContact::mark_joined() {
  forget_measures();  // which pairs count has changed
  // Sutured: close in the material, with a corner in a copy a spring holds (a primitive's own
  // copy and its corners' copies may differ: a triangle's vertices can be embedded in its
  // neighbours).
  const auto sutured = [&](Index copy) { return static_cast<std::size_t>(copy) < sutured_.size() && sutured_[static_cast<std::size_t>(copy)] != 0; };
  // Each candidate on its own, in parallel: run after every rebuild and whenever joins end (every
  // step while a piece slides off the cut it was joined across), over lists of 25k to 80k pairs.
  for_chunks(static_cast<Index>(candidates_.size()), kNodeChunk, [&](Index begin, Index end, Index) {
    for (Index index = begin; index < end; ++index) {
      Candidate& c = candidates_[static_cast<std::size_t>(index)];
      // Of joined copies, only the pairs that touch in the material (within the guards' allowance):
      // the two sides of the cut. Their other pairs, apart when the cut was made, collide as any
      // others: sticks sliding along each other while their cut faces still touch somewhere, and
      // faces of neighbouring sticks a sliver apart (a cut 0.0123 from a lattice plane), whose
      // barrier, finite there, starts active.
      // Of neighbouring copies, joined for good: pairs near in the material, guarded where they face.
      c.joined = c.rest_touching && (c.neighbouring || std::binary_search(joins_.begin(), joins_.end(), c.copies)) ? 1 : 0;
      c.sutured = 0;
      if (sutured_.empty()) continue;
      const std::array<Index, 4> k = corners(c);
      if (c.rest_close) {
        for (const Index v : k) {
          if (sutured(vertex_copy_[static_cast<std::size_t>(v)])) c.sutured = 1;
        }
      }
      const int first_of_b = c.edges ? 2 : 1;
      // Or two neighbouring copies with corners in sutured copies on both sides: near an incision's
      // end, where the two sides' copies share nodes, the springs squeeze the wound shut, pressing
      // pairs 3 to 8 dhat apart in the material into each other (the lip incision: 17 such pairs
      // held the springs off, and Newton stalled for two steps as they came in).
      if (c.neighbouring) {
        bool first_side = false, second_side = false;
        for (int i = 0; i < 4; ++i) (i < first_of_b ? first_side : second_side) |= sutured(vertex_copy_[static_cast<std::size_t>(k[i])]);
        if (first_side && second_side) c.sutured = 1;
      }
      // Or two copies one spring holds together, wherever in them: the springs pull the whole of
      // both into place, squeezing pairs that were a little further apart than dhat (measured on
      // the lip incision: pairs 1.6 to 1.9 dhat apart in the material pressed to 0.5 dhat).
      for (int i = 0; i < first_of_b && !c.sutured; ++i) {
        for (int j = first_of_b; j < 4 && !c.sutured; ++j) {
          const std::uint64_t key = copy_pair(vertex_copy_[static_cast<std::size_t>(k[i])], vertex_copy_[static_cast<std::size_t>(k[j])]);
          if (std::binary_search(suture_pairs_.begin(), suture_pairs_.end(), key)) c.sutured = 1;
        }
      }
    }
  });
  sutures_changed_ = false;
}

void SurfaceContact::suture(Index copy_a, Index copy_b) {
  for (const Index copy : {copy_a, copy_b}) {
    if (static_cast<std::size_t>(copy) >= sutured_.size()) sutured_.resize(static_cast<std::size_t>(copy) + 1, 0);
    sutured_[static_cast<std::size_t>(copy)] = 1;
  }
  const std::uint64_t key = copy_pair(copy_a, copy_b);
  suture_pairs_.insert(std::lower_bound(suture_pairs_.begin(), suture_pairs_.end(), key), key);
  sutures_changed_ = true;
}

void SurfaceContact::clear_sutures() {
  if (sutured_.empty()) return;
  sutured_.clear();
  suture_pairs_.clear();
  sutures_changed_ = true;
}

double SurfaceContact::max_step(const Points& from, const double* direction) {
  if (!enabled()) return 1;
  const PartTimer timer(&part_seconds_.ccd, &part_seconds_.rebuild);
  // How far parts of the surface that may meet move relative to each other over the whole step,
  // piece by piece (see PieceMotion): two pieces whose boxes where the move starts lie
  // apart by more than their relative motion over all of it and dhat cannot meet in it, and do
  // not count (a piece falling away from another, or beside it).
  const double dhat = settings_.thickness;
  const Eigen::Map<const Points> motion(direction, from.rows(), 3);
  const auto moved_by = [&](Index n) { return Vec3(motion.row(n).transpose()); };
  vertex_motion(moved_by, &move_motion_);
  // What the list made for the move must reach beyond dhat for pieces p and q: their relative
  // motion; within a piece whose turn was taken out (below), twice the residual r, and |w| (dhat
  // + 2 r) more: along a straight move a turn stretches pairs apart, so a pair that comes within
  // dhat midway lies up to that much farther at the move's end, where the list is made.
  // Between two pieces whose turns were fitted, what the list must reach is how far a pair that
  // comes within dhat moves relative to itself (PieceMotion::fitted), and the move's turn is
  // bounded by kMaxTurn as a piece's own (the list made at its end also bounds how much its pairs
  // closed since its start: see kMaxTurn).
  const auto move_relative = [&](Index p, Index q) {
    if (p != q) {
      const auto i = static_cast<std::size_t>(p), j = static_cast<std::size_t>(q);
      const double plain = move_motion_.moved_apart(i, j);
      if (!move_motion_.fits(i, j)) return plain;
      const PieceMotion::Fitted fit = move_motion_.fitted(i, j);
      return std::min(plain, fit.closing + fit.turn * (dhat + fit.closing));
    }
    const auto i = static_cast<std::size_t>(p);
    const double turned = move_motion_.turned[i], plain = 2 * move_motion_.radius[i];
    return std::isfinite(turned) ? std::min(plain, 2 * turned + move_motion_.turn[i] * (dhat + 2 * turned)) : plain;
  };
  // The largest of those of pieces that may meet, given their boxes at `from` or lower bounds of
  // them (apart by `gap` less the motion `since`), and the largest turn it counts.
  double turning = 0;
  const auto largest = [&](const PieceBoxes& boxes, const PieceMotion* since) {
    double whole = 0;
    turning = 0;
    const double reach = move_motion_.farthest() + (since ? since->farthest() : 0.0) + dhat;
    for_near_pieces(boxes, reach, [&](Index p, Index q, double gap) {
      const double relative = move_relative(p, q);
      if (p != q && gap - (since ? since->relative(p, q) : 0.0) - relative > dhat) return true;
      whole = std::max(whole, relative);
      const auto i = static_cast<std::size_t>(p), j = static_cast<std::size_t>(q);
      if (p == q && relative < 2 * move_motion_.radius[i]) turning = std::max(turning, move_motion_.turn[i]);
      if (p != q && relative < move_motion_.moved_apart(i, j)) turning = std::max({turning, move_motion_.turn[i], move_motion_.turn[j]});
      return true;
    });
    return whole;
  };
  // One piece: its own motion. Of several, first from the boxes where the list was made and the
  // nodes' motion since (no vertex placed); where that would shorten the move, from the boxes at
  // `from`. And where the move would still be shortened, with each piece's turn taken out (a
  // piece spinning on its own had every move cut to the trust region: its ends move far against
  // each other, though no two of its points come closer).
  // (The nodes' motion since the list and the boxes at `from` do not depend on the turns: each
  // is made once a call, where first needed.)
  const bool listed = rho_ >= 0 && reference_nodes_.rows() == from.rows();
  bool from_motion_made = false, from_boxes_made = false;
  const auto whole_move = [&]() {
    if (pieces_ == 1) {
      const double whole = move_relative(0, 0);
      turning = whole < 2 * move_motion_.radius[0] ? move_motion_.turn[0] : 0.0;
      return whole;
    }
    double whole = 0;
    if (pieces_ > 1) {
      whole = std::numeric_limits<double>::infinity();
      if (listed) {
        if (!from_motion_made) node_motion(from, reference_nodes_, &from_motion_);
        from_motion_made = true;
        whole = largest(reference_boxes_, &from_motion_);
      }
      if (whole > 2 * kMaxSweep * dhat) {
        if (!from_boxes_made) {
          piece_boxes([&](Index v) { return embedded(v, [&](Index n) { return Vec3(from.row(n).transpose()); }); }, &from_boxes_);
        }
        from_boxes_made = true;
        whole = largest(from_boxes_, nullptr);
      }
    }
    return whole;
  };
  double whole = whole_move();
  if (whole > 2 * kMaxSweep * dhat) {
    // From the nodes (a few thousand; from the vertices it was 0.5 ms a call on the femur).
    piece_turn(piece_nodes_, moved_by, [&](Index n) { return Vec3(from.row(n).transpose()); }, weight_bound_, &move_motion_);
    whole = whole_move();
  }
  guards_held_ = false;
  if (!(whole > 0)) return 1;
  // The move is taken in legs, each within the trust region (and its turns within kMaxTurn where a
  // turn was taken out): each leg's list covers that leg only, so a list never grows with the
  // whole move. A leg over which nothing comes closer than conservative advancement allows leads
  // to the next, up to kMaxLegs; the first leg that stops short ends the move there. Cut to one
  // leg, a piece sliding along another faster than 2 kMaxSweep dhat a Newton move was held to that
  // speed in the real-time solver; a wild direction on a pile stops within its first leg, where
  // the pile's pairs meet. Where guards hold the surface, the whole move stays within what their
  // planes, held from the step's start, allow (guards_share).
  direction_placed_ = false;
  const double leg = std::min({1.0, 2 * kMaxSweep * dhat / whole, turning > 0 ? kMaxTurn / turning : 1.0});
  const double limit = guards_.empty() ? 1.0 : guards_share(from, motion);
  // A leg whose list came out empty (nothing within its reach, no guard) is followed by one twice
  // as long, up to kMaxLegGrowth times the trust region: a piece deforming on its own, nothing
  // near it (the hanging femur), takes its moves in a few legs, not one list for every 4
  // thicknesses of them. Where anything was listed, legs keep the trust region's length.
  double done = 0, length = leg;  // the share of the direction behind the leg, and the next leg's
  for (int legs = 1;; ++legs) {
    const double share = std::min(length, limit - done);
    if (legs > 1) leg_start_.swap(move_end_);  // the last leg's end (leg_step makes move_end_ anew)
    const double t = leg_step(legs == 1 ? from : leg_start_, motion, share, share * whole);
    if (t < 1 || legs == kMaxLegs || !(done + share < limit)) {
      guards_held_ = t == 1 && limit < 1 && !(done + share < limit);
      return done + t * share;
    }
    done += share;
    length = candidates_.empty() && guards_.empty() ? std::min(2 * length, kMaxLegGrowth * leg) : leg;
  }
}

void SurfaceContact::place_direction(const Eigen::Map<const Points>& motion) {
  if (direction_placed_) return;
  node_move_ = motion;
  place(node_move_, &direction_move_);
  direction_placed_ = true;
}

double SurfaceContact::guards_share(const Points& from, const Eigen::Map<const Points>& motion) {
  // A guard holds g = n0 . r - zero above -wall, where r = sum_i w_i corner_i runs from a point of
  // its triangle's plane (or of an edge in it) to the guarded vertex or edge, and n0 is the
  // triangle's unit normal at the step's start. The side's true offset from the plane is n . r,
  // with n the triangle's normal now: g is off by (n - n0) . r, at most |n - n0| |r|. Over a
  // straight move to share s, r is linear (|r| at most its larger end) and the triangle's doubled
  // area vector c = E1 x E2 quadratic, c(t) - c(0) = t (E1 x D2 + D1 x E2) + t^2 D1 x D2 (D the
  // edges' motions): n(t) turns from n(0) by at most the part of that across n(0) over what is
  // left of |c(0)| along it (a face stretched in its plane does not turn); |n(0) - n0| is
  // measured. That error may use the allowance behind the wall (1 - kGuardWall of it) and
  // whatever the guard stays clear of its wall by over the move (g is linear, and CCD stops it
  // short of -wall): so the side never lies deeper behind its triangle's true plane than the
  // allowance (or, for a guard made where its side lay behind the wall already, to push it back
  // out, than a hair beyond that wall: guard_depth). Both sides are monotone in s: the largest s
  // is found by bisection where s = 1 fails. Each move starts where the last ended within its
  // bound, and guards start with n = n0 (at a step's start, or made again within it), so the
  // error is bounded over the whole step, not only within a move. A face
  // turning with the guarded side (the halves of a cut spinning together) has r across the gap,
  // a few hundredths of dhat, and moves freely; a side sliding along a turning face is held as
  // far as its own slide and that face's turn require. (Before, a bound per pair of pieces from
  // their fitted turns and relative motion, argued from an older rule's worst case: it cut the
  // first step of the spinning halves to about a half.) O(guards + V).
  place_direction(motion);
  // The vertices at `from`: y_ where it was placed there (CCD's next move from an evaluated point).
  const bool placed = y_nodes_.rows() == from.rows() && y_nodes_ == from;
  if (!placed) place(from, &guard_from_);
  const Points& at_from = placed ? y_ : guard_from_;
  // Each triangle's terms once (O(guards' triangles)), then each guard's bound (O(guards)).
  triangle_turns_.resize(guard_triangles_.size());
  for_chunks(static_cast<Index>(guard_triangles_.size()), kNodeChunk, [&](Index begin, Index end, Index) {
    for (Index k = begin; k < end; ++k) {
      const auto& tri = triangles_[static_cast<std::size_t>(guard_triangles_[static_cast<std::size_t>(k)])];
      const auto at = [&](int i) { return Vec3(at_from.row(tri[static_cast<std::size_t>(i)]).transpose()); };
      const auto moved = [&](int i) { return Vec3(direction_move_.row(tri[static_cast<std::size_t>(i)]).transpose()); };
      const Vec3 e1 = at(1) - at(0), e2 = at(2) - at(0), d1 = moved(1) - moved(0), d2 = moved(2) - moved(0);
      const Vec3 c0 = e1.cross(e2);
      TriangleTurn& turn = triangle_turns_[static_cast<std::size_t>(k)];
      turn.area = c0.norm();
      turn.normal = turn.area > 0 ? Vec3(c0 / turn.area) : Vec3::Zero();
      const Vec3& n = turn.normal;
      const Vec3 linear = e1.cross(d2) + d1.cross(e2), square = d1.cross(d2);
      // c(t) - c(0) along n (a change of area, no turn) and across it (a turn).
      turn.linear_along = std::abs(linear.dot(n));
      turn.square_along = std::abs(square.dot(n));
      turn.linear_across = (linear - linear.dot(n) * n).norm();
      turn.square_across = (square - square.dot(n) * n).norm();
    }
  });
  return min_chunks(static_cast<Index>(guards_.size()), kNodeChunk, 1.0, &chunk_least_, [&](Index begin, Index end) {
    double least = 1;
    for (Index k = begin; k < end; ++k) {
      const Guard& guard = guards_[static_cast<std::size_t>(k)];
      const Vec3 r0 = guard_vector(guard, at_from), dr = guard_vector(guard, direction_move_);
      const TriangleTurn& terms = triangle_turns_[static_cast<std::size_t>(guard_triangle_slot_[static_cast<std::size_t>(guard.triangle)])];
      const double area = terms.area, linear_along = terms.linear_along, square_along = terms.square_along;
      const double linear_across = terms.linear_across, square_across = terms.square_across;
      const double turned = area > 0 ? (terms.normal - guard.normal).norm() : 2.0;
      const double g0 = guard.normal.dot(r0) - guard.zero, rate = guard.normal.dot(dr);
      const auto error = [&](double s) {
        // |n(t) - n(0)| <= the angle between c(t) and c(0) <= its tangent, |c(t) - c(0)| across n
        // over c(0)'s length plus the change along n (while that stays positive).
        const double below = area - s * linear_along - s * s * square_along;
        const double turn = below > 0 ? std::min(2.0, turned + (s * linear_across + s * s * square_across) / below) : 2.0;
        return turn * std::max(r0.norm(), (r0 + s * dr).norm());
      };
      const double allowed = guard_depth(guard);
      const auto room = [&](double s) { return allowed + std::max(-guard.wall, std::min(g0, g0 + s * rate)); };
      if (error(least) <= room(least)) continue;
      // Past the room where the move starts (not along moves this allowed: each starts where the
      // last ended within it, and a step's guards start with n = n0): no bound from this guard.
      if (!(error(0) <= room(0))) continue;
      double lo = 0, hi = least;
      for (int i = 0; i < kGuardBisections; ++i) {
        const double mid = (lo + hi) / 2;
        (error(mid) <= room(mid) ? lo : hi) = mid;
      }
      least = lo;
    }
    return least;
  });
}

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

double SurfaceContact::leg_step(const Points& from, const Eigen::Map<const Points>& motion, double share, double relative) {
  move_end_ = from + share * motion;
  cover(from, &move_end_, relative);
  // Each vertex's motion over the move, once, for the pairs and the guards (a candidate's and a
  // guard's corners were embedded each time: 100k corners against 43k vertices on the sliced hand):
  // the direction's, placed once a call, scaled to the leg.
  if (!candidates_.empty() || !guards_.empty()) {
    place_direction(motion);
    vertex_move_ = share * direction_move_;
  }
  const bool counted_measured = (measured_ & kCounted) != 0;
  const double t_pairs = min_chunks(static_cast<Index>(candidates_.size()), kNodeChunk, 1.0, &chunk_least_, [&](Index begin, Index end) {
    double t_min = 1;
    for (Index k = begin; k < end; ++k) {
      const Candidate& c = candidates_[k];
      if (c.joined || c.sutured) continue;
      // Listed too far apart to meet in this move, its corners unread: at the move's start it is
      // at least reference_distance less reference_relative_ apart, and over the move its
      // corners move at most `relative` against each other, so each at most that from its pair's
      // mean: the bound below exceeds no 2 relative, and this pair would be skipped there. (Of
      // pieces found apart over the whole move above, the pair stays beyond dhat anyway.)
      if (c.reference_distance - reference_relative_ - 2 * relative > kBoundSlack * settings_.thickness) continue;
      const std::array<Index, 4> corner = corners(c);
      std::array<Vec3, 4> y, d;
      Vec3 mean = Vec3::Zero();
      for (int i = 0; i < 4; ++i) {
        y[i] = y_.row(corner[i]).transpose();
        d[i] = vertex_move_.row(corner[i]).transpose();
        mean += d[i] / 4;
      }
      // A bound of how fast the distance can shrink: the motions relative to their mean.
      double bound_a = 0, bound_b = 0;
      for (int i = 0; i < 4; ++i) {
        const double speed = (d[i] - mean).norm();
        if (c.edges) {
          (i < 2 ? bound_a : bound_b) = std::max(i < 2 ? bound_a : bound_b, speed);
        } else if (i == 0) {
          bound_a = speed;
        } else {
          bound_b = std::max(bound_b, speed);
        }
      }
      const double bound = bound_a + bound_b;
      // The gap of their boxes bounds the distance from below: beyond reach by it, beyond reach.
      if (bound > 0 && gap_between(y, c.edges) - bound > 0) continue;
      const auto proximity_along = [&](double t) {
        const auto p = [&](int i) -> Vec3 { return y[i] + t * d[i]; };
        return proximity_at({p(0), p(1), p(2), p(3)}, c.edges);
      };
      // Where the pair was measured at the move's start already (within dhat, at y_: the Newton
      // step's evaluation there), that.
      collision::Proximity at = counted_measured && std::isfinite(distances_[k]) ? proximities_[k] : proximity_along(0);
      const double start = at.distance;
      if (!(bound > 0) || start - bound > 0) continue;  // cannot come within reach this step
      if (!(start > 0)) {
        t_min = 0;
        continue;
      }
      // Conservative advancement (ACCD): from t, with the distance there, each advance covers
      // kAdvanceShare of it over the bound (the first, 1 - kKeepShare), and stops once the
      // distance reached would fall below kKeepShare of the start. The bound counts how fast the
      // corners slide as well as how fast they close: a pair sliding along another a hair apart
      // (an edge resting 5e-7 from another under the sliced hand's upper part, 3e-4 dhat, its
      // corners sliding thousands of times that a move) advanced by a hair each time, and held
      // each Newton move to a hundredth. So each advance goes at least as far as the two stay
      // apart along the direction between their closest points: the first primitive's corners'
      // least reach along it less the second's most (convex sets apart by that much along a unit
      // vector are apart by that much at least), linear in t corner by corner, and equal to the
      // distance where measured (the closest points' direction separates the sets there). Sliding
      // pairs cover the move in one advance.
      const int split = c.edges ? 2 : 1;  // the first primitive's corners, then the second's
      const double keep = kKeepShare * start;
      const auto apart_until = [&](const collision::Proximity& measured, double t) {
        if (!(measured.distance > 0)) return t;
        const Vec3 n = measured.r / measured.distance;  // from the second primitive to the first
        double until = 1;
        for (int i = 0; i < split; ++i) {
          for (int j = split; j < 4; ++j) {
            const double gap = n.dot(y[i] - y[j]), rate = n.dot(d[i] - d[j]);
            if (rate < 0) until = std::min(until, (keep - gap) / rate);
          }
        }
        return std::max(t, until);
      };
      double t = 0, advance = (1 - kKeepShare) * start / bound;
      for (int i = 0; i < kMaxAdvances; ++i) {
        const double next = std::min(1.0, std::max(t + advance, apart_until(at, t)));
        const collision::Proximity reached = proximity_along(next);
        if (t > 0 && reached.distance < keep) break;
        t = next;
        if (t >= 1) break;
        at = reached;
        advance = kAdvanceShare * reached.distance / bound;
      }
      t_min = std::min(t_min, t);
    }
    return t_min;
  });
  const double t_guard = min_chunks(static_cast<Index>(guards_.size()), kNodeChunk, 1.0, &chunk_least_, [&](Index begin, Index end) {
    double t_min = 1;
    for (Index k = begin; k < end; ++k) {
      const Guard& guard = guards_[static_cast<std::size_t>(k)];
      const double rate = guard.normal.dot(guard_vector(guard, vertex_move_));  // over the leg
      // g is linear along the step: stop where all but kKeepShare of what was left of the
      // allowance is used up. (y_: the vertices at `from`, see cover.)
      if (rate < 0) t_min = std::min(t_min, std::max(0.0, (1 - kKeepShare) * (guard_gap(guard, y_) + guard.wall) / -rate));
    }
    return t_min;
  });
  return std::min(t_guard, t_pairs);
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
