#pragma once
/// Quad meshes → tetrahedron-clipped quadrics ([Stoll06] §4.5, eq. 1, 20–29).
///
/// Representation, per face (corners p0..p3 counter-clockwise seen from outside, L = diameter):
/// - Non-planar quad: the hyperbolic paraboloid through the bilinear patch s(u,v) (eq. 1), clipped
///   by the tetrahedron (p0, p1, p2, p3). With the tetrahedron's barycentric coordinates λᵢ, the
///   patch has λ = ((1−u)(1−v), u(1−v), uv, (1−u)v), so the quadric is λ₀λ₂ − λ₁λ₃ = 0 (eq. 20 in
///   barycentric form), built without dividing by the volume as D₀D₂ − D₁D₃ (Dᵢ = 6·volume with
///   pᵢ replaced by x) in a frame centred on the corners' centroid and scaled by L. The gradient
///   points along (p2 − p0) × (p3 − p1). Quadric ∩ tetrahedron = the patch exactly (λ ≥ 0 ⇔ u,v ∈ [0,1]).
/// - Planar and nearly planar quad: two flat triangles along the diagonal whose smaller triangle is
///   largest (robust for nearly triangular quads). The patch deviates from them by uv·d,
///   d = p0 − p1 + p2 − p3, so at most δ = |det(p1−p0, p2−p0, p3−p0)| / (8·A_min) off their planes.
///   Flat when δ ≤ planar_threshold · L.
/// - Triangle (and a quad with a repeated corner): its plane clipped by the tetrahedron with apex
///   a = centroid + h·n and base bᵢ = 2vᵢ − a (h = flat_height × longest edge); the triangle is
///   exactly the tetrahedron's cross-section (the vᵢ are the edge midpoints), a fat tetrahedron
///   that clips robustly in double and in float.
/// - A non-planar piece that is neither flat nor a well-conditioned quadric is halved along its
///   rulings (exact: same paraboloid, straight split lines) and each half decided again, up to
///   max_split_depth levels. A quadric piece (stored relative to its tetrahedron's centroid) must
///   have a tetrahedron thicker than 4e-12 L³ (the .qxm reader rejects 1e-12), a first-order
///   coefficient-rounding bound ≤ planar_threshold·L, and its second sheet ≥ 1e-5 of its size away
///   (min ‖∇f‖ ≥ 1e-5·‖A‖·size): closer, double ray casting loses the root (near-planar quads with
///   g ≈ 1e-9…1e-6, the corner of a nearly triangular quad). Both errors fall 4× per halving in
///   both directions, so the recursion ends; fold lines of self-intersecting near-planar quads
///   do not improve and stop at max_split_depth, where the better candidate is stored and its
///   deviation reported in max_relative_deviation.
/// - Polygons with more than four sides: ear-clipped into triangles, with a warning.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh_io.h"
#include "core/model.h"

namespace quadrix {

struct QuadConvertOptions {
  /// A quad is stored flat when its bilinear patch is within planar_threshold × L of the two
  /// triangles (L = the quad's diameter). Larger values trade exactness for thicker tetrahedra.
  double planar_threshold = 1e-9;
  /// Apex height of a flat triangle's clip tetrahedron, relative to its longest edge.
  double flat_height = 0.5;
  /// Faces with area ≤ degenerate_area × L² are zero-area.
  double degenerate_area = 1e-12;
  /// Skip zero-area faces (counted in degenerate_skipped) instead of throwing InvalidInput.
  bool skip_degenerate = false;
  /// Halving levels for pieces neither flat nor well-conditioned quadrics (at most 2^depth pieces).
  int max_split_depth = 12;
  /// Constant colour for every patch; none by default.
  std::optional<Rgb> colour;
  /// Names the mesh in error messages (e.g. the file name).
  std::string source = "mesh";
};

/// How many faces took each path.
struct QuadConversionCounts {
  std::size_t quadric_quads = 0;          ///< non-planar quads stored as one clipped quadric
  std::size_t flat_quads = 0;             ///< planar and nearly planar quads stored as two triangles
  std::size_t split_quads = 0;            ///< quads split in halves (thin tetrahedron, ill-conditioned)
  std::size_t collapsed_quads = 0;        ///< quads with a repeated corner, stored as a triangle
  std::size_t triangles = 0;              ///< triangle faces
  std::size_t polygons_triangulated = 0;  ///< faces with more than four sides
  std::size_t degenerate_skipped = 0;     ///< zero-area faces skipped (skip_degenerate)
};

struct QuadConversion {
  /// Tet patches only. Metadata left to the caller, except `closed` = 1 (core/culling.h) when the
  /// mesh is closed, consistently oriented and its faces point outward (backface culling exact).
  Model model;
  QuadConversionCounts counts;
  /// Face f became model.tets[tet_offsets[f] .. tet_offsets[f+1]).
  std::vector<std::size_t> tet_offsets;
  /// Largest estimated deviation of any stored surface from its bilinear patch, relative to the
  /// quad's diameter (flat deviation, or the quadric's coefficient-rounding bound).
  double max_relative_deviation = 0.0;
};

/// Converts every face of the mesh (world units) to tetrahedron-clipped quadric patches.
/// \throws InvalidInput naming options.source and the face index for a zero-area face (unless
///         skip_degenerate), a non-finite coordinate, or an index out of range.
QuadConversion convert_quads(const PolygonMesh& mesh, const QuadConvertOptions& options = {});

}  // namespace quadrix
