#pragma once
/// Skin surfaces of ball sets → tetrahedron-clipped quadrics ([Stoll06] §5.1.2; Edelsbrunner's
/// skin surface, as CGAL `Skin_surface_3` defines it: balls grown to weight r²/s, shrink s).
///
/// Every simplex δ of the balls' regular triangulation and its dual power-diagram face ν span a
/// mixed cell (1−s)δ + sν, a convex polyhedron carrying one quadric: the closed forms of CGAL's
/// `Skin_surface_quadratic_surface_3.h` (weighted circumcentre p, c = s(1−s)·radius² of the
/// smallest orthogonal sphere, Q from the simplex's direction).
///
/// Three ways to the tetrahedra (SkinTetrahedra):
/// - regular (default; convert/skin_regular.cpp): our own mixed complex over CGAL's
///   `Regular_triangulation_3`. δ and ν span orthogonal complementary spaces, so each cell is the
///   product of the scaled simplex and the scaled dual face and splits into tetrahedra directly
///   (fans and prisms). Cells are visited one at a time and only tetrahedra the surface can cross
///   are kept: 1aon (58,870 atoms) in 13 s and 2.4 GB.
/// - cgal (convert/skin_cgal.cpp): CGAL's `triangulated_mixed_complex()` as is; the quadrics are
///   checked against CGAL's `value()` at the 10 quadratic nodes of every tetrahedron
///   (max_quadric_disagreement). CGAL triangulates every cell first: 5.8 GB for 5,684 atoms.
/// - tetgen: CGAL's crossed cells (the convex hull of their tetrahedra's corners) tetrahedralised
///   again by TetGen (convert/tetrahedralize.h: validated, in a child process; a cell TetGen aborts
///   on keeps CGAL's tetrahedra and is counted in tetgen_failed_cells). Known issue: TetGen's
///   output for cells with (nearly) coplanar boundary points contains flat tetrahedra, which are
///   skipped, and a few CGAL mesh vertices then fall outside every kept tetrahedron.
/// tests/convert/test_skin.cpp renders all three against each other and checks them against
/// CGAL's own mesh of the skin (`mesh_skin_surface_3`).
///
/// Clipped: a tetrahedron reaching outside the box of its simplex's balls (always those of the
/// outer, unbounded mixed cells) is cut to that box (core/bounds.h clip_tetrahedron_to_box); in a
/// mixed cell the skin lies inside the union of the simplex's balls, so no surface is lost.
///
/// Skipped: mixed cells of the bounding-octahedron vertices (weight −1, as CGAL adds them), and
/// tetrahedra whose Bézier control net of the quadric (b_ij = p̃ᵢᵀQ̃p̃ⱼ) has one strict sign (the
/// surface cannot cross them). Colour: the CPK colour of the simplex's ball nearest (in power
/// distance) to the tetrahedron's centroid.
#include <cstddef>
#include <string>
#include <vector>

#include "convert/balls.h"
#include "core/model.h"

namespace quadrix {

enum class SkinTetrahedra { tetgen, cgal, regular };

struct SkinOptions {
  double shrink = 0.5;                              ///< CGAL's shrink factor s, in (0, 1)
  SkinTetrahedra tetrahedra = SkinTetrahedra::regular;
  std::string source = "balls";                     ///< names the input in error messages
};

struct SkinConversion {
  Model model;                           ///< tet patches only; metadata left to the caller
  std::size_t mixed_cells = 0;           ///< mixed cells of the balls (bounding-box cells excluded)
  std::size_t mixed_cells_crossed = 0;   ///< mixed cells the surface crosses
  std::size_t bbox_cells_skipped = 0;    ///< CGAL tetrahedra of bounding-octahedron cells
  std::size_t cgal_tets = 0;             ///< tetrahedra of CGAL's triangulated mixed complex
  std::size_t cgal_tets_crossed = 0;     ///< of which the surface can cross
  std::size_t tetgen_tets = 0;           ///< TetGen's tetrahedra of the crossed cells (tetgen mode)
  std::size_t slivers_skipped = 0;       ///< tetrahedra of (near) zero volume, skipped
  std::size_t tets_clipped_to_box = 0;   ///< tetrahedra clipped to their simplex's balls' box
  std::size_t tetgen_failed_cells = 0;   ///< crossed cells TetGen failed on: CGAL's tetrahedra kept
  /// Largest |ours − CGAL value()| over the 10 nodes of every CGAL tetrahedron, relative to the
  /// largest |value| there and the tetrahedron's squared diameter.
  double max_quadric_disagreement = 0;
  std::size_t mixed_tets = 0;            ///< tetrahedra of the mixed cells tested (regular mode)
  std::size_t hidden_balls = 0;          ///< balls with no vertex in the regular triangulation (regular mode)
  double triangulation_seconds = 0;      ///< regular triangulation and power centres (regular mode)
  double cgal_seconds = 0, tetgen_seconds = 0;
};

/// \throws InvalidInput for an empty set, a non-positive radius, duplicate centres or a shrink
///         factor outside (0, 1); SolverError when TetGen fails on a cell.
SkinConversion convert_skin(const std::vector<Ball>& balls, const SkinOptions& options = {});

/// CGAL's own triangle mesh of the skin surface (`mesh_skin_surface_3`, then `subdivide_skin_surface_mesh_3`
/// `subdivisions` times): the reference the conversion is checked against.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;
};
TriangleMesh cgal_skin_mesh(const std::vector<Ball>& balls, double shrink, int subdivisions);

}  // namespace quadrix
