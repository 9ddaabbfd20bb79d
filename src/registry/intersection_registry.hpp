#pragma once
// The intersection registry (paper, Appendix A). Every point the cutter uses is the meeting of three
// planes, each the supporting plane of a triangle of one big soup: a tet face, a cut triangle, or a
// virtual triangle through one edge of a cut triangle. The paper writes the virtual triangle as
// pq∅ with ∅ an unspecified point; here ∅ is p plus a coordinate axis, so the virtual triangle's
// plane is the "wall" through pq along that axis (geometry/plane.hpp). Mesh nodes are registered as
// the meeting of three faces of a tet.
//
// Nothing is rounded while topology is decided: a point is its three planes plus filtered
// homogeneous coordinates, and side tests are exact (filter first, GMP when the filter cannot
// decide). Planes made from the same input doubles are stored once (keyed by those doubles, never
// by rounded values). Points are never duplicated: the cell complex creates a point only strictly
// inside one of its edges, where no other point can be, and it recognises a point that a new triple
// names by an exact side test returning zero.
//
// Threads: add_point, add_node and add_plane may run concurrently with each other and with reads
// (planes and points live in concurrent vectors, whose elements never move), and so may side
// tests: their exact caches are filled under a lock (the exact path is rare), and an insertion's
// memo of side tests (SideMemo) is its own, passed to side(). triangle_plane and wall, which look
// up equal planes, are sequential. A point's rounded position is computed when it is added, so
// position() only reads.

#include <tetcut/types.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <tbb/concurrent_vector.h>
#include <unordered_map>
#include <vector>

#include "geometry/plane.hpp"
#include "util/hash.hpp"

namespace tetcut::registry {

using PlaneId = std::int32_t;
using VertexId = std::int32_t;

/// What names the wall through edge (p, q) along an axis, so that it is stored once: the edge's
/// ends in lexicographic order, whichever way the edge is given, as the bits of their coordinates
/// (-0.0 folded into 0.0), and the axis. The registry keys its walls by it, and PlaneBook its
/// world-space walls, which are not the registry's planes.
using WallKey = std::array<double, 7>;
/// The key of the wall through (p, q) along `axis`; `*swapped` tells whether the ends are in the
/// order (q, p) in it.
WallKey wall_key(const Vec3& p, const Vec3& q, int axis, bool* swapped);

/// A stored plane and how a requested orientation relates to it: sign +1 when the stored plane's
/// normal points the requested way, -1 when opposite.
struct OrientedPlane {
  PlaneId id = -1;
  int sign = 1;
};

struct Vertex {
  std::array<PlaneId, 3> planes{};
  geometry::Homogeneous homogeneous{};
  std::int8_t orientation = 1;  ///< sign of the homogeneous W
  Index node = -1;              ///< the mesh node, for input points; -1 for intersections
  Vec3 position = Vec3::Zero(); ///< rounded coordinates (see IntersectionRegistry::position)
};

class IntersectionRegistry {
 public:
  /// `rest` holds the mesh nodes' rest positions (|V| x 3); it must outlive the registry.
  explicit IntersectionRegistry(const Points& rest) : rest_(&rest) {}

  /// Stores a plane without looking for an equal one.
  PlaneId add_plane(const geometry::Plane& plane);
  /// The plane through a, b, c (not collinear), oriented by (b - a) x (c - a). The same three
  /// points in any order give the same stored plane.
  OrientedPlane triangle_plane(const Vec3& a, const Vec3& b, const Vec3& c);
  /// The wall through p and q along `axis`, oriented so that `inner` (off the wall) is on its
  /// positive side. The same edge and axis give the same stored plane.
  OrientedPlane wall(const Vec3& p, const Vec3& q, int axis, const Vec3& inner);

  /// Registers the point where a, b and c meet; they must meet in exactly one point.
  VertexId add_point(PlaneId a, PlaneId b, PlaneId c);
  /// Registers mesh node `node`, which lies on the three planes a, b, c.
  VertexId add_node(Index node, PlaneId a, PlaneId b, PlaneId c);

