#pragma once
// The material of the whole mesh as one complex of convex cells, refined by cut triangles.
//
// Every tet starts as one cell bounded by its four faces. A tet is "refined" (given explicit cells,
// facets and edges) the first time a cut triangle touches it; until then it is implicit, one cell,
// and facets of refined neighbours refer to it by its tet id. This keeps the cost of a cut
// proportional to the tets it touches, not to the size of the mesh.
//
// Inserting a cut triangle splits by its plane only the cells whose section by that plane overlaps
// the triangle with positive area (an exact separating-axis test). The new facet on the plane is
// then split within the plane along the triangle's edges, and the part inside the triangle is
// "covered": material does not pass through it. The lines of the triangle's edges are given by its
// walls (planes through each edge along the axis on which the triangle's normal is largest: the
// paper's virtual triangles). A cell that already has a facet on the triangle's plane gets that
// facet split and covered the same way (cuts along earlier cuts or along tet faces). Cells stay
// convex; a cell may have several facets on one plane. Covered facets are the paper's polygon mesh
// of the cut surface; uncovered facets between cells of one tet are where material continues.
//
// The complex is conforming across the whole mesh: a facet on a mesh face is one record shared by
// the cells of the two tets, and a point put on an edge goes into every facet around that edge
// (edges are radial records listing their facets). So two tets that share a face see the very same
// polygons on it, by construction, and the material surface has no T-junctions.
//
// Every vertex is a point of the intersection registry, and every decision is an exact side test.

#include <tetcut/tet_mesh.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <tbb/concurrent_vector.h>
#include <tbb/enumerable_thread_specific.h>

#include "registry/intersection_registry.hpp"

namespace tetcut::cells {

using registry::PlaneId;
using registry::VertexId;
using CellId = std::int32_t;
using FacetId = std::int32_t;
using EdgeId = std::int32_t;

/// What lies on one side of a facet: a cell (>= 0), the outside of the mesh, or a tet that is not
/// refined yet (its one implicit cell).
using Side = std::int32_t;
inline constexpr Side kOutside = -1;
inline constexpr Side unrefined_side(Index tet) { return -2 - tet; }
inline constexpr bool is_cell(Side s) { return s >= 0; }
inline constexpr bool is_unrefined(Side s) { return s <= -2; }
inline constexpr Index unrefined_tet(Side s) { return -2 - s; }

/// A facet corner: a vertex and the edge from it to the next corner's vertex.
struct Corner {
  VertexId vertex;
  EdgeId edge;
};

struct Edge {
  VertexId a = -1, b = -1;
  /// Two distinct planes whose intersection is the edge's line.
  std::array<PlaneId, 2> line{};
  Index mesh_edge = -1;  ///< the mesh edge it lies on, or -1
  EdgeId next_on_mesh_edge = -1;
  /// Every facet that has this edge (the radial set).
  std::vector<FacetId> facets;
};

struct Facet {
  PlaneId plane = -1;
  /// The cells on the side the plane's normal points to (front) and on the other side (back).
  Side front = kOutside, back = kOutside;
  /// Convex polygon, counter-clockwise seen from the front. Consecutive corners may be collinear.
  std::vector<Corner> corners;
  Index mesh_face = -1;  ///< the mesh face it lies on, or -1
  FacetId next_on_mesh_face = -1;
  /// The first insertion covering this facet (see CellComplex::cut_id), or -1 when uncovered
  /// (material passes through).
  std::int32_t covering = -1;
  /// Sum over the cut triangles covering it of +1 (triangle normal along the plane's) or -1: the
  /// jump of the winding number of the cut surface when crossing from back to front.
  std::int32_t winding = 0;
  /// Last insertion that covered it, so that the two cells sharing it count a triangle once.
  std::int32_t stamp = -1;

