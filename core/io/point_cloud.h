#pragma once
/// A point cloud: positions and, optionally, one unit normal and one colour per point.
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

struct PointCloud {
  std::vector<Eigen::Vector3d> points;   ///< world units
  std::vector<Eigen::Vector3d> normals;  ///< empty, or one unit normal per point
  /// Empty, or one 8-bit sRGB colour per point (a coloured scan: PLY red/green/blue, XYZ's
  /// nine-column form); fit_slim gives its patches their points' blended colour.
  std::vector<std::array<std::uint8_t, 3>> colours;
  bool has_normals() const { return !normals.empty(); }
  bool has_colours() const { return !colours.empty(); }
  /// Appends src's point i with its normal and colour (where src has them).
  void push_back_from(const PointCloud& src, std::size_t i) {
    points.push_back(src.points[i]);
    if (src.has_normals()) normals.push_back(src.normals[i]);
    if (src.has_colours()) colours.push_back(src.colours[i]);
  }
};

}  // namespace quadrix
