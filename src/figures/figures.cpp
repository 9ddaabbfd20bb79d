#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>

#include <cmath>
#include <numbers>
#include <random>

namespace tetcut::figures {

TetMesh figure2_tet() {
  Points p(4, 3);
  p << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Tets t(1, 4);
  t << 0, 1, 2, 3;
  return TetMesh(std::move(p), std::move(t), "figure 2 tet");
}

TriangleSurface figure2_triangles(std::uint64_t seed, int count) {
  const TetMesh tet = figure2_tet();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> gauss;
  TriangleSurface soup;
  soup.vertices.resize(3 * count, 3);
  soup.triangles.resize(count, 3);
  for (int i = 0; i < count; ++i) {
    // A uniform random point of the tet (normalised exponential weights), a uniform random normal.
    double w[4], sum = 0;
    for (double& x : w) sum += x = -std::log(unit(rng));
    Vec3 centre = Vec3::Zero();
    for (int k = 0; k < 4; ++k) centre += w[k] / sum * tet.rest().row(k).transpose();
    const Vec3 normal = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const Vec3 u = normal.unitOrthogonal(), v = normal.cross(u);
    const double radius = 0.2 + 1.3 * unit(rng), turn = 2 * std::numbers::pi * unit(rng);
    for (int k = 0; k < 3; ++k) {
      const double angle = turn + 2 * std::numbers::pi * k / 3;
      soup.vertices.row(3 * i + k) = (centre + radius * (std::cos(angle) * u + std::sin(angle) * v)).transpose();
      soup.triangles(i, k) = 3 * i + k;
    }
  }
  return soup;
}

TetMesh figure4_cube() { return make_grid(Box{}, {4, 4, 4}, 5); }

TriangleSurface axis_square(int axis, double value, double lo, double hi) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  TriangleSurface s;
  s.vertices.resize(4, 3);
  for (int k = 0; k < 4; ++k) {
    s.vertices(k, axis) = value;
    s.vertices(k, u) = (k == 1 || k == 2) ? hi : lo;
    s.vertices(k, v) = (k >= 2) ? hi : lo;
  }
  s.triangles.resize(2, 3);
  s.triangles << 0, 1, 2, 0, 2, 3;
  return s;
}

TriangleSurface concatenate(const TriangleSurface& a, const TriangleSurface& b) {
  TriangleSurface s;
  s.vertices.resize(a.num_vertices() + b.num_vertices(), 3);
  s.vertices.topRows(a.num_vertices()) = a.vertices;
  s.vertices.bottomRows(b.num_vertices()) = b.vertices;
  s.triangles.resize(a.num_triangles() + b.num_triangles(), 3);
  s.triangles.topRows(a.num_triangles()) = a.triangles;
  s.triangles.bottomRows(b.num_triangles()) = b.triangles.array() + a.num_vertices();
  return s;
}

TriangleSurface figure4_planes() {
  TriangleSurface soup;
  for (int i = 1; i <= 16; ++i) {
    soup = concatenate(soup, axis_square(0, i / 17.0, -0.5, 1.5));
    soup = concatenate(soup, axis_square(1, i / 17.0, -0.5, 1.5));
  }
  return soup;
}

}  // namespace tetcut::figures
