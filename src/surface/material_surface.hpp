#pragma once
// The material surface (paper, section 4): the polygons incident on material on exactly one side
// — both sides of every covered facet, and facets between material and the outside or void —
// triangulated and oriented outward, each vertex embedded in the tet copy whose material it bounds.
//
// The complex is conforming, so the surface needs no T-junction repair: surface vertices are the
// complex's points, keyed by the point and by the copy's nodes that carry weight there. Two
// polygons share a vertex exactly when the vertex moves identically in both (same point, same
// nodes with non-zero weights), which keeps the surface closed and consistently oriented.

#include <tetcut/cutter.hpp>

#include <memory>
#include <span>
#include <vector>

#include "cells/cell_complex.hpp"
#include "connectivity/tet_copies.hpp"

namespace tetcut::surface {

/// The material surface kept as one patch per input tet: the polygons bounding the material of
/// that tet's copies, with their corners keyed but not yet numbered. A batch of cuts changes the
/// patches of the tets it touched and of their neighbours only, so after a batch only those are
/// rebuilt (the costly part: exact strictness and zero-weight tests, triangulation), and the
/// surface is assembled from all patches by numbering their corners.
class SurfacePatches {
 public:
  /// Every patch starts out of date. `mesh` must outlive this.
  explicit SurfacePatches(const TetMesh& mesh);
  ~SurfacePatches();
  SurfacePatches(SurfacePatches&&) noexcept;
  SurfacePatches& operator=(SurfacePatches&&) noexcept;

  /// Marks out of date the patches that a change to these tets' cells can change: theirs, and
  /// those of every tet sharing an edge with one of them (facets on shared faces, points put on
  /// shared edges). O(tets x tets around their nodes).
  void mark_around(std::span<const Index> tets);
  /// Marks out of date the patches of these tets only (their copies' nodes changed).
  void mark(std::span<const Index> tets);

  /// Rebuilds the out-of-date patches (in parallel) and assembles the surface. Vertices are
  /// numbered in order of first use over the patches in tet order, so the result depends only
  /// on the complex and copies, not on which patches were rebuilt when. O(rebuilt patches' cells
  /// + surface size).
  MaterialSurface assemble(const cells::CellComplex& complex, const connectivity::TetCopies& copies);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// The whole surface at once (every patch built).
MaterialSurface extract_material_surface(const cells::CellComplex& complex, const connectivity::TetCopies& copies);

/// Triangulates a convex polygon whose consecutive corners may be collinear, with no zero-area
/// triangle: ear clipping at strict corners (where the boundary turns). `strict[i]` says whether
/// corner i is one. Emits corner index triples in the polygon's orientation, or reversed.
void triangulate_convex_polygon(std::vector<std::uint8_t> strict, bool reverse, std::vector<std::array<int, 3>>* triangles);

/// The same for a facet, deciding its strict corners exactly through the lines of its edges.
void triangulate_facet(const cells::CellComplex& complex, const cells::Facet& facet, bool reverse,
                       std::vector<std::array<int, 3>>* triangles);

}  // namespace tetcut::surface
