#include "support/planar_invariants.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace tetcut::testing {

Polyline polyline(std::initializer_list<std::array<double, 2>> points, bool closed) {
  Polyline l;
  l.points.resize(static_cast<Index>(points.size()), 2);
  Index i = 0;
  for (const auto& p : points) l.points.row(i++) << p[0], p[1];
  l.closed = closed;
  return l;
}

double planar_area(const PlanarMesh& mesh) {
  double area = 0;
  for (Index t = 0; t < mesh.num_triangles(); ++t) {
    const Eigen::Vector2d a = mesh.rest.row(mesh.triangles(t, 0)), b = mesh.rest.row(mesh.triangles(t, 1)),
                          c = mesh.rest.row(mesh.triangles(t, 2));
    area += 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
  }
  return area;
}

std::vector<double> sorted_areas(const PlanarCutResult& r) {
  std::vector<double> areas = r.mesh.piece_areas;
  std::sort(areas.begin(), areas.end());
  return areas;
}

void expect_planar_invariants(const PlanarMesh& input, const PlanarCutResult& r) {
  const PlanarCutMesh& m = r.mesh;
  const Index copies = m.mesh.num_triangles();
  ASSERT_EQ(static_cast<Index>(m.triangle_material_area.size()), copies);
  std::vector<double> piece_sum(m.num_pieces(), 0);
  for (Index c = 0; c < copies; ++c) {
    EXPECT_GT(m.triangle_material_area[c], 0) << "copy " << c << " holds no material";
    piece_sum[m.triangle_piece[c]] += m.triangle_material_area[c];
  }
  const double total = planar_area(input);
  double sum = 0;
  for (Index p = 0; p < m.num_pieces(); ++p) {
    EXPECT_NEAR(piece_sum[p], m.piece_areas[p], 1e-12 * total);
    sum += m.piece_areas[p];
    if (p > 0) {
      EXPECT_GE(m.piece_areas[p - 1], m.piece_areas[p]);
    }
  }
  EXPECT_NEAR(sum, total, 1e-12 * total);

  const PlanarMaterial& b = r.material;
  std::vector<int> balance(b.num_vertices(), 0);
  std::vector<double> shoelace(m.num_pieces(), 0);
  for (Index s = 0; s < b.num_segments(); ++s) {
    const Index u = b.segments(s, 0), v = b.segments(s, 1);
    ++balance[u];
    --balance[v];
    const Eigen::Vector2d p = b.rest.row(u), q = b.rest.row(v);
    shoelace[m.triangle_piece[b.segment_copy[s]]] += 0.5 * (p.x() * q.y() - p.y() * q.x());
  }
  for (Index v = 0; v < b.num_vertices(); ++v) EXPECT_EQ(balance[v], 0) << "boundary vertex " << v << " is an end";
  for (Index p = 0; p < m.num_pieces(); ++p) EXPECT_NEAR(shoelace[p], m.piece_areas[p], 1e-12 * total) << "piece " << p;
  // The material triangles cover each piece, counter-clockwise.
  std::vector<double> covered(m.num_pieces(), 0);
  for (Index t = 0; t < b.num_triangles(); ++t) {
    const Eigen::Vector2d p = b.rest.row(b.triangles(t, 0)), q = b.rest.row(b.triangles(t, 1)), w = b.rest.row(b.triangles(t, 2));
    const double area = 0.5 * ((q - p).x() * (w - p).y() - (q - p).y() * (w - p).x());
    EXPECT_GE(area, -1e-15 * total) << "material triangle " << t;
    covered[m.triangle_piece[b.triangle_copy[t]]] += area;
  }
  for (Index p = 0; p < m.num_pieces(); ++p) EXPECT_NEAR(covered[p], m.piece_areas[p], 1e-12 * total) << "piece " << p;
  // Embedded vertices sit where the copies' rest corners put them.
  const Points rest3 = [&] {
    Points x(m.mesh.num_nodes(), 3);
    for (Index n = 0; n < m.mesh.num_nodes(); ++n) x.row(n) << m.mesh.rest(n, 0), m.mesh.rest(n, 1), 0;
    return x;
  }();
  const Points embedded = b.positions(m, rest3);
  for (Index v = 0; v < b.num_vertices(); ++v) {
    EXPECT_NEAR(embedded(v, 0), b.rest(v, 0), 1e-12);
    EXPECT_NEAR(embedded(v, 1), b.rest(v, 1), 1e-12);
  }
}

}  // namespace tetcut::testing
