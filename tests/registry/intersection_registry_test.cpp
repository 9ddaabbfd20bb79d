// The registry's side tests (filter, the "on the plane by construction" shortcut, cached exact
// forms) against a direct exact evaluation, and the shortcut's soundness on its own, on points made from every kind of plane: triangle
// planes sharing corners and edges (where the shortcut fires), walls, and pulled-back planes
// (which define no input points: a regression, the shortcut once read their unset corners).

#include <gtest/gtest.h>

#include <random>

#include "geometry/plane.hpp"
#include "registry/intersection_registry.hpp"

namespace tetcut::registry {
namespace {

using geometry::Plane;

TEST(IntersectionRegistry, SideTestsAgreeWithExactEvaluation) {
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int> grid(-4, 4);
  // Corners on a coarse grid make shared corners, coplanar planes and exact zeros common.
  const auto point = [&]() -> Vec3 { return Vec3(grid(rng), grid(rng), grid(rng)) * 0.25; };
  const Points rest(0, 3);
  for (int trial = 0; trial < 40; ++trial) {
    IntersectionRegistry registry(rest);
    std::vector<Vec3> corners;
    for (int i = 0; i < 6; ++i) corners.push_back(point());
    std::vector<PlaneId> planes;
    // Triangles over shared corners, and walls of their edges.
    for (int i = 0; i < 6; ++i) {
      const Vec3& a = corners[i];
      const Vec3& b = corners[(i + 1) % 6];
      const Vec3& c = corners[(i + 3) % 6];
      if ((b - a).cross(c - a).squaredNorm() == 0) continue;
      planes.push_back(registry.triangle_plane(a, b, c).id);
      for (int axis = 0; axis < 3; ++axis) {
        if ((b - a).cross(Vec3::Unit(axis)).squaredNorm() == 0 || (c - a).cross(Vec3::Unit(axis)).dot(b - a) == 0) continue;
        planes.push_back(registry.wall(a, b, axis, c).id);
        break;
      }
    }
    // Pulled-back planes: four world triangles through two different tet motions, so that some
    // points are made of pulled-back planes only.
    const std::array<Vec3, 4> tet_rest = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
    const std::array<std::array<Vec3, 4>, 2> tet_now = {
        std::array<Vec3, 4>{Vec3(0.25, 0, 0), Vec3(1, 0.25, 0), Vec3(0, 1, 0.5), Vec3(0, 0.25, 1)},
        std::array<Vec3, 4>{Vec3(0, 0, 0.5), Vec3(1.5, 0, 0), Vec3(0, 0.75, 0), Vec3(0.25, 0.25, 1)}};
    for (int i = 0; i < 4; ++i) {
      const Plane world = Plane::through(point(), point(), point());
      if (world.certainly_zero()) continue;
      planes.push_back(registry.add_plane(Plane::pulled_back(world, tet_rest, tet_now[i % 2])));
    }
    // Points: every triple of planes that meets in one point.
    std::vector<VertexId> points;
    for (std::size_t i = 0; i < planes.size(); ++i) {
      for (std::size_t j = i + 1; j < planes.size(); ++j) {
        for (std::size_t k = j + 1; k < planes.size(); ++k) {
          const Plane &a = registry.plane(planes[i]), &b = registry.plane(planes[j]), &c = registry.plane(planes[k]);
          if (geometry::normal_determinant_sign(a, b, c) != 0) points.push_back(registry.add_point(planes[i], planes[j], planes[k]));
        }
      }
    }
    for (const VertexId v : points) {
      const Vertex& vertex = registry.vertex(v);
      const geometry::ExactPoint x = geometry::exact_tpi(geometry::exact_plane(registry.plane(vertex.planes[0])),
                                                         geometry::exact_plane(registry.plane(vertex.planes[1])),
                                                         geometry::exact_plane(registry.plane(vertex.planes[2])));
      for (const PlaneId q : planes) {
        const int exact = geometry::exact_side(geometry::exact_plane(registry.plane(q)), x);
        ASSERT_EQ(registry.side(v, q), exact) << "trial " << trial << " point " << v << " plane " << q;
        // The shortcut runs only where the filter fails, so check it on its own: it may only ever
        // claim a zero that is one.
        if (registry.on_plane_by_construction(v, q)) {
          ASSERT_EQ(exact, 0) << "trial " << trial << " point " << v << " plane " << q;
        }
      }
    }
  }
}

}  // namespace
}  // namespace tetcut::registry