  bool covered() const { return covering >= 0; }
};

struct Cell {
  Index tet = -1;
  CellId next_in_tet = -1;
  bool material = true;
  /// The caller's label, kept by both parts when the cell is split: the cutter stores the tet copy
  /// whose material the cell is, so that a cut placed on a deformed copy goes into its cells only.
  std::int32_t label = -1;
  std::vector<FacetId> facets;
  /// A box certainly holding the cell (rounded corners widened by their error bound, rounded
  /// outward to float), or empty (min > max) until computed; split() clears both parts'.
  std::array<float, 3> box_min{1, 1, 1}, box_max{0, 0, 0};
};

/// A cut triangle in rest space, with its id in the caller's numbering.
struct CutTriangle {
  Vec3 a, b, c;
  std::int32_t id = -1;
};

/// A cut triangle ready to insert into the cells of some tets: its plane, oriented along the
/// triangle's normal, and its three walls (walls[e] through corners e and e + 1), oriented so the
/// triangle is on their positive side, all in the rest space of those tets. In a cut placed on a
/// deformed mesh they are world planes pulled back through one tet copy's motion.
struct PreparedTriangle {
  registry::OrientedPlane plane;
  std::array<registry::OrientedPlane, 3> walls;
  std::int32_t cut_id = -1;
  /// The corners, when they are input points (rest-space cuts), for cheaper tests; otherwise
  /// corner k is where the plane meets walls k and k + 2.
  bool corners_are_inputs = false;
  std::array<Vec3, 3> corners{};
};

/// Whether a triangle may cover part of the closed tet with corners x (positively oriented): the
/// tests that spare a tet without cells, exact. `plane` is the triangle's plane; `walls` its
/// walls with the sign of their inner side; corner_side(k, q) the side of plane q at corner k.
/// False only when the triangle certainly covers no area of the tet.
bool tet_may_meet_triangle(const std::array<Vec3, 4>& x, const geometry::Plane& plane,
                           const std::array<std::pair<const geometry::Plane*, int>, 3>& walls,
                           const std::function<int(int, const geometry::Plane&)>& corner_side);

class CellComplex {
 public:
  /// No tet is refined yet. `mesh` and `registry` must outlive the complex; the registry must be
  /// built on mesh.rest().
  CellComplex(const TetMesh& mesh, registry::IntersectionRegistry& registry);

  /// Registers the plane and walls of a rest-space triangle whose corners are not collinear (walls
  /// along the axis on which its normal is largest).
  PreparedTriangle prepare(const CutTriangle& triangle);

  /// Inserts a prepared triangle into the cells of `tets` labelled `label` (any cell when -1).
  /// `tets` must contain every tet whose closure meets the triangle (more only cost time). Appends
  /// to `touched` each tet whose cells, or whose facets' covering, changed, once per call. Cost:
  /// O(sum over touched cells of their size), independent of the mesh size.
  void insert_triangle(const PreparedTriangle& triangle, std::span<const Index> tets, std::int32_t label,
                       std::vector<Index>* touched);
  /// Rest space, into every cell.
  void insert_triangle(const CutTriangle& triangle, std::span<const Index> tets, std::vector<Index>* touched) {
    insert_triangle(prepare(triangle), tets, -1, touched);
  }

  /// Inserts a batch of prepared triangles into every cell (label -1), triangle `i` into the tets
  /// `tets[i]` (as for insert_triangle), using the threads of the current TBB arena. The result
  /// has the same cells and covered polygons as inserting the triangles one by one in order; only
  /// the numbering of cells, facets, edges and points, and the corner a facet starts at, differ
  /// (and do not depend on the threads' timing). Appends the touched tets to `touched`, in no
  /// particular order and possibly repeated.
  ///
  /// Why it is safe: inserting into tet A writes only records of A and of the tets sharing a node
  /// with A (facets on A's faces and their neighbours' facet lists, points on A's edges and the
  /// facets around them). Tets are grouped into cubic blocks of side 5 L (L the longest mesh edge)
  /// by their centroids, and the blocks coloured by the parity of their coordinates: two tets in
  /// different blocks of one colour have centroids more than 5 L apart along an axis, while a tet
  /// sharing a node with both would put them within 4.5 L. So the blocks of one colour run at
  /// once, each taking its own tets one at a time, with their triangles in order. A facet on a
  /// mesh face is covered by the tet on its front side alone (when that side holds material, which
  /// then always inserts the triangle too), since the two tets may insert the triangle at
  /// different times. Cost: that of the insertions, over the threads, plus O(P log P) for sorting
  /// the P pairs of triangle and tet.
  void insert_triangles(std::span<const PreparedTriangle> triangles, std::span<const std::vector<Index>> tets,
                        std::vector<Index>* touched);

