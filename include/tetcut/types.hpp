#pragma once
// Plain buffers used at the API boundary. Shapes are given as rows x columns.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

namespace tetcut {

/// Node and tet indices. 32 bits address two billion elements, far beyond what fits in memory
/// with the per-tet data the cutter keeps, and halve the index traffic of 64-bit ids.
using Index = std::int32_t;

/// |V| x 3 node coordinates, one node per row.
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// |T| x 4 node ids of each tetrahedron; positive orientation means
/// det[p1 - p0, p2 - p0, p3 - p0] > 0 (the VTK, Gmsh and TetGen convention).
using Tets = Eigen::Matrix<Index, Eigen::Dynamic, 4, Eigen::RowMajor>;
/// |F| x 3 node ids of each triangle, counter-clockwise seen from the side its normal points to.
using Triangles = Eigen::Matrix<Index, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// |E| x 2 node ids of each edge.
using Edges = Eigen::Matrix<Index, Eigen::Dynamic, 2, Eigen::RowMajor>;

using Vec3 = Eigen::Vector3d;

}  // namespace tetcut
