#pragma once
/// The one I/O entry point for meshes and point clouds (models: core/model_io.h; tetrahedral
/// meshes and volumes: convert/). A file's format is chosen by its extension and, for PLY and
/// unknown extensions, by its content; each format has one reader in core/io/read_X.cpp.
///
/// | format          | read as        | extension          | reader / writer           |
/// |-----------------|----------------|--------------------|---------------------------|
/// | PLY (all three encodings) with `comment quadrix-format` | model | .qxm .ply | core/model_io |
/// | PLY with faces  | mesh, points   | .ply               | read_ply.cpp / write_mesh.cpp |
/// | PLY without     | points         | .ply               | read_ply.cpp              |
/// | OFF ([ST][C][N]OFF) | mesh, points | .off             | read_off.cpp / write_mesh.cpp |
/// | OBJ (v, vn, f)  | mesh, points   | .obj               | read_obj.cpp / write_mesh.cpp |
/// | STL ASCII/binary | mesh, points  | .stl               | read_stl.cpp / write_mesh.cpp |
/// | XYZ, 3 or 6 columns | points     | .xyz .txt .pts     | read_xyz.cpp              |
/// | Kanai's SLIM    | model          | .slim2t            | core/model_io             |
///
/// Every reader goes through io::read_file and io::TextReader or ply::File: counts are checked
/// against the bytes left before anything is reserved, bytes after the declared data are an
/// error, and every message names the file (`FILE:LINE:COL: …`, binary `FILE: byte N: …`).
#include <cstdint>
#include <cmath>
#include <filesystem>
#include <optional>
#include <utility>
#include <vector>

#include "core/io/point_cloud.h"
#include "core/io/polygon_mesh.h"

namespace quadrix {

enum class FileKind { model, mesh, points };

/// What a file holds, by extension and content (reads at most its first 64 KiB): known_file_kind,
/// else points (an unknown name with no recognised content is read as XYZ).
/// \throws IoError when it is missing, a folder or unreadable.
FileKind detect_file_kind(const std::filesystem::path& path);
/// The same, but nothing for a file whose extension is none of the formats' (.ply .off .obj .stl
/// .xyz .txt .pts .qxm .slim2t) and whose content none of them claims: the caller decides (a
/// command that takes several kinds lets the model reader name what is wrong with it).
std::optional<FileKind> known_file_kind(const std::filesystem::path& path);

/// Reads a mesh (PLY, OFF, OBJ, STL). Faces are kept as in the file (no triangulation); faces
/// that a halfedge mesh would refuse (complex edge/vertex, repeated vertex) are kept and counted
/// in a warning. \throws FormatError naming the file and place (no faces, NaN, bad indices,
/// counts beyond the file, trailing data); IoError when it cannot be read.
PolygonMesh read_mesh(const std::filesystem::path& path);

/// Writes PLY (binary, double coordinates), OBJ, OFF or STL (binary, float32, polygons fanned into
/// triangles) by extension (temporary file + rename); per-vertex colours where the format has
/// them (not STL). \throws InvalidInput, IoError.
void write_mesh(const PolygonMesh& mesh, const std::filesystem::path& path);

/// Reads points (and the file's normals, if any) from PLY, XYZ/PTS/TXT, OFF, OBJ or STL vertices.
/// \throws FormatError (no points, NaN, wrong columns, bad counts), IoError.
PointCloud read_points(const std::filesystem::path& path);

/// Points with normals for fitting: a mesh file with faces gives its vertices and normals from
/// its faces (points_from_mesh); any other file is read_points.
PointCloud read_surface_points(const std::filesystem::path& path);

/// Turns faces wound against their neighbours so that each edge-connected part of the mesh is
/// wound one way: across every edge shared by exactly two faces, the two faces run it in opposite
/// directions. A closed part ends wound outward (positive volume); in an open part the faces of
/// the smaller area turn. A face keeps its first vertex (v0 v1 … vn → v0 vn … v1), so a
/// non-planar face keeps its fan of triangles. A part already wound one way is left as it is
/// (inward or not), and so is one that cannot be (a Möbius strip). Returns how many faces were
/// turned. (Hand-written: CGAL's orient_polygon_soup also splits non-manifold vertices,
/// renumbering the mesh, and costs a CGAL translation unit.)
std::size_t orient_faces_coherently(PolygonMesh& mesh);

/// Whether a closed or nearly closed mesh (at most 0.5 % of its edges not on exactly two faces:
/// a scan with a few holes, like bunny.ply: 0.2 %) encloses a negative signed volume, i.e. its faces
/// are wound clockwise seen from outside. Open sheets: false (their winding is taken as it is).
bool mesh_wound_inward(const PolygonMesh& mesh);

/// Which edges of a mesh are open (used by one face): every face's edges, sorted once.
class EdgeUses {
public:
  explicit EdgeUses(const PolygonMesh& mesh);
  /// Whether the edge between vertices a and b is used by exactly one face.
  bool open(int a, int b) const;
  /// mesh_wound_inward for the mesh these edges came from, without sorting them again.
  bool wound_inward(const PolygonMesh& mesh) const;

private:
  std::vector<std::pair<int, int>> edges_;  // (min, max) per face edge, sorted
};

/// A face whose area is at rounding level against its longest edge (twice_area: the norm of its
/// Newell normal, or of the fan's summed cross products): its normal is noise, and a ray along
/// one of its edges "hits" it with no defined side. One test for every reader of faces.
inline bool is_sliver(double twice_area, double longest_edge_squared) {
  return !(twice_area > 1e-9 * longest_edge_squared) || !std::isfinite(twice_area);
}

/// The vertices used by some face, each with the unit area-weighted sum of its faces' normals
/// (Newell's polygon normal), flipped when mesh_wound_inward, so they point outward.
/// Vertices of no face, or whose face normals cancel, are left out.
PointCloud points_from_mesh(const PolygonMesh& mesh);

/// One sample per face: its centroid with its unit normal, oriented as points_from_mesh orients
/// its vertex normals. Slivers (area at rounding level against their longest edge, whose normal is
/// noise) are left out.
/// face_of (optional): the face index of each sample, appended.
PointCloud face_centroids(const PolygonMesh& mesh, std::vector<std::uint32_t>* face_of = nullptr);

/// face_centroids, plus samples on the faces much larger than their neighbours (longest edge
/// above large_factor × the mesh's median longest edge): a barycentric lattice of spacing about
/// that median over each triangle of the face's fan, corners left out (the vertices are points
/// already). So the points a fit must cover leave no face interior uncovered (a filled scan hole
/// in the bunny left a hole in its SLIM surface between a big face's vertices and centroid).
/// face_of (optional): the face index of each sample, appended (centroids first, as above).
/// The lattice is added only when that median edge exceeds min_spacing.
PointCloud face_samples(const PolygonMesh& mesh, double large_factor = 2.0, std::vector<std::uint32_t>* face_of = nullptr,
                        double min_spacing = 0.0);

/// count points drawn uniformly by area over the faces (fans of triangles; slivers left out),
/// each with its face's unit normal oriented as face_centroids orients them: a scan-like cloud of
/// a mesh whose truth is known (bench fit --sample). Deterministic for a seed.
PointCloud sample_faces_uniformly(const PolygonMesh& mesh, std::size_t count, std::uint64_t seed = 1);

/// Writes x y z [nx ny nz] lines (temporary file + rename).
void write_points_xyz(const PointCloud& cloud, const std::filesystem::path& path);

}  // namespace quadrix