  /// The caller's id of the cut triangle that first covered a facet, or -1.
  std::int32_t cut_id(const Facet& facet) const {
    return facet.covering < 0 ? -1 : inserted_[facet.covering].cut_id;
  }

  /// Labels: a refined tet's cells carry their own; an unrefined tet has one, which its first cell
  /// takes when it is refined.
  void set_cell_label(CellId cell, std::int32_t label) { cells_[cell].label = label; }
  void set_tet_label(Index tet, std::int32_t label) { tet_label_[tet] = label; }
  std::int32_t tet_label(Index tet) const { return tet_label_[tet]; }

  /// Marks an unrefined tet as holding no material (embedding); cells of refined tets are marked
  /// through set_cell_material.
  void set_tet_material(Index tet, bool material);
  void set_cell_material(CellId cell, bool material) { cells_[cell].material = material; }
  /// Whether an unrefined tet holds material.
  bool tet_material(Index tet) const { return tet_material_[tet] != 0; }
  /// Lets material pass through a covered facet again (embedding joins the overlapping insides
  /// of a self-intersecting surface); its winding jump stays.
  void uncover(FacetId facet) { facets_[facet].covering = -1; }

  bool refined(Index tet) const { return first_cell_[tet] >= 0; }
  /// First cell of a refined tet (then follow Cell::next_in_tet), or -1.
  CellId first_cell(Index tet) const { return first_cell_[tet]; }
  /// Appends the points that refined tets put strictly inside mesh edge `mesh_edge`, in order from
  /// node `from` to node `to` (its two nodes). A face of an unrefined tet is the polygon of its
  /// three nodes and these points. O(points on the edge squared).
  void mesh_edge_points(Index mesh_edge, Index from, Index to, std::vector<VertexId>* out) const;
  /// The registry plane of a mesh face (oriented by its ascending node ids), or -1 when no tet
  /// around it is refined yet.
  PlaneId face_plane_id(Index face) const { return face_plane_[face]; }
  /// Facets on a mesh face (then follow Facet::next_on_mesh_face), or -1 when none exist yet.
  FacetId first_facet_on_face(Index face) const { return face_first_facet_[face]; }

  const TetMesh& mesh() const { return *mesh_; }
  const registry::IntersectionRegistry& registry() const { return *registry_; }
  /// Read-only access to records by id, whatever container holds them (concurrent vectors, so
  /// that the parallel insertion may append from several threads while elements never move).
  template <typename Record>
  class Records {
   public:
    explicit Records(const tbb::concurrent_vector<Record>& records) : records_(&records) {}
    std::size_t size() const { return records_->size(); }
    const Record& operator[](std::size_t id) const { return (*records_)[id]; }
    auto begin() const { return records_->begin(); }
    auto end() const { return records_->end(); }

   private:
    const tbb::concurrent_vector<Record>* records_;
  };
  Records<Cell> cells() const { return Records<Cell>(cells_); }
  Records<Facet> facets() const { return Records<Facet>(facets_); }
  Records<Edge> edges() const { return Records<Edge>(edges_); }

  /// The tet on side `s` of a facet, or -1 for the outside.
  Index tet_of(Side s) const;
  /// Whether side `s` holds material (false for the outside).
  bool side_is_material(Side s) const;

  /// Volume of a cell, times 6, from rounded vertex positions relative to `origin`: the sum over
  /// its facets of signed fan volumes. Each facet's fan starts at its first corner, so a facet
  /// shared by two cells adds opposite amounts to them and the cells of a tet add up to the tet.
  double cell_volume6(CellId cell, const Vec3& origin) const;
  /// The same from exact points: what cell_volume6 falls back to for a cell whose rounded
  /// volume is within its error bound (a cell far thinner than rounding).
  double exact_cell_volume6(CellId cell) const;

