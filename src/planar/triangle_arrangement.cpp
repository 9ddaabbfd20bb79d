#include "planar/triangle_arrangement.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "util/broken.hpp"
#include "util/union_find.hpp"

namespace tetcut::planar {

namespace {
void note_vertex(PlanarGeometry& geometry, VertexId v, Index edge) {
  if (static_cast<std::size_t>(v) >= geometry.vertex_edge.size()) geometry.vertex_edge.resize(v + 1, -1);
  geometry.vertex_edge[v] = edge;
}
}  // namespace

VertexId PlanarGeometry::edge_point(Index edge, PlaneId line) {
  // A side holds few points (one per line crossing it), so a scan is cheaper than any index.
  for (const VertexId v : edge_points[edge]) {
    if (registry.side(v, line) == 0) return v;
  }
  const VertexId v = registry.add_point(line, edge_line[edge], rest_plane);
  edge_points[edge].push_back(v);
  note_vertex(*this, v, edge);
  return v;
}

VertexId PlanarGeometry::interior_point(PlaneId a, PlaneId b) {
  const VertexId v = registry.add_point(a, b, rest_plane);
  note_vertex(*this, v, -1);
  return v;
}

TriangleArrangement::TriangleArrangement(std::array<VertexId, 3> corners, std::array<PlaneId, 3> side_lines,
                                         std::array<Index, 3> side_edges, Index label)
    : corners_(corners), side_edges_(side_edges) {
  // Inner half-edge of side k is 2k (corner k to k + 1, in face 0); its twin 2k + 1 runs the other
  // way outside, and the outside loop turns clockwise: outer k is followed by outer k + 2.
  half_edges_.resize(6);
  for (int k = 0; k < 3; ++k) {
    HalfEdge& inner = half_edges_[2 * k];
    inner = {corners[k], 2 * k + 1, 2 * ((k + 1) % 3), 0, side_lines[k], static_cast<std::int8_t>(k), -1};
    HalfEdge& outer = half_edges_[2 * k + 1];
    outer = {corners[(k + 1) % 3], 2 * k, 2 * ((k + 2) % 3) + 1, -1, side_lines[k], static_cast<std::int8_t>(k), -1};
  }
  faces_.push_back({0, label});
}

bool TriangleArrangement::insert(PlanarGeometry& geometry, const PreparedSegment& segment) {
  bool changed = false;
  // Faces made by this insertion lie on one side of the segment's line: nothing more to do there.
  const int existing = static_cast<int>(faces_.size());
  for (int f = 0; f < existing; ++f) {
    if (segment.label < 0 || faces_[f].label == segment.label) changed |= insert_into_face(geometry, f, segment);
  }
  return changed;
}

std::int32_t TriangleArrangement::split_edge(std::int32_t h, VertexId point) {
  const std::int32_t t = half_edges_[h].twin;
  HalfEdge after = half_edges_[h];
  after.origin = point;
  HalfEdge twin_after = half_edges_[t];
  twin_after.origin = point;
  const auto a = static_cast<std::int32_t>(half_edges_.size());
  const std::int32_t b = a + 1;
  half_edges_.push_back(after);
  half_edges_.push_back(twin_after);
  half_edges_[h].next = a;
  half_edges_[t].next = b;
  // h now ends at the point and pairs with b (point to h's origin); a pairs with t.
  half_edges_[h].twin = b;
  half_edges_[b].twin = h;
  half_edges_[a].twin = t;
  half_edges_[t].twin = a;
  return a;
}

VertexId TriangleArrangement::point_on_edge(PlanarGeometry& geometry, std::int32_t h, PlaneId line) {
  const HalfEdge& e = half_edges_[h];
  if (e.side >= 0) return geometry.edge_point(side_edges_[e.side], line);
  return geometry.interior_point(line, e.line);
}

void TriangleArrangement::cover(std::int32_t h, std::int64_t id) {
  if (half_edges_[h].covering >= 0) return;
  half_edges_[h].covering = id;
  half_edges_[half_edges_[h].twin].covering = id;
}

namespace {
// Sides of a point on the segment's line relative to each of its walls (+1 for walls it has not).
using WallSides = std::array<int, PreparedSegment::kMaxWalls>;

bool inside(const WallSides& s) { return s[0] >= 0 && s[1] >= 0 && s[2] >= 0; }

WallSides wall_sides(const PlanarGeometry& geometry, VertexId v, const PreparedSegment& segment) {
  WallSides s = {1, 1, 1};
  for (int w = 0; w < segment.num_walls; ++w) s[w] = geometry.side(v, segment.walls[w]);
  return s;
}

// A point of a chord or a collinear edge and its sides of the segment's walls.
struct ChainPoint {
  VertexId vertex;
  WallSides wall_side;
};

// What the segment makes of the stretch from a to b of a line it lies on (`carrier`, the plane the
// stretch's points are made on), from the points' sides of its walls: whether they overlap with
// positive length, and the segment's ends strictly between them, in order from a. The segment is
// an interval of the line (the walls' positive sides are convex), so where the stretch enters it
// is a wall's crossing, strictly between a and b, with a on the wall's negative side and inside
// every other wall; where it leaves, the same with a on the positive side. Two walls may cross the
// line at one point (a cut triangle's corner on the cloth): then either names it. When the entry
// and the exit are one point the stretch only touches the segment.
struct Ends {
  bool overlaps = false;
  int count = 0;
  std::array<int, 2> wall{};           ///< the wall each end lies on
  std::array<WallSides, 2> sides{};    ///< the end's sides of every wall
};

Ends ends_between(const PlanarGeometry& geometry, PlaneId carrier, const PreparedSegment& segment, const WallSides& a,
                  const WallSides& b) {
  std::array<int, 2> found = {-1, -1};  // entry, exit
  std::array<WallSides, 2> found_sides{};
  for (int w = 0; w < segment.num_walls; ++w) {
    if (a[w] * b[w] >= 0) continue;
    const int slot = a[w] < 0 ? 0 : 1;
    if (found[slot] >= 0) continue;
    WallSides at = {1, 1, 1};
    at[w] = 0;
    bool within = true;
    for (int j = 0; j < segment.num_walls && within; ++j) {
      if (j == w) continue;
      at[j] = segment.walls[j].sign *
              geometry.registry.side_of_meet(carrier, segment.walls[w].id, geometry.rest_plane, segment.walls[j].id);
      within = at[j] >= 0;
    }
    if (!within) continue;
    found[slot] = w;
    found_sides[slot] = at;
  }
  Ends ends;
  if (found[0] >= 0 && found[1] >= 0 && found_sides[0][found[1]] == 0) return ends;  // a single point
  // The chain a, entry, exit, b: a piece lies in the segment when both its ends do.
  bool previous_inside = inside(a);
  for (int slot = 0; slot < 2; ++slot) {
    if (found[slot] < 0) continue;
    ends.overlaps |= previous_inside;
    previous_inside = true;
    ends.wall[ends.count] = found[slot];
    ends.sides[ends.count] = found_sides[slot];
    ++ends.count;
  }
  ends.overlaps |= previous_inside && inside(b);
  return ends;
}

bool inside_segment(const ChainPoint& a, const ChainPoint& b) { return inside(a.wall_side) && inside(b.wall_side); }
}  // namespace

bool TriangleArrangement::cover_collinear(PlanarGeometry& geometry, std::int32_t h, const PreparedSegment& segment) {
  const VertexId u = half_edges_[h].origin, v = half_edges_[half_edges_[h].twin].origin;
  const WallSides su = wall_sides(geometry, u, segment), sv = wall_sides(geometry, v, segment);
  const Ends ends = ends_between(geometry, half_edges_[h].line, segment, su, sv);
  if (!ends.overlaps) return false;
  std::vector<ChainPoint> chain = {{u, su}};
  std::vector<std::int32_t> pieces = {h};
  for (int i = 0; i < ends.count; ++i) {
    const VertexId point = point_on_edge(geometry, pieces.back(), segment.walls[ends.wall[i]].id);
    pieces.push_back(split_edge(pieces.back(), point));
    chain.push_back({point, ends.sides[i]});
  }
  chain.push_back({v, sv});
  bool changed = false;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (!inside_segment(chain[i], chain[i + 1]) || half_edges_[pieces[i]].covering >= 0) continue;
    cover(pieces[i], segment.id);
    changed = true;
  }
  return changed;
}

