#pragma once
/// Tetrahedral meshes with per-vertex values, the unstructured input of `convert volume --tets`.
///
/// Formats: Medit `.mesh` (ASCII: `MeshVersionFormatted`, `Dimension 3`, `Vertices` n then
/// x y z ref, `Tetrahedra` m then four 1-based indices and a ref, `End`; other sections such as
/// Triangles, Edges, Corners are skipped; `#` starts a comment) and TetGen `.node` + `.ele` pairs
/// (either file names the pair; indices 0- or 1-based as the `.node` file's first point says;
/// 10-node `.ele` files keep their 4 corners). Values: one number per vertex, whitespace
/// separated, `#` comments.
///
/// Everything is validated before it is trusted: counts against the file, indices in range,
/// finite coordinates and values, and no degenerate tetrahedron (core/bounds.h
/// is_degenerate_tetrahedron).
#include <array>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

/// Vertices and tetrahedra (0-based indices into vertices), world units.
struct TetMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 4>> tets;
  std::string source = "tet mesh";  ///< names the mesh in messages
};

/// Reads `.mesh` (Medit) or `.node`/`.ele` (TetGen) by extension.
/// \throws FormatError naming the file and line: unknown keyword, truncated section, a count that
///         disagrees with the file, an index out of range, a non-finite coordinate, a degenerate
///         tetrahedron, Dimension ≠ 3, no tetrahedra; InvalidInput for an unknown extension;
///         IoError when a file cannot be opened.
TetMesh read_tet_mesh(const std::filesystem::path& path);
TetMesh read_medit_mesh(const std::filesystem::path& path);
/// `path` may name the `.node` or the `.ele` file; the other one sits beside it.
TetMesh read_tetgen_mesh(const std::filesystem::path& path);

/// Writes a Medit `.mesh` (MeshVersionFormatted 2, refs 0) through a temporary file. \throws IoError.
void write_medit_mesh(const TetMesh& mesh, const std::filesystem::path& path);

/// One finite value per vertex (`vertex_count` of them).
/// \throws FormatError naming the file and line of a non-number, a non-finite value, a value
///         past the last vertex, or (at the end of the file) too few values; IoError.
std::vector<double> read_vertex_values(const std::filesystem::path& path, std::size_t vertex_count);

/// Checks indices, finite coordinates and non-degenerate tetrahedra of a mesh built in memory.
/// \throws InvalidInput naming the tetrahedron (index and corners) or the vertex.
void validate_tet_mesh(const TetMesh& mesh);

}  // namespace quadrix
