#pragma once
// Embedding (paper, section 5 and Figure 10): carve a detailed surface out of a coarse tet mesh.
//
//   tetcut::TriangleSurface scan = tetcut::read_surface("face.off");
//   tetcut::TetMesh lattice = tetcut::embedding_lattice(scan, spacing);
//   tetcut::Cutter cutter = tetcut::embed(std::move(lattice), scan, {});
//   cutter.cut(incision);                  // keep cutting the embedded model
//
// The surface cuts the mesh like any other cut; then only the material is kept. Each tet copy
// holds one connected part of the material inside its tet, so a tet that holds two disjoint
// parts (an upper and a lower lip within one tet) is duplicated and the parts move apart freely.
// Tets without material are dropped. The material surface of the result is the input surface,
// split where it crosses tet faces, plus, for an open surface, the boundary of the kept block.

#include <tetcut/cutter.hpp>
#include <tetcut/generators.hpp>
#include <tetcut/quality.hpp>  // check_surface, which embed() runs first

#include <optional>
#include <string>
#include <string_view>

namespace tetcut {

/// Which material an embedding keeps.
enum class KeepMaterial {
  kInside,   ///< where the winding number of the (balanced) surface is not zero
  kLargest,  ///< the piece of largest volume after cutting the mesh by the surface
  kPoint,    ///< the piece holding EmbedOptions::point
};

/// The name scenes, the CLI and Python give each choice: "inside", "largest", "point".
std::string_view keep_material_name(KeepMaterial keep);
/// The choice keep_material_name calls `name`; nothing for any other word.
std::optional<KeepMaterial> keep_material_from_name(std::string_view name);

struct EmbedOptions {
  KeepMaterial keep = KeepMaterial::kInside;
  Vec3 point = Vec3::Zero();  ///< for kPoint; must not lie on the surface
};

/// What an embedding did, with the time of each stage.
struct EmbedReport {
  SurfaceCheck check;
  Index tets_in = 0;
  Index tets_with_material = 0;   ///< input tets that hold material
  Index tets_duplicated = 0;      ///< of those, tets holding several disjoint parts
  Index covered_facets_joined = 0;  ///< cut polygons with material on both sides, removed (kInside)
  double seconds_check = 0, seconds_insert = 0, seconds_classify = 0, seconds_copies = 0;
};

/// Embeds `surface` in `mesh`: cuts the mesh by it and keeps the chosen material. For kInside
/// the surface must be balanced (Error(kInvalidInput) with the number of unbalanced edges otherwise);
/// material is where its winding number is not zero, decided exactly, so a self-intersecting
/// surface gives the union of what it encloses, and a polygon where two surface parts lie face to
/// face with opposite orientation stays a cut. Surface parts outside the mesh are ignored. Throws
/// Error(kInvalidInput) when no material is left, or when kPoint's point is outside the mesh or on
/// the surface. The returned cutter can be cut further; its node ids are dense over the kept
/// copies, so node n need not be input node n (see Cutter::node_parent).
Cutter embed(TetMesh mesh, const TriangleSurface& surface, const EmbedOptions& options = {},
             EmbedReport* report = nullptr);

/// A BCC lattice (make_bcc) of cube size `spacing` covering the surface's bounding box with a
/// margin of one cube on every side, so that every tet touching the boundary of the lattice is
/// free of the surface.
TetMesh embedding_lattice(const TriangleSurface& surface, double spacing);
/// The spacing that puts `cubes` BCC cubes along the longest side of the surface's bounding box.
double spacing_for_cubes(const TriangleSurface& surface, Index cubes);

}  // namespace tetcut
