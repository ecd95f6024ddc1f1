#pragma once
/// The peers `quadrix bench fit` measures SLIM fitting against (issue 4 item 6): OpenMesh
/// quadric decimation bounded by a Hausdorff tolerance, CGAL Poisson surface reconstruction,
/// and the point-to-triangle-mesh distance both are measured with.
#include <cstddef>
#include <limits>
#include <span>

#include <Eigen/Core>

#include "core/mesh_io.h"
#include "core/points_io.h"

namespace quadrix::peers {

struct Decimation {
  PolygonMesh mesh;        ///< triangles
  std::size_t skipped_faces = 0;  ///< input faces OpenMesh refused (non-manifold, degenerate)
  double seconds = 0;      ///< conversion, decimation and garbage collection
};

/// OpenMesh's Decimater with ModQuadricT as the priority and ModHausdorffT (tolerance
/// max_error, world units) as a binary bound: collapses until none is legal. Polygons are
/// fanned into triangles first.
/// \throws InvalidInput for an empty mesh or a tolerance that is not positive.
Decimation decimate_quadric(const PolygonMesh& mesh, double max_error);

struct Poisson {
  PolygonMesh mesh;     ///< triangles
  double spacing = 0;   ///< average spacing of 6 neighbours, world units
  double seconds = 0;   ///< spacing, implicit function, solve and meshing
};

/// CGAL::poisson_surface_reconstruction_delaunay with CGAL's default meshing criteria
/// (angle 20°, radius 30, distance 0.375 × spacing). cloud needs normals (outward, unit).
/// \throws InvalidInput without normals; SolverError when CGAL's solver fails.
Poisson reconstruct_poisson(const PointCloud& cloud);

struct MeshDistance {
  std::size_t points = 0;
  double max = 0;  ///< world units
  double rms = 0;  ///< world units
  std::size_t beyond = 0;  ///< points farther than the bound asked about (none asked: 0)
};

/// Euclidean distance of every point to the nearest point of the triangles of mesh (CGAL
/// AABB tree; TBB-parallel over the points). \throws InvalidInput for a mesh without faces.
/// beyond: counts the points farther than `bound`.
MeshDistance point_mesh_distance(std::span<const Eigen::Vector3d> points, const PolygonMesh& mesh,
                                 double bound = std::numeric_limits<double>::infinity());

}  // namespace quadrix::peers
