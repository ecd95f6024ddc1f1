#pragma once
/// Normal estimation for point clouds that come without normals: PCA over the k nearest
/// neighbours, orientation propagated along a minimum spanning tree of the kNN graph
/// (Hoppe et al. 1992, weight 1 − |nᵢ·nⱼ|), then made outward globally.
#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

struct NormalEstimationOptions {
  std::size_t neighbours = 16;  ///< k for the PCA covariance (≥ 3)
  std::size_t mst_neighbours = 8;  ///< k for the orientation graph (≥ 2)
};

struct NormalEstimation {
  std::vector<Eigen::Vector3d> normals;  ///< one unit normal per point, outward
  std::size_t components = 0;            ///< connected components of the kNN graph (each seeded separately)
  std::size_t flipped_components = 0;    ///< components turned round by the global outward test
};

/// Unit outward normals for points (N×3, world units). Each kNN-graph component is seeded at its
/// point farthest from the component's centroid, oriented away from it; after propagation a
/// component whose normals mostly point to its centroid is flipped.
/// \throws InvalidInput for fewer than 3 points or non-finite coordinates.
NormalEstimation estimate_normals(std::span<const Eigen::Vector3d> points,
                                  const NormalEstimationOptions& options = {});

}  // namespace quadrix
