#pragma once
/// Local refinement of a grid's Kuhn triangulation (each cube cell split into the six
/// tetrahedra around its main diagonal) by conforming longest-edge bisection (Rivara): a
/// tetrahedron is cut at its longest edge together with every tetrahedron around that edge, and
/// a neighbour whose own longest edge is another is cut there first. Three generations of cuts
/// give the Kuhn triangulation of the cell's eight half-size cells. The tetrahedra returned
/// share whole faces with one another and with the plain Kuhn split of every cell not in
/// `cells`, so marching tetrahedra on both together leaves no T-junction or crack at the seam.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

/// A coarse cell (its lowest node, grid coordinates) and the depth it is refined to: its
/// tetrahedra are cut until they are those of its cells of spacing h / 2^depth.
struct KuhnCellDepth {
  Eigen::Vector3i cell;
  int depth = 1;
};

struct KuhnRefinement {
  /// Lattice points are grid coordinates times 2^levels (a coarse node i is i·2^levels).
  int levels = 0;
  /// The coarse cells whose Kuhn tetrahedra are replaced by `tets` (the requested ones and those
  /// the closure reached), lowest node, grid coordinates.
  std::vector<Eigen::Vector3i> cells;
  /// The tetrahedra filling `cells`, four lattice points each.
  std::vector<std::array<Eigen::Vector3i, 4>> tets;
};

/// Refines the Kuhn triangulation of a grid with `cells_per_axis` cells per axis where `wanted`
/// asks (depths clamped to 1..levels; cells outside the grid ignored). Lattice coordinates must
/// fit 21 bits: cells_per_axis · 2^levels < 2^21.
/// \throws InvalidInput for levels outside 1..8 or a grid too large for them.
KuhnRefinement refine_kuhn_cells(const Eigen::Vector3i& cells_per_axis, std::span<const KuhnCellDepth> wanted,
                                 int levels);

}  // namespace quadrix
