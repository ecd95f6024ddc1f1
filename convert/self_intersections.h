#pragma once
/// Self-intersections of a triangle mesh: pairs of triangles that cross or overlap where they
/// should not meet. Decided with CGAL's exact predicates (box_self_intersection_d for the
/// candidate pairs, do_intersect on triangles and segments), on a soup: vertices at one position
/// count as one vertex, so pieces closed at a seam by equal vertices are not counted, and
/// non-manifold meshes (open sheets, edges of three faces) are measured as they are.
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/mesh_io.h"

namespace quadrix {

struct SelfIntersections {
  std::size_t pairs = 0;  ///< pairs of triangles that meet where they should not
  std::vector<std::pair<std::uint32_t, std::uint32_t>> examples;  ///< the first few such pairs (face indices)
  std::size_t degenerate = 0;  ///< faces of zero area (collinear corners), left out of the test
};

/// Pairs of triangles of m (faces with more corners are fanned from their first vertex: face
/// indices then count the fan's triangles) that meet beyond what they share: triangles with no
/// common vertex that touch or cross; with one common vertex, that meet elsewhere too (an
/// edge of one through the other, or coplanar overlap); with a common edge, that fold onto each
/// other (coplanar, on one side of the edge). keep: how many examples to return.
SelfIntersections self_intersections(const PolygonMesh& m, std::size_t keep = 8);

}  // namespace quadrix