  /// Checks the complex's invariants exactly and returns the first violation, or an empty string:
  /// every facet's corners lie on its plane and each edge on both planes of its line; edges and
  /// facets list each other; every cell is closed (each directed edge of its outward facets used
  /// once each way), convex (every vertex on the inner side of each facet), with positive volume;
  /// front and back agree with the cells' facet lists; no edge or point is stored twice; every
  /// covered facet lies inside the triangle that covered it. O(total size squared per cell).
  std::string validate() const;

 private:
  CellId refine(Index tet);
  PlaneId face_plane(Index face);
  VertexId node_vertex(Index node, Index tet);
  void add_face_facet(Index face, Index tet, CellId cell);
  /// Calls visit(vertex, edge) for each edge record along mesh edge `mesh_edge` from vertex `start`
  /// to vertex `target`, with the vertex it leaves from.
  template <typename Visit>
  void walk_mesh_edge(Index mesh_edge, VertexId start, VertexId target, Visit&& visit) const;
  /// Corners along mesh edge (from -> to), creating its first edge record when missing; registers
  /// `facet` on each edge record.
  void append_mesh_edge_chain(Index mesh_edge, Index from, Index to, Index tet, FacetId facet,
                              std::vector<Corner>* corners);

  // One triangle's insertion: what the functions below that take it read and write besides the
  // complex (the parallel insertion runs several at once, each with its own). Its stamp is the
  // triangle's index in inserted_.
  struct Insertion {
    std::int32_t stamp = -1;
    const PreparedTriangle* triangle = nullptr;
    std::vector<Index>* touched = nullptr;
    bool has_box = false;
    std::array<double, 3> box_min{}, box_max{};
    /// A facet on a mesh face is covered only on behalf of its front side when that side holds
    /// material (insert_triangles); otherwise by whichever side comes first, by the stamps.
    bool front_covers_faces = false;
    /// Side tests against the triangle's plane and walls, remembered for this insertion.
    registry::IntersectionRegistry::SideMemo* memo = nullptr;
  };
  /// Starts inserting `triangle` with stamp `stamp`, its side tests remembered in `memo`.
  Insertion begin_insertion(const PreparedTriangle& triangle, std::int32_t stamp, std::vector<Index>* touched,
                            bool front_covers_faces, registry::IntersectionRegistry::SideMemo* memo) const;

  /// Whether an unrefined tet's closed volume can be changed by the triangle (same tests as
  /// process_cell, on the four corners).
  bool tet_may_be_cut(const Insertion& in, Index tet) const;
  /// Side of `plane` at corner k of the triangle being inserted.
  int corner_side(const Insertion& in, int k, PlaneId plane) const;
  /// Splits and covers inside one cell; returns whether anything changed.
  bool process_cell(Insertion& in, CellId cell);
  /// Inserts the triangle into the cells of one tet labelled `label` (any when -1), refining the
  /// tet first when the triangle may cut it. `scratch` is reused storage.
  void insert_into_tet(Insertion& in, Index tet, std::int32_t label, std::vector<CellId>* scratch);

  /// -1, 0 or +1 when every vertex of the cell is <= 0, some are on each side, or all are >= 0
  /// (2 when all are on the plane, impossible for a cell with volume). `memo` may be null.
  int classify(CellId cell, PlaneId plane, registry::IntersectionRegistry::SideMemo* memo) const;
  /// Whether every corner of the facet lies on the plane.
  bool facet_on_plane(FacetId facet, PlaneId plane, registry::IntersectionRegistry::SideMemo* memo) const;
  /// classify() for one facet.
  int classify_facet(FacetId facet, PlaneId plane, registry::IntersectionRegistry::SideMemo* memo) const;
  /// Whether the cell's section by the triangle's plane overlaps the triangle with positive area
  /// (exact separating-axis test in that plane). The cell must cross the plane.
  bool section_overlaps_triangle(const Insertion& in, CellId cell) const;
  /// Covers the part of facet `f` (on the triangle's plane) inside the triangle, splitting the
  /// facet along the triangle's edges within its plane, on behalf of `cell` (one of its sides).
  /// Returns whether anything changed.
  bool cover_inside(Insertion& in, FacetId f, CellId cell);

