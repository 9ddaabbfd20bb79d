// Surface contact (see surface_contact.hpp): the surface taken from a cut and what it is made of
// (copies, primitives, rest normals, facing), the barrier and its terms, friction, and the pairs'
// measures. The candidate list and conservative advancement are in surface_contact_list.cpp, the
// guards and joins of a cut's two sides in surface_contact_guards.cpp.

#include "sim/surface_contact.hpp"

#include "sim/block_sparse.hpp"
#include "sim/surface_contact_parts.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace tetcut::sim::detail {

using contact_parts::kFacing;
using contact_parts::measure_within;
using contact_parts::PartTimer;
using contact_parts::proximity_at;
using contact_parts::unit_normal;

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

}  // namespace tetcut::sim::detail
