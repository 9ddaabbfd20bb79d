// Surface contact's candidate list (see surface_contact.hpp, "Broad phase"): the pieces and their
// motion bounds, the Verlet lists of pairs of copies and of primitives, and conservative
// advancement with its trust region in legs and the guards' bound on a move.

#include "sim/surface_contact.hpp"

#include "sim/block_sparse.hpp"
#include "sim/surface_contact_parts.hpp"

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

std::uint64_t copy_pair(Index a, Index b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
  return lo << 32 | hi;
}

}  // namespace

using contact_parts::gap_between;
using contact_parts::kFacing;
using contact_parts::measure_within;
using contact_parts::PartTimer;
using contact_parts::proximity_at;

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

}  // namespace tetcut::sim::detail