bool TriangleArrangement::insert_into_face(PlanarGeometry& geometry, int face, const PreparedSegment& segment) {
  const auto& registry = geometry.registry;
  std::vector<std::int32_t> loop;
  for (std::int32_t h = faces_[face].half_edge;;) {
    loop.push_back(h);
    h = half_edges_[h].next;
    if (h == faces_[face].half_edge) break;
  }
  const int m = static_cast<int>(loop.size());
  std::vector<int> sides(m);
  bool positive = false, negative = false;
  for (int i = 0; i < m; ++i) {
    sides[i] = registry.side(half_edges_[loop[i]].origin, segment.line);
    positive |= sides[i] > 0;
    negative |= sides[i] < 0;
  }
  if (!(positive && negative)) {
    // The line misses the open cell; edges lying on it may still be covered.
    std::vector<std::int32_t> collinear;
    for (int i = 0; i < m; ++i) {
      if (sides[i] == 0 && sides[(i + 1) % m] == 0) collinear.push_back(loop[i]);
    }
    bool changed = false;
    for (const std::int32_t h : collinear) changed |= cover_collinear(geometry, h, segment);
    return changed;
  }

  // The line crosses the cell: exactly two crossings, each at a corner on the line or strictly
  // inside an edge whose ends it separates (convexity), found in counter-clockwise order.
  struct Crossing {
    int index;
    bool at_corner;
    WallSides wall_side;
  };
  std::array<Crossing, 2> crossings{};
  int found = 0;
  for (int i = 0; i < m && found < 2; ++i) {
    const HalfEdge& e = half_edges_[loop[i]];
    if (sides[i] == 0) {
      crossings[found++] = {i, true, wall_sides(geometry, e.origin, segment)};
    } else if (sides[i] * sides[(i + 1) % m] < 0) {
      WallSides wall_side = {1, 1, 1};
      for (int w = 0; w < segment.num_walls; ++w) {
        wall_side[w] = segment.walls[w].sign *
                       registry.side_of_meet(segment.line, e.line, geometry.rest_plane, segment.walls[w].id);
      }
      crossings[found++] = {i, false, wall_side};
    }
  }
  if (found != 2) broken("planar", "a line crossing a convex cell does not cross its boundary twice");
  const Ends ends = ends_between(geometry, segment.line, segment, crossings[0].wall_side, crossings[1].wall_side);
  if (!ends.overlaps) return false;

  // Make both crossings corners of the cell.
  std::array<std::int32_t, 2> from{};
  for (int c = 0; c < 2; ++c) {
    const std::int32_t h = loop[crossings[c].index];
    if (crossings[c].at_corner) {
      from[c] = h;
    } else {
      from[c] = split_edge(h, point_on_edge(geometry, h, segment.line));
    }
  }
  std::vector<ChainPoint> chain = {{half_edges_[from[0]].origin, crossings[0].wall_side}};
  for (int i = 0; i < ends.count; ++i) {
    // The segment's end lies strictly inside the chord, so inside the open cell: a new point.
    chain.push_back({geometry.interior_point(segment.line, segment.walls[ends.wall[i]].id), ends.sides[i]});
  }
  chain.push_back({half_edges_[from[1]].origin, crossings[1].wall_side});

  // Split: this face keeps the boundary from the first crossing to the second and returns along
  // the chord; a new face takes the rest and goes along the chord the other way.
  auto predecessor = [&](std::int32_t h) {
    std::int32_t p = h;
    while (half_edges_[p].next != h) p = half_edges_[p].next;
    return p;
  };
  const std::int32_t before_first = predecessor(from[0]), before_second = predecessor(from[1]);
  const auto new_face = static_cast<std::int32_t>(faces_.size());
  faces_.push_back({from[1], faces_[face].label});
  const int pieces = static_cast<int>(chain.size()) - 1;
  const auto first_piece = static_cast<std::int32_t>(half_edges_.size());
  // Piece i: forward (chain i to i + 1, new face) at first_piece + 2i, backward at + 2i + 1.
  for (int i = 0; i < pieces; ++i) {
    const std::int32_t forward = first_piece + 2 * i, backward = forward + 1;
    const std::int64_t covering = inside_segment(chain[i], chain[i + 1]) ? segment.id : -1;
    half_edges_.push_back({chain[i].vertex, backward, i + 1 < pieces ? forward + 2 : from[1], new_face, segment.line, -1,
                           covering});
    half_edges_.push_back({chain[i + 1].vertex, forward, i > 0 ? backward - 2 : from[0], face, segment.line, -1,
                           covering});
  }
  half_edges_[before_first].next = first_piece;
  half_edges_[before_second].next = first_piece + 2 * (pieces - 1) + 1;
  faces_[face].half_edge = from[0];
  for (std::int32_t h = from[1];;) {
    half_edges_[h].face = new_face;
    h = half_edges_[h].next;
    if (h == from[1]) break;
  }
  return true;
}

