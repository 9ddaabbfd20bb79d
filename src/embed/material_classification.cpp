#include "embed/material_classification.hpp"

#include <tetcut/error.hpp>

#include <limits>

#include "geometry/predicates.hpp"

namespace tetcut::embedding {
namespace {

using cells::CellComplex;
using cells::CellId;
using cells::Facet;
using cells::FacetId;
using cells::Side;

constexpr std::int32_t kUnknown = std::numeric_limits<std::int32_t>::min();

[[noreturn]] void not_closed_inside_mesh() {
  throw Error(ErrorKind::kInvalidInput,
              "the surface does not enclose a well-defined inside within the mesh: it leaves through the mesh "
              "boundary (use a mesh that contains the whole surface), or keep the largest piece or the piece at "
              "a point instead");
}

}  // namespace

Windings winding_numbers(const CellComplex& complex) {
  const TetMesh& mesh = complex.mesh();
  const TetAdjacency& adjacency = mesh.adjacency();
  const auto& cells = complex.cells();
  const auto& facets = complex.facets();
  Windings w;
  w.cell.assign(cells.size(), kUnknown);
  w.tet.assign(static_cast<std::size_t>(mesh.num_tets()), kUnknown);
  std::vector<Side> stack;
  const auto value = [&](Side s) -> std::int32_t& {
    return cells::is_cell(s) ? w.cell[s] : w.tet[cells::unrefined_tet(s)];
  };
  // Gives side s the winding `winding`, reached from a side whose winding is known.
  const auto reach = [&](Side s, std::int32_t winding) {
    if (s == cells::kOutside) {
      if (winding != 0) not_closed_inside_mesh();
      return;
    }
    std::int32_t& known = value(s);
    if (known == kUnknown) {
      known = winding;
      stack.push_back(s);
    } else if (known != winding) {
      not_closed_inside_mesh();
    }
  };
  // Crossing facet f from side `from` to its other side: the winding drops by the facet's jump
  // when going from back to front (a triangle's normal points out of what it encloses).
  const auto cross = [&](const Facet& f, Side from, std::int32_t winding) {
    if (f.front == from) {
      reach(f.back, winding + f.winding);
    } else {
      reach(f.front, winding - f.winding);
    }
  };
  // Seeds: zero outside the mesh, carried through the boundary faces.
  for (Index face = 0; face < adjacency.num_faces(); ++face) {
    if (adjacency.tets_of_face(face).size() != 1) continue;
    if (complex.first_facet_on_face(face) < 0) {
      reach(cells::unrefined_side(adjacency.tets_of_face(face)[0]), 0);
      continue;
    }
    for (FacetId f = complex.first_facet_on_face(face); f >= 0; f = facets[f].next_on_mesh_face) {
      cross(facets[f], cells::kOutside, 0);
    }
  }
  while (!stack.empty()) {
    const Side s = stack.back();
    stack.pop_back();
    const std::int32_t winding = value(s);
    if (cells::is_cell(s)) {
      for (const FacetId f : cells[s].facets) cross(facets[f], s, winding);
      continue;
    }
    const Index tet = cells::unrefined_tet(s);
    for (int k = 0; k < 4; ++k) {
      const Index face = adjacency.tet_faces(tet, k);
      if (complex.first_facet_on_face(face) >= 0) {
        for (FacetId f = complex.first_facet_on_face(face); f >= 0; f = facets[f].next_on_mesh_face) {
          cross(facets[f], s, winding);
        }
        continue;
      }
      // No facet on the face: the tet across it is unrefined too, and nothing covers the face.
      const auto around = adjacency.tets_of_face(face);
      if (around.size() == 1) {
        reach(cells::kOutside, winding);
      } else {
        reach(cells::unrefined_side(around[0] == tet ? around[1] : around[0]), winding);
      }
    }
  }
  // Sides cut off from the boundary cannot exist in a mesh whose every tet has faces; keep zero.
  for (auto& x : w.cell) x = x == kUnknown ? 0 : x;
  for (auto& x : w.tet) x = x == kUnknown ? 0 : x;
  return w;
}

Index keep_nonzero_winding(CellComplex& complex, const Windings& windings) {
  Index kept = 0;
  for (Index t = 0; t < complex.mesh().num_tets(); ++t) {
    bool any = false;
    if (!complex.refined(t)) {
      any = windings.tet[t] != 0;
      complex.set_tet_material(t, any);
    } else {
      for (CellId c = complex.first_cell(t); c >= 0; c = complex.cells()[c].next_in_tet) {
        const bool material = windings.cell[c] != 0;
        complex.set_cell_material(c, material);
        any = any || material;
      }
    }
    kept += any ? 1 : 0;
  }
  return kept;
}

Index join_overlaps(CellComplex& complex) {
  Index joined = 0;
  const auto& facets = complex.facets();
  for (FacetId f = 0; f < static_cast<FacetId>(facets.size()); ++f) {
    const Facet& facet = facets[f];
    if (!facet.covered() || facet.winding == 0) continue;
    if (!complex.side_is_material(facet.front) || !complex.side_is_material(facet.back)) continue;
    complex.uncover(f);
    ++joined;
  }
  return joined;
}

Side side_holding(const CellComplex& complex, std::span<const Index> tets, const Vec3& x) {
  // Every tet and cell whose closure holds x is looked at: x on a covered facet of any of them
  // (a tet touching x only at a node or edge may be unrefined while its neighbours are cut there).
  const TetMesh& mesh = complex.mesh();
  const registry::IntersectionRegistry& registry = complex.registry();
  Side found = cells::kOutside;
  for (const Index t : tets) {
    std::array<Vec3, 4> corner;
    for (int k = 0; k < 4; ++k) corner[k] = mesh.rest().row(mesh.tets()(t, k)).transpose();
    bool inside = true;
    for (int k = 0; k < 4 && inside; ++k) {
      std::array<Vec3, 4> with_x = corner;
      with_x[k] = x;  // positive or zero exactly when x is on the inner side of the face opposite k
      inside = geometry::orient3d(with_x[0], with_x[1], with_x[2], with_x[3]) >= 0;
    }
    if (!inside) continue;
    if (!complex.refined(t)) {
      if (found == cells::kOutside) found = cells::unrefined_side(t);
      continue;
    }
    for (CellId c = complex.first_cell(t); c >= 0; c = complex.cells()[c].next_in_tet) {
      bool in_cell = true, on_cut = false;
      for (const FacetId f : complex.cells()[c].facets) {
        const Facet& facet = complex.facets()[f];
        const int side = registry.side_of_input(facet.plane, x) * (facet.front == c ? 1 : -1);
        if (side < 0) {
          in_cell = false;
          break;
        }
        on_cut = on_cut || (side == 0 && facet.covered());
      }
      if (!in_cell) continue;
      if (on_cut) {
        throw Error(ErrorKind::kInvalidInput, "the point chosen to keep material lies on the cut surface: move it off");
      }
      if (found == cells::kOutside || !cells::is_cell(found)) found = c;
    }
  }
  if (found == cells::kOutside) throw Error(ErrorKind::kInvalidInput, "the point chosen to keep material lies outside the mesh");
  return found;
}

}  // namespace tetcut::embedding
