#include "support/cut_invariants.hpp"

#include <tetcut/quality.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace tetcut::testing {
namespace {

double input_volume(const TetMesh& mesh) {
  double v = 0;
  const Points& p = mesh.rest();
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    v += signed_volume(p.row(mesh.tets()(t, 0)), p.row(mesh.tets()(t, 1)), p.row(mesh.tets()(t, 2)),
                       p.row(mesh.tets()(t, 3)));
  }
  return v;
}

bool close(double a, double b, double relative, double scale) { return std::abs(a - b) <= relative * scale; }

std::string describe(const std::string& what, double a, double b) {
  std::ostringstream s;
  s.precision(17);
  s << what << ": " << a << " vs " << b;
  return s.str();
}

}  // namespace

TriangleSurface soup(const std::vector<Triangle>& triangles) {
  TriangleSurface s;
  s.vertices.resize(static_cast<Index>(3 * triangles.size()), 3);
  s.triangles.resize(static_cast<Index>(triangles.size()), 3);
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      s.vertices.row(static_cast<Index>(3 * i + k)) = triangles[i][k].transpose();
      s.triangles(static_cast<Index>(i), k) = static_cast<Index>(3 * i + k);
    }
  }
  return s;
}

std::string check_cut_invariants(const TetMesh& input, const CutResult& result) {
  return check_cut_invariants(input, result, input_volume(input));
}

std::string check_cut_invariants(const TetMesh& input, const CutResult& result, double volume) {
  const CutMesh& cut = result.mesh;
  const Index copies = cut.mesh.num_tets();
  if (static_cast<Index>(cut.tet_parent.size()) != copies || static_cast<Index>(cut.tet_piece.size()) != copies ||
      static_cast<Index>(cut.tet_material_volume.size()) != copies ||
      static_cast<Index>(cut.node_parent.size()) != cut.mesh.num_nodes()) {
    return "per-copy or per-node arrays have the wrong size";
  }
  double copy_sum = 0;
  for (Index c = 0; c < copies; ++c) {
    if (!(cut.tet_material_volume[c] > 0)) return "copy " + std::to_string(c) + " holds no material";
    copy_sum += cut.tet_material_volume[c];
    for (int k = 0; k < 4; ++k) {
      if (cut.node_parent[cut.mesh.tets()(c, k)] != input.tets()(cut.tet_parent[c], k)) {
        return "copy " + std::to_string(c) + " has a node that copies the wrong input node";
      }
    }
    if (cut.mesh.rest().row(cut.mesh.tets()(c, 0)) != input.rest().row(input.tets()(cut.tet_parent[c], 0))) {
      return "copy " + std::to_string(c) + " moved in rest space";
    }
  }
  const double piece_sum = std::accumulate(cut.piece_volumes.begin(), cut.piece_volumes.end(), 0.0);
  if (!close(piece_sum, volume, 1e-12, volume)) return describe("piece volumes do not add up to the material volume", piece_sum, volume);
  if (!close(copy_sum, volume, 1e-12, volume)) return describe("copy volumes do not add up to the material volume", copy_sum, volume);
  if (!std::is_sorted(cut.piece_volumes.rbegin(), cut.piece_volumes.rend())) return "pieces are not ordered largest first";

  // Pieces against the output mesh: copies sharing a face (the same three nodes) are one piece,
  // and each piece is connected through shared faces.
  {
    const TetAdjacency& adj = cut.mesh.adjacency();
    std::vector<Index> parent(static_cast<std::size_t>(copies));
    std::iota(parent.begin(), parent.end(), Index{0});
    const auto find = [&](Index x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (Index f = 0; f < adj.num_faces(); ++f) {
      const auto around = adj.tets_of_face(f);
      for (std::size_t i = 1; i < around.size(); ++i) {
        if (cut.tet_piece[around[i]] != cut.tet_piece[around[0]]) return "copies sharing a face are in different pieces";
        parent[find(around[i])] = find(around[0]);
      }
    }
    std::vector<Index> root_of_piece(static_cast<std::size_t>(cut.num_pieces()), -1);
    for (Index c = 0; c < copies; ++c) {
      Index& root = root_of_piece[cut.tet_piece[c]];
      if (root < 0) root = find(c);
      if (root != find(c)) return "a piece is not connected through shared faces";
    }
    std::vector<double> by_piece(static_cast<std::size_t>(cut.num_pieces()), 0.0);
    for (Index c = 0; c < copies; ++c) by_piece[cut.tet_piece[c]] += cut.tet_material_volume[c];
    for (Index p = 0; p < cut.num_pieces(); ++p) {
      if (!close(by_piece[p], cut.piece_volumes[p], 1e-12, volume)) return describe("piece volume", by_piece[p], cut.piece_volumes[p]);
    }
  }

  // The material surface.
  const MaterialSurface& s = result.surface;
  const SurfaceStats stats = measure_surface(s.surface);
  if (!stats.balanced) {
    return "the material surface is not balanced: " + std::to_string(stats.num_unbalanced_edges) + " unbalanced edges";
  }
  if (!close(stats.enclosed_volume, volume, 1e-12, volume)) {
    return describe("the material surface does not enclose the material volume", stats.enclosed_volume, volume);
  }
  const Points embedded = s.positions(cut, cut.mesh.rest());
  double scale = 0;
  for (Index v = 0; v < s.surface.num_vertices(); ++v) scale = std::max(scale, s.surface.vertices.row(v).cwiseAbs().maxCoeff());
  for (Index v = 0; v < s.surface.num_vertices(); ++v) {
    if ((embedded.row(v) - s.surface.vertices.row(v)).cwiseAbs().maxCoeff() > 1e-12 * std::max(scale, 1.0)) {
      return "surface vertex " + std::to_string(v) + " is not where its embedding puts it";
    }
    if (s.vertex_weights.row(v).minCoeff() < -1e-12 || std::abs(s.vertex_weights.row(v).sum() - 1) > 1e-12) {
      return "surface vertex " + std::to_string(v) + " has weights outside its tet";
    }
  }
  for (Index t = 0; t < s.surface.num_triangles(); ++t) {
    const Index copy = s.triangle_tet[t];
    for (int k = 0; k < 3; ++k) {
      if (cut.tet_piece[s.vertex_tet[s.surface.triangles(t, k)]] != cut.tet_piece[copy]) {
        return "surface triangle " + std::to_string(t) + " has a vertex embedded in another piece";
      }
    }
  }
  return {};
}

}  // namespace tetcut::testing
