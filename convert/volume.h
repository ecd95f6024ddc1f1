#pragma once
/// Volume data → quadratic iso-surface patches clipped by tetrahedra ([Stoll06] §5.1.2, after
/// Rössl et al.'s quadratic splines on a tetrahedral partition of a regular grid).
///
/// Readers: NRRD (`.nhdr` detached header + data file, or attached `.nrrd`; raw encoding, gzip
/// when built with zlib), INRIMAGE-4 (`.inr`, `.inr.gz`), and headerless raw voxels with the
/// dimensions and type given by the caller. x varies fastest, then y, then z.
///
/// Conversion (convert_volume): every grid cell is split into the 6 tetrahedra around its
/// main diagonal (a conforming Kuhn split, as core/synth.h split_cube). On each tetrahedron the
/// quadratic Lagrange interpolant of the 10 nodes — its 4 corner samples and the values of a
/// smooth reconstruction of the volume at its 6 edge midpoints — is written in Bézier form
/// (b_ii = f_i, b_ij = 2 f_ij − (f_i + f_j)/2); a tetrahedron is kept only when its control net
/// straddles the iso-value V (the Bézier convex-hull property bounds the patch's range). The
/// patch's quadric is V − f (so it is negative where the data exceed V and its gradient points
/// towards lower values), written relative to the tetrahedron's centroid and normalised.
/// Midpoint values depend only on the edge, so neighbouring patches agree on shared faces: the
/// iso-surface is continuous (C0) across tetrahedra.
///
/// Unstructured meshes (convert_tet_mesh): the same patches on the tetrahedra of a given mesh
/// with per-vertex values; the edge midpoints come from the cubic Hermite interpolant along the
/// edge, f_ij = (f_i + f_j)/2 + (∇f_i − ∇f_j)·(x_j − x_i)/8, with vertex gradients from a local
/// least-squares quadratic fit (estimate_vertex_gradients). Exact for quadratic data.
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "core/model.h"

namespace quadrix {

/// A scalar field on a regular grid: sample (i, j, k) sits at origin + (i, j, k) ⊙ spacing.
struct Volume {
  std::array<int, 3> dims{0, 0, 0};                          ///< samples per axis, each ≥ 2
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones();         ///< world units, > 0
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();          ///< world position of sample (0,0,0)
  std::vector<float> values;                                 ///< dims[0]·dims[1]·dims[2], x fastest
  std::string source = "volume";                             ///< names the volume in messages
  std::string voxel_type = "float";                          ///< sample type in the file (NRRD name)

  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * dims[1] + j) * dims[0] + i;
  }
  float at(int i, int j, int k) const { return values[index(i, j, k)]; }
  Eigen::Vector3d position(int i, int j, int k) const {
    return origin + Eigen::Vector3d(i, j, k).cwiseProduct(spacing);
  }
  /// Smallest and largest sample.
  std::pair<double, double> range() const;
};

/// Voxel types of raw data. Names as in NRRD (`uint8`, `int16`, `float`, …).
enum class VoxelType { uint8, int8, uint16, int16, uint32, int32, float32, float64 };

/// Parses uint8|uchar|int8|uint16|ushort|int16|short|uint32|uint|int32|int|float|float32|double|float64
/// (and the NRRD long forms). \throws InvalidInput naming the unknown type.
VoxelType parse_voxel_type(std::string_view name);

/// What a headerless raw file holds.
struct RawVolumeLayout {
  std::array<int, 3> dims{0, 0, 0};
  VoxelType type = VoxelType::uint8;
  bool big_endian = false;
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones();
  std::size_t header_bytes = 0;  ///< bytes skipped at the start of the file
};

/// Reads `.nhdr`/`.nrrd`, `.inr`/`.inr.gz` by extension; anything else needs `raw`.
/// \throws FormatError naming the file and the field, or the expected against the actual byte
///         count, for a malformed header, an unsupported encoding or a size mismatch;
///         IoError when a file cannot be opened.
Volume read_volume(const std::filesystem::path& path, const std::optional<RawVolumeLayout>& raw = std::nullopt);
Volume read_nrrd(const std::filesystem::path& path);
Volume read_inr(const std::filesystem::path& path);
Volume read_raw_volume(const std::filesystem::path& path, const RawVolumeLayout& layout);

