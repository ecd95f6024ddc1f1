#pragma once
/// The union of closed triangle meshes (CGAL's corefinement, convert/mesh_cgal.cpp): what a
/// renderer draws of overlapping glyphs, as one closed surface without the parts hidden inside
/// the others, so the exported mesh has no crossing shells (a molecule's atoms each meshed as
/// a sphere: 4lfq spacefill had 134,972 pairs of crossing triangles).
#include <cstddef>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "core/mesh_io.h"

namespace quadrix {

struct MeshUnion {
  PolygonMesh mesh;          ///< the union's triangles (outward), with the parts that failed appended (same shape; corefined: vertices added on the intersection curves)
  std::size_t parts = 0;     ///< meshes given
  std::size_t failed = 0;    ///< unions CGAL refused (a result that would not be a closed manifold): both kept as they were
};

/// The union of `parts`, each a closed, outward-oriented triangle mesh without self-intersections
/// (an icosphere, a capped cylinder). Merged pairwise in rounds, neighbours first (parts ordered
/// along a Morton curve of their centres), one pair after another (CGAL 5.5's corefinement is not
/// thread-safe). The union has no
/// vertex colours (the caller's to give: its vertices are the parts' own, at the same places, and
/// those CGAL made on intersection curves). progress (optional): the fraction done.
MeshUnion union_of_closed_meshes(std::vector<PolygonMesh> parts, const std::function<void(double)>& progress = {});

}  // namespace quadrix
