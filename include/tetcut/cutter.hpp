#pragma once
// Cutting a tet mesh by triangle soups (Sifakis, Der, Fedkiw 2007, made exact).
//
//   tetcut::Cutter cutter(mesh);
//   cutter.cut(soup);                      // any number of batches, in rest space
//   cutter.cut_deformed(blade, positions); // or in world space, on the deformed cut mesh
//   const tetcut::CutResult r = cutter.result();
//   r.mesh.mesh          // the simulation mesh: one copy of a tet per material component
//   r.surface.surface    // the material surface, embedded in the copies
//
// Cut triangles may intersect each other and the mesh in any way: through nodes, along edges and
// faces, coplanar and overlapping, partly inside a tet, closed inside one tet. Every topological
// decision is an exact predicate; coordinates are rounded for output only. Zero-area triangles
// are skipped and reported.

#include <tetcut/surface.hpp>
#include <tetcut/tet_mesh.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace tetcut {

/// The simulation mesh after cutting. Each material component of an input tet has its own copy
/// of the tet, with the tet's rest positions, so no element is smaller or worse shaped than an
/// input element. Copies whose shared face holds common material share that face's nodes.
struct CutMesh {
  /// Nodes and tet copies. For a Cutter made from a mesh, input node n keeps id n and duplicated
  /// nodes follow; each input tet's first copy comes first, in input order (so tet t's first copy
  /// is t), and further copies follow. For an embedding, ids start dense over the kept material
  /// (see node_parent and tet_parent); copies made by later cuts follow.
  TetMesh mesh;
  std::vector<Index> node_parent;           ///< per node: the input node it copies
  std::vector<Index> tet_parent;            ///< per copy: the input tet it copies
  std::vector<Index> tet_piece;             ///< per copy: its piece (pieces by volume, largest first)
  std::vector<double> tet_material_volume;  ///< per copy: volume of the material it holds
  std::vector<double> piece_volumes;        ///< per piece, largest first

  Index num_pieces() const { return static_cast<Index>(piece_volumes.size()); }
  /// Per copy: the fraction of its tet's volume that is material (tet_material_volume over the
  /// copy's rest volume), what a simulator scales the copy's mass and stiffness by. O(copies).
  std::vector<double> material_fractions() const;
};

/// The boundary of the material: both sides of every cut and the uncut outer boundary, as
/// triangles oriented outward. Each vertex is embedded in one tet copy by barycentric weights, so
/// it follows the simulation mesh as it deforms.
struct MaterialSurface {
  TriangleSurface surface;  ///< rest positions
  /// Per vertex: the tet copy (a CutMesh tet id) it is embedded in, and its barycentric weights
  /// (|V| x 4, summing to one) with respect to that copy's four nodes.
  std::vector<Index> vertex_tet;
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> vertex_weights;
  /// Per triangle: the cut triangle it lies on (numbered over all batches, in order), or -1 - f
  /// for input mesh face f (TetAdjacency numbering) on the outer boundary.
  std::vector<std::int64_t> triangle_source;
  /// Per triangle: the tet copy whose material it bounds.
  std::vector<Index> triangle_tet;

  /// Vertex positions for the given positions of the cut mesh's nodes (|V'| x 3), e.g. deformed.
  Points positions(const CutMesh& mesh, const Points& nodes) const;
  /// The same with the copies' nodes given as Cutter::tet_nodes gives them.
  Points positions(std::span<const std::array<Index, 4>> copy_nodes, const Points& nodes) const;
};

struct CutResult {
  CutMesh mesh;
  MaterialSurface surface;
  /// Seconds spent building each: components, copies and joins; then the surface.
  double seconds_mesh = 0;
  double seconds_surface = 0;
};

/// What one batch did, and what a simulator needs to carry its state over.
struct CutBatchReport {
  Index triangles = 0;                     ///< triangles in the batch
  std::vector<Index> degenerate;           ///< zero-area triangles (collinear corners), skipped
  Index tets_touched = 0;                  ///< input tets whose material changed
  std::vector<Index> touched;              ///< those tets, in increasing order
  /// World-space cuts: tet copies that the batch would have cut but whose current corners are
  /// inverted or flat, so the cut was not applied there (their material is not cut by this batch).
  std::vector<Index> skipped_inverted;