/// Writes a NRRD detached header `path` (.nhdr) and its float32 little-endian data file beside it
/// (same stem, `.raw`), each through a temporary file. \throws IoError.
void write_nrrd(const Volume& volume, const std::filesystem::path& path);

/// Marschner and Lobb's test function (1994) on [−1, 1]³:
/// ρ = (1 − sin(πz/2) + α(1 + cos(2π f_M cos(πr/2)))) / (2(1 + α)), r = √(x² + y²),
/// f_M = 6, α = 0.25; the classic iso-value is 0.5.
double marschner_lobb(const Eigen::Vector3d& p);
Eigen::Vector3d marschner_lobb_gradient(const Eigen::Vector3d& p);
/// The function sampled on an n³ grid over [−1, 1]³ (spacing 2/(n − 1)). \throws InvalidInput for n < 2.
Volume marschner_lobb_volume(int n);

/// How edge-midpoint values are reconstructed from the samples.
enum class Reconstruction {
  trilinear,    ///< the trilinear interpolant of the cell
  catmull_rom,  ///< tensor-product Catmull–Rom (interpolating, C1), clamped at the border
};

struct VolumeIsoOptions {
  double iso = 0.0;                                        ///< iso-value V, in (min, max) of the data
  Reconstruction reconstruction = Reconstruction::catmull_rom;
  bool linear = false;       ///< linear patches (marching tetrahedra: planes clipped by the tets)
  std::optional<Rgb> colour = std::nullopt;  ///< constant colour of every patch; none by default
  /// Called with the fraction done (0..1) from worker threads.
  std::function<void(double)> progress = {};
};

struct VolumeConversion {
  Model model;                     ///< tet patches only; metadata left to the caller, but `tetrahedra tessellation`
  std::size_t cells = 0;           ///< grid cells (a tet mesh: its tetrahedra)
  std::size_t cells_visited = 0;   ///< cells whose neighbourhood range could reach V (tet mesh: all)
  std::size_t tets_tested = 0;     ///< tetrahedra whose control net was computed
  std::size_t linear_gradients = 0;  ///< tet mesh: vertices whose gradient fell back to a linear fit
  double value_min = 0, value_max = 0;
};

/// The iso-surface {f = V} as tetrahedron-clipped quadrics (see the file comment).
/// \throws InvalidInput when V is not strictly inside the data range, or for a volume with
///         fewer than 2 samples along an axis, non-positive spacing or non-finite values.
VolumeConversion convert_volume(const Volume& volume, const VolumeIsoOptions& options);

struct TetMesh;  // convert/tetmesh_io.h

/// Per-vertex gradients of values on a tetrahedral mesh, least squares over the vertex's
/// neighbours: a full quadratic f(x_j) − f(x_i) ≈ g·d + ½dᵀHd, d = x_j − x_i (9 unknowns) over the
/// 1-ring, or the 2-ring when the 1-ring has fewer than 12 vertices (mesh borders); a linear fit
/// g·d over the same vertices where the quadratic one is rank-deficient. Exact for quadratic data
/// wherever the quadratic fit applies. values: one per vertex.
struct VertexGradients {
  std::vector<Eigen::Vector3d> gradients;  ///< one per vertex; zero for an unreferenced vertex
  std::size_t linear_fits = 0;              ///< vertices that fell back to the linear fit
};
VertexGradients estimate_vertex_gradients(const TetMesh& mesh, std::span<const double> values);

/// The iso-surface {f = V} of per-vertex values on a tetrahedral mesh, as convert_volume does on
/// a grid (same keep rule, same quadrics, one patch per kept tetrahedron, corners positively
/// oriented); edge midpoints from the Hermite rule in the file comment. options.reconstruction is
/// not used. values: one per vertex.
/// 	hrows InvalidInput for a values count other than the vertex count, a non-finite value, V not
///         strictly inside the value range, or a mesh failing validate_tet_mesh.
VolumeConversion convert_tet_mesh(const TetMesh& mesh, std::span<const double> values,
                                  const VolumeIsoOptions& options);

}  // namespace quadrix
