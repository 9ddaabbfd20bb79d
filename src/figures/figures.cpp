#include <tetcut/figures.hpp>
#include <tetcut/generators.hpp>

#include <algorithm>
#include <cmath>
#include <map>
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

TriangleSurface icosphere(const Vec3& centre, double radius, int subdivisions) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<Index, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                         {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                         {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                         {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Vec3& p : v) p.normalize();
  for (int level = 0; level < subdivisions; ++level) {
    // One midpoint per edge, shared by the two triangles on it.
    std::map<std::pair<Index, Index>, Index> midpoint;
    const auto middle = [&](Index a, Index b) {
      const auto key = std::minmax(a, b);
      const auto [it, inserted] = midpoint.try_emplace({key.first, key.second}, static_cast<Index>(v.size()));
      if (inserted) v.push_back((v[a] + v[b]).normalized());
      return it->second;
    };
    std::vector<std::array<Index, 3>> finer;
    for (const auto& tri : f) {
      const Index ab = middle(tri[0], tri[1]), bc = middle(tri[1], tri[2]), ca = middle(tri[2], tri[0]);
      finer.push_back({tri[0], ab, ca});
      finer.push_back({tri[1], bc, ab});
      finer.push_back({tri[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    f = std::move(finer);
  }
  TriangleSurface s;
  s.vertices.resize(static_cast<Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) s.vertices.row(static_cast<Index>(i)) = (centre + radius * v[i]).transpose();
  s.triangles.resize(static_cast<Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) {
    for (int k = 0; k < 3; ++k) s.triangles(static_cast<Index>(i), k) = f[i][k];
  }
  return s;
}

TriangleSurface box_surface(const Box& box) {
  TriangleSurface s;
  s.vertices.resize(8, 3);
  for (Index v = 0; v < 8; ++v) {
    for (int k = 0; k < 3; ++k) s.vertices(v, k) = ((v >> k) & 1) != 0 ? box.max[k] : box.min[k];
  }
  // Corner v has bit k set when it is at max along axis k; each face as two triangles, outward.
  s.triangles.resize(12, 3);
  s.triangles << 0, 2, 1, 1, 2, 3,  // z = min
      4, 5, 6, 5, 7, 6,             // z = max
      0, 1, 4, 1, 5, 4,             // y = min
      2, 6, 3, 3, 6, 7,             // y = max
      0, 4, 2, 2, 4, 6,             // x = min
      1, 3, 5, 3, 7, 5;             // x = max
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
