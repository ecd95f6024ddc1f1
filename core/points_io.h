#pragma once
/// Point clouds: PLY (ASCII, binary little/big-endian; with or without normals; extra
/// properties and extra elements ignored), XYZ (3 or 6 columns), vertices of OFF and OBJ.
#include <filesystem>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

struct PointCloud {
  std::vector<Eigen::Vector3d> points;   ///< world units
  std::vector<Eigen::Vector3d> normals;  ///< empty, or one unit normal per point
  bool has_normals() const { return !normals.empty(); }
};

/// Reads by extension (.ply .xyz .pts .txt .off .obj), sniffing the content where needed.
/// \throws FormatError naming the file and line/byte offset (NaN, wrong column counts,
///         truncated data, counts that exceed the file); IoError when it cannot be opened.
PointCloud read_points(const std::filesystem::path& path);

/// Writes x y z [nx ny nz] lines (temporary file + rename).
void write_points_xyz(const PointCloud& cloud, const std::filesystem::path& path);

}  // namespace quadrix
