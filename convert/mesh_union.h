#pragma once
/// The union of closed triangle meshes (CGAL's corefinement, convert/mesh_cgal.cpp): what a
/// renderer draws of overlapping glyphs, as one closed surface without the parts hidden inside
/// the others, so the exported mesh has no crossing shells (a molecule's atoms each meshed as
/// a sphere: 4lfq spacefill had 134,972 pairs of crossing triangles).
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/mesh_io.h"

namespace quadrix {

struct MeshUnion {
  PolygonMesh mesh;          ///< the union's triangles (outward), with the parts that failed appended (same shape; corefined: vertices added on the intersection curves)
  std::size_t parts = 0;     ///< meshes given
  std::size_t failed = 0;    ///< unions CGAL refused (a result that would not be a closed manifold): both kept as they were
  std::string why;           ///< union_by_autorefinement: why it failed (empty when it did not)
  bool apart = false;        ///< union_by_autorefinement failed outright: the parts as they were
};

/// The union of `parts`, each a closed, outward-oriented triangle mesh without self-intersections
/// (an icosphere, a capped cylinder). Merged pairwise in rounds, neighbours first (parts ordered
/// along a Morton curve of their centres), one pair after another (CGAL 5.5's corefinement is not
/// thread-safe). The union has no
/// vertex colours (the caller's to give: its vertices are the parts' own, at the same places, and
/// those CGAL made on intersection curves). progress (optional): the fraction done.
MeshUnion union_of_closed_meshes(std::vector<PolygonMesh> parts, const std::function<void(double)>& progress = {});

/// The same union by another route: every part in one soup, autorefined (CGAL 5.5's
/// experimental autorefine_and_remove_self_intersections: the soup cut along every intersection
/// curve, the patches inside the volume removed, the rest stitched). Pairwise corefinement crashed
/// on capped cylinders meeting spheres (4lfq balls-and-sticks, round 8); this does not (16 s
/// there), but it is about twice as slow on spheres alone. CGAL asserts nothing in release builds,
/// so it runs in a child process: a crash, a CGAL exception or a truncated result leaves the parts
/// as they were (failed = parts − 1, why says what happened). failed = 1 where CGAL could not fix
/// every self-intersection (the mesh is then its best attempt).
MeshUnion union_by_autorefinement(std::vector<PolygonMesh> parts);

}  // namespace quadrix