  /// Splits `cell` by `plane` when the plane passes through its interior. The part on the positive
  /// side keeps the id `cell`; returns the id of the negative part, or -1 when nothing was split.
  /// The new facet on the plane is returned through `section`. Reports the tets it changes as
  /// touched by the insertion `in`.
  CellId split(Insertion& in, CellId cell, PlaneId plane, FacetId* section);
  /// Splits facet f, whose corners are all on `plane` or on one side of it except that both sides
  /// occur, into its positive part (kept as f) and its negative part (returned). In a split of
  /// `cell`, the negative part belongs to `negative_cell` on that side; with cell = -1 the facet is
  /// split within its plane and both parts keep both cells.
  FacetId split_facet(Insertion& in, FacetId f, PlaneId plane, CellId cell, CellId negative_cell);
  /// Puts a vertex where `plane` crosses an edge of facet f (strictly), in every facet around it.
  void mark_crossings(Insertion& in, FacetId f, PlaneId plane);
  /// Splits a facet by a line in its plane (its intersection with `plane`), after putting the
  /// crossing points on its edges; returns the negative part.
  FacetId split_facet_in_plane(Insertion& in, FacetId f, PlaneId plane);
  /// Inserts vertex w, which lies strictly inside edge e, into every facet around e.
  void insert_on_edge(Insertion& in, EdgeId e, VertexId w);
  EdgeId add_edge(VertexId a, VertexId b, std::array<PlaneId, 2> line, Index mesh_edge);
  void cover(Insertion& in, FacetId facet);
  /// Reports a tet (or the tet on a side) as touched by the insertion, once per insertion.
  void touch_side(const Insertion& in, Side s);
  void touch(const Insertion& in, Index tet);

  const TetMesh* mesh_;
  registry::IntersectionRegistry* registry_;
  tbb::concurrent_vector<Cell> cells_;
  tbb::concurrent_vector<Facet> facets_;
  tbb::concurrent_vector<Edge> edges_;
  std::vector<CellId> first_cell_;         // per tet
  std::vector<std::uint8_t> tet_material_; // per tet, for unrefined tets
  std::vector<FacetId> face_first_facet_;  // per mesh face
  std::vector<PlaneId> face_plane_;        // per mesh face, -1 until needed
  std::vector<EdgeId> mesh_edge_first_;    // per mesh edge
  std::vector<VertexId> node_vertex_;      // per mesh node, -1 until needed
  std::vector<std::int32_t> tet_label_;    // per tet, for unrefined tets
  double longest_edge_ = -1;               // of the mesh, once insert_triangles needs it

  /// Whether the cell certainly misses the box of the triangle being inserted (rest-space
  /// triangles, whose corners are inputs): a sound filter before the exact tests, as the cell's box
  /// holds its exact corners. Most cells of a tet crossed by many small triangles (an embedded
  /// scan) are far from each one.
  bool cell_misses_triangle_box(const Insertion& in, CellId cell);

  // Side-test memos for insertions: one per thread that inserts (the sequential insertion and each
  // task of the parallel one take their thread's), kept between insertions so that their per-vertex
  // tables are allocated once.
  tbb::enumerable_thread_specific<registry::IntersectionRegistry::SideMemo> side_memos_;
  // Every insertion's plane, walls and cut id: facets name the insertion that covered them, and
  // validate() checks they lie inside its triangle.
  struct InsertedTriangle {
    registry::OrientedPlane plane;
    std::array<registry::OrientedPlane, 3> walls;
    std::int32_t cut_id;
  };
  std::vector<InsertedTriangle> inserted_;
  std::vector<std::int32_t> tet_touch_stamp_;  // per tet: last insertion that reported it
};

}  // namespace tetcut::cells