int TriangleArrangement::components(std::vector<int>* face_component) const {
  UnionFind sets(faces_.size());
  for (const HalfEdge& e : half_edges_) {
    const std::int32_t other = half_edges_[e.twin].face;
    if (e.face >= 0 && other >= 0 && e.covering < 0) sets.join(e.face, other);
  }
  face_component->assign(faces_.size(), -1);
  std::vector<int> root_component(faces_.size(), -1);
  int count = 0;
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    int& c = root_component[sets.find(static_cast<Index>(f))];
    if (c < 0) c = count++;
    (*face_component)[f] = c;
  }
  return count;
}

SideIntervals TriangleArrangement::side_intervals(int k) const {
  std::vector<std::int32_t> on_side;
  for (std::size_t h = 0; h < half_edges_.size(); ++h) {
    if (half_edges_[h].side == k && half_edges_[h].face >= 0) on_side.push_back(static_cast<std::int32_t>(h));
  }
  SideIntervals out;
  const VertexId end = corners_[(k + 1) % 3];
  for (VertexId v = corners_[k]; v != end;) {
    std::int32_t piece = -1;
    for (const std::int32_t h : on_side) {
      if (half_edges_[h].origin == v) piece = h;
    }
    if (piece < 0) broken("planar", "a triangle's side is not a chain of edges");
    const HalfEdge& e = half_edges_[piece];
    out.points.push_back(v);
    out.labels.push_back(faces_[e.face].label);
    out.covered.push_back(e.covering >= 0 ? 1 : 0);
    v = half_edges_[e.twin].origin;
  }
  out.points.push_back(end);
  return out;
}

