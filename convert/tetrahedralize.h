#pragma once
/// Tetrahedralisation of convex cells and of closed surfaces with TetGen 1.5 (AGPL: linked only into the
/// `quadrix_tetgen` library, convert/tetrahedralize_tetgen.cpp).
///
/// TetGen 1.5 crashes (double free, segfault) on some invalid inputs, so no input reaches it
/// unchecked and every call runs in a forked child process: the input is validated first
/// (cells: finite coordinates, at least 4 distinct points, positive volume; surfaces: closed,
/// edge-manifold, consistently oriented, no degenerate triangle), and a TetGen crash or error in
/// the child becomes a SolverError in the caller that names the input, never a crash.
#include <array>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/bounds.h"

namespace quadrix {

using TetIndices = std::array<int, 4>;

struct TetrahedralizeOptions {
  /// Points closer than this fraction of the cell's diameter are merged before TetGen sees them.
  double merge_tolerance = 1e-10;
  /// Cells no thicker than this (6·volume of their largest tetrahedron over diameter³) are
  /// degenerate (InvalidInput): core/bounds.h's limit for one tetrahedron.
  double min_relative_volume = kDegenerateTetrahedron;
  /// Names the cells' owner in error messages.
  std::string source = "cells";
  /// When TetGen fails or crashes on a cell: false → SolverError; true → the cell is listed in
  /// Tetrahedralization::failed (no tetrahedra) and a fresh child process goes on with the next.
  bool skip_failed = false;
};

struct Tetrahedralization {
  std::vector<std::vector<TetIndices>> cells;  ///< cells[i] indexes the points of input cell i
  std::vector<std::size_t> failed;             ///< cells TetGen failed on (skip_failed only)
  std::string first_failure;                   ///< why the first of them failed
};

/// Tetrahedralises the convex hull of each point set (one TetGen run per cell, the cells in one
/// child process, restarted after a failure). Every tetrahedron is positively oriented.
/// \throws InvalidInput naming the cell for fewer than 4 distinct points, a non-finite point or a
///         flat cell; SolverError naming the cell when TetGen fails or crashes (unless skip_failed).
Tetrahedralization tetrahedralize_convex_cells(std::span<const std::vector<Eigen::Vector3d>> cells,
                                               const TetrahedralizeOptions& options = {});

struct SurfaceTetrahedralizeOptions {
  /// TetGen's bound on the tetrahedra's radius–edge ratio (`-q`), ≥ 1.1: smaller gives rounder
  /// tetrahedra and more points inside; 0 refines nothing (the constrained Delaunay mesh).
  double quality = 2.0;
  /// Largest tetrahedron volume (`-a`), world units³; 0: unbounded.
  double max_volume = 0;
  /// Names the surface in error messages.
  std::string source = "surface";
};

/// The tetrahedra filling a closed surface.
struct SurfaceTetrahedralization {
  std::vector<Eigen::Vector3d> points;  ///< the surface's vertices (same indices), then added points
  std::vector<TetIndices> tets;         ///< positively oriented
};

/// Checks that the triangles (indices into vertices) bound a volume: finite coordinates, indices
/// in range, no triangle of zero area, and every edge in exactly two triangles, once in each
/// direction (closed, edge-manifold, consistently oriented; either orientation as a whole).
/// \throws InvalidInput naming the source, the triangle or edge (vertex indices) and the fault.
void validate_closed_surface(std::span<const Eigen::Vector3d> vertices, std::span<const std::array<int, 3>> triangles,
                             const std::string& source);

/// Fills a closed triangle surface with tetrahedra (TetGen `-p`, with `-q`/`-a` as asked), in a
/// child process after validate_closed_surface; the boundary is kept (refinement may add points
/// on it).
/// \throws InvalidInput as validate_closed_surface; SolverError when TetGen fails or crashes
///         (a self-intersecting surface, for one).
SurfaceTetrahedralization tetrahedralize_closed_surface(std::span<const Eigen::Vector3d> vertices,
                                                        std::span<const std::array<int, 3>> triangles,
                                                        const SurfaceTetrahedralizeOptions& options = {});

}  // namespace quadrix
