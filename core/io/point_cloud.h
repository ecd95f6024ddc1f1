#pragma once
/// A point cloud: positions and, optionally, one unit normal per point.
#include <vector>

#include <Eigen/Core>

namespace quadrix {

struct PointCloud {
  std::vector<Eigen::Vector3d> points;   ///< world units
  std::vector<Eigen::Vector3d> normals;  ///< empty, or one unit normal per point
  bool has_normals() const { return !normals.empty(); }
};

}  // namespace quadrix