std::vector<VertexId> TriangleArrangement::face_corners(int face) const {
  std::vector<VertexId> corners;
  for (std::int32_t h = faces_[face].half_edge;;) {
    corners.push_back(half_edges_[h].origin);
    h = half_edges_[h].next;
    if (h == faces_[face].half_edge) break;
  }
  return corners;
}

double TriangleArrangement::face_area(const registry::IntersectionRegistry& registry, int face) const {
  // Shoelace about the first corner, with a bound on its error: rounded corners are off by at most
  // `delta` each, and each product rounds. A cell thinner than that rounding (a cut passing 1e-17
  // from a node) would come out with an arbitrary sign, so then the area is summed exactly.
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  const std::vector<VertexId> corners = face_corners(face);
  const Vec3& o = registry.position(corners[0]);
  double largest = 0;
  for (const VertexId v : corners) largest = std::max(largest, registry.position(v).cwiseAbs().maxCoeff());
  const double delta = 2 * registry::IntersectionRegistry::position_tolerance() * largest;
  double twice = 0, bound = 0;
  for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
    const Vec3 a = registry.position(corners[i]) - o, b = registry.position(corners[i + 1]) - o;
    twice += a.x() * b.y() - a.y() * b.x();
    const double na = a.head<2>().norm(), nb = b.head<2>().norm();
    bound += 2 * delta * (na + nb + 2 * delta) + 8 * kEps * (na * nb + largest * (na + nb));
  }
  if (std::abs(twice) > bound) return 0.5 * twice;
  // Exactly: the sum over edges of (Xa Yb - Ya Xb) / (Wa Wb), in rationals (rare, and cells are small).
  mpq_class sum = 0;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const geometry::ExactPoint a = registry.exact_homogeneous(corners[i]);
    const geometry::ExactPoint b = registry.exact_homogeneous(corners[(i + 1) % corners.size()]);
    mpq_class term(mpz_class(a[0] * b[1] - a[1] * b[0]), mpz_class(a[3] * b[3]));
    term.canonicalize();
    sum += term;
  }
  return 0.5 * sum.get_d();
}

}  // namespace tetcut::planar