  /// Sign (+1, 0, -1) of plane q at vertex v. Exact.
  int side(VertexId v, PlaneId q) const { return compute_side(v, q); }
  /// The same for a plane that is not stored in the registry. Exact; not memoised.
  int side(VertexId v, const geometry::Plane& q) const;
  /// Side of q at the point where a, b and c meet, without registering that point (they must meet
  /// in exactly one point). Exact.
  int side_of_meet(PlaneId a, PlaneId b, PlaneId c, PlaneId q) const;
  /// Side of q at an input point. Exact; zero at once when x defines q.
  int side_of_input(PlaneId q, const Vec3& x) const;
  /// Sign of the dot product of two planes' normals. Exact.
  int normal_alignment(PlaneId a, PlaneId b) const;

  /// Whether v lies on q by construction, decided from the input points defining the planes: a
  /// plane passes through its defining points, and two planes through the same two points meet
  /// in the line through them. Sound, not complete (false says nothing); side() asks it before the
  /// exact path, to settle the commonest zeros (corners and edges shared by a surface's triangles).
  bool on_plane_by_construction(VertexId v, PlaneId q) const;

  /// Coordinates of v, correctly rounded or nearly (geometry::tpi_coordinates). For output and
  /// for sound filters widened by position_tolerance(), never for decisions.
  const Vec3& position(VertexId v) const { return vertices_[v].position; }
  /// Exact homogeneous coordinates of v, X / W (slow: for measurements rounding cannot settle).
  /// Uses no cache, so it is safe to call concurrently.
  geometry::ExactPoint exact_homogeneous(VertexId v) const;
  /// Bound on the error of each rounded coordinate of position(), relative to the position's
  /// largest coordinate (see geometry::tpi_coordinates).
  static double position_tolerance();

  const geometry::Plane& plane(PlaneId p) const { return planes_[p]; }
  const Vertex& vertex(VertexId v) const { return vertices_[v]; }
  PlaneId num_planes() const { return static_cast<PlaneId>(planes_.size()); }
  VertexId num_vertices() const { return static_cast<VertexId>(vertices_.size()); }

  /// Side tests against up to four planes (one cut triangle's plane and walls), remembered per
  /// vertex: the splits of one insertion ask the same vertex many times. A memo serves one
  /// insertion at a time (begin starts the next, forgetting the last); insertions running at once
  /// each use their own. Memory: two words per registry vertex, grown as vertices are asked about.
  class SideMemo {
   public:
    void begin(const IntersectionRegistry& registry, std::initializer_list<PlaneId> planes);

   private:
    friend class IntersectionRegistry;
    static constexpr std::int8_t kUnknown = 2;
    const IntersectionRegistry* owner_ = nullptr;
    std::array<PlaneId, 4> planes_{-1, -1, -1, -1};
    std::uint32_t stamp_ = 0;
    std::vector<std::uint32_t> vertex_stamp_;            // per vertex: the stamp its sides are of
    std::vector<std::array<std::int8_t, 4>> sides_;      // per vertex: sign per plane, or kUnknown
  };
  /// side(v, q), remembered in `memo` when q is one of the planes it was begun with (a null memo
  /// remembers nothing).
  int side(VertexId v, PlaneId q, SideMemo* memo) const;

 private:
  int compute_side(VertexId v, PlaneId q) const;
  Vec3 compute_position(const Vertex& vertex) const;
  VertexId push_vertex(Vertex vertex);
  // Exact forms, computed when a filter first fails and kept: later exact tests on the same plane
  // or point are then a four-term integer dot product.
  const geometry::ExactPlane& exact_plane(PlaneId p) const;
  const geometry::ExactPoint& exact_point(VertexId v) const;

  const Points* rest_;
  tbb::concurrent_vector<geometry::Plane> planes_;
  tbb::concurrent_vector<Vertex> vertices_;
  mutable std::mutex exact_mutex_;  // guards the two caches below
  mutable std::vector<std::unique_ptr<geometry::ExactPlane>> exact_planes_;
  mutable std::vector<std::unique_ptr<geometry::ExactPoint>> exact_points_;
  std::unordered_map<std::array<double, 9>, PlaneId, WordsHash> triangle_planes_;  // by sorted corners
  std::unordered_map<WallKey, PlaneId, WordsHash> walls_;
};

}  // namespace tetcut::registry