  /// Nodes from first_new_node on are new; node first_new_node + i was split from node
  /// new_node_source[i] (an id from before the batch): give it that node's position and velocity.
  Index first_new_node = 0;
  std::vector<Index> new_node_source;
  /// Tet copies from first_new_tet on are new, split from copy new_tet_source[i] (same input tet).
  Index first_new_tet = 0;
  std::vector<Index> new_tet_source;
  /// Copies that existed before the batch and whose nodes changed, ascending. All other ids
  /// (nodes and copies) keep their meaning.
  std::vector<Index> changed_tets;
};

/// The cut state of one mesh: the intersection registry, the cell complex, and the tet copies
/// and nodes of the cut mesh. Batches of triangles accumulate; each changes only the tets it
/// touches, and node and tet ids, once given, stay.
class Cutter {
 public:
  /// Takes the mesh to cut. Each tet starts as its own copy over the input nodes. O(T log T).
  explicit Cutter(TetMesh mesh);
  ~Cutter();
  Cutter(Cutter&&) noexcept;
  Cutter& operator=(Cutter&&) noexcept;

  /// Cuts by a batch of triangles given in rest positions. Throws Error(kInvalidInput) naming the
  /// triangle when a coordinate is not finite (nothing is changed then). Cost: proportional to the
  /// tets the batch touches and their cells, plus O(log T) per triangle.
  CutBatchReport cut(const TriangleSurface& batch);

  /// Sets the current (deformed) positions of the cut mesh's nodes: num_nodes() x 3. Throws
  /// Error(kInvalidInput) on a wrong size or a non-finite entry. Refits the bounding boxes of the
  /// copies in their current shapes: O(copies), in parallel. Nodes that later batches add start
  /// at the position of the node they were split from.
  void set_current(const Points& nodes);
  /// The current positions (the input's, until set_current).
  Points current() const;

  /// Cuts by a batch of triangles given in world space, on the cut mesh in its current positions
  /// (set_current). Each tet copy that a triangle touches in its current shape takes its own copy
  /// of the triangle, pulled back through its motion into rest space, and only that copy's
  /// material is cut; copies sharing a face and its nodes agree on it exactly. Copies inverted or
  /// flat in their current positions are skipped and reported. Cost: as cut().
  CutBatchReport cut_deformed(const TriangleSurface& batch);
  /// set_current(nodes), then cut_deformed(batch).
  CutBatchReport cut_deformed(const TriangleSurface& batch, const Points& nodes);

  /// Maps points given in world space, on the mesh in its current positions, to rest space: each
  /// through the motion of a tet copy whose current shape holds it (the one it is deepest in), or,
  /// outside every copy, of the copy nearest to it, extended. Copies inverted or flat in their
  /// current positions are not used. Geometry, not topology: the result is rounded. Use it to
  /// follow a blade in the material as the mesh moves (see swept_blade). |P| x 3 in, |P| x 3 out;
  /// O(log copies) per point for points inside the mesh.
  Points to_rest(const Points& world) const;

  /// The cut mesh as it stands: node and tet counts, each copy's nodes (in its input tet's order),
  /// and where each node and copy came from. O(1).
  Index num_nodes() const;
  Index num_tets() const;
  const std::vector<std::array<Index, 4>>& tet_nodes() const;
  const std::vector<Index>& node_parent() const;
  const std::vector<Index>& tet_parent() const;
  /// The copies of input tet `tet` (empty when it holds no material), valid until the next batch.
  std::span<const Index> copies_of(Index tet) const;
  /// The fraction of its tet's volume that copy `copy` holds as material, as
  /// CutMesh::material_fractions gives it (the same bits). O(cells of its tet): after a batch, a
  /// simulator asks only for the copies of the tets the batch touched.
  double material_fraction(Index copy) const;

  /// The material surface as it stands. The surface is kept in patches, one per input tet; a
  /// batch marks the patches of the tets it touched and of their neighbours, and only those are
  /// rebuilt here, so after a batch this costs O(the batch's tets + surface size), the latter a
  /// plain numbering pass. The result is the same as building it at once. Not const: it updates
  /// the patches.
  MaterialSurface surface();

  /// The simulation mesh, pieces and material surface for all batches so far, with the current
  /// positions. O(T log T + refined cells) for the mesh; the surface as surface().
  CutResult result();

  const TetMesh& input() const;
  /// Cut triangles inserted so far (degenerate ones included in the numbering).
  std::int64_t num_cut_triangles() const;

 private:
  // The library's later stages (the embedding) reach the state through CutterAccess, an internal
  // class (src/cutter/cutter_state.hpp), so that this header names none of them.
  friend struct CutterAccess;
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tetcut
