#pragma once
/// Internal to core/io: one reader (and writer, where one exists) per format, each parsing
/// bytes already read by the kit. io.cpp dispatches to them; nothing else includes this header.
#include <filesystem>
#include <string_view>
#include <vector>

#include "core/io/point_cloud.h"
#include "core/io/polygon_mesh.h"

namespace quadrix::io {

/// What a surface file holds: a mesh (possibly without faces) and the file's own per-vertex
/// normals (empty when it has none).
struct Surface {
  PolygonMesh mesh;
  std::vector<Eigen::Vector3d> normals;
};

Surface read_off(std::string_view text, const std::filesystem::path& path);  // read_off.cpp
Surface read_obj(std::string_view text, const std::filesystem::path& path);  // read_obj.cpp
Surface read_stl(std::string_view bytes, const std::filesystem::path& path);  // read_stl.cpp
Surface read_ply(std::string bytes, const std::filesystem::path& path);       // read_ply.cpp
/// XYZ/PTS/TXT: 3 or 6 columns; with count_line a leading point count (.pts).   read_xyz.cpp
PointCloud read_xyz(std::string_view text, const std::filesystem::path& path, bool count_line);

void write_off(const PolygonMesh& mesh, const std::filesystem::path& path);  // write_mesh.cpp
void write_obj(const PolygonMesh& mesh, const std::filesystem::path& path);
void write_ply(const PolygonMesh& mesh, const std::filesystem::path& path);  // binary little-endian
void write_stl(const PolygonMesh& mesh, const std::filesystem::path& path);  // binary, float32
void write_xyz(const PointCloud& cloud, const std::filesystem::path& path);  // read_xyz.cpp

/// Whether the bytes are a binary STL: 84 + 50·n bytes for the count n at byte 80.
bool is_binary_stl(std::string_view bytes);

}  // namespace quadrix::io
