#pragma once
/// Normal estimation for point clouds that come without normals: PCA over the k nearest
/// neighbours, orientation propagated along a minimum spanning tree of the kNN graph
/// (Hoppe et al. 1992, weight 1 − |nᵢ·nⱼ|), then made outward globally.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

/// Whether a neighbourhood's covariance eigenvalues (ascending) spread over a plane, not along a
/// line (a scanner's line, a row of a grid: any plane through it fits).
inline bool spreads_over_a_plane(const Eigen::Vector3d& eigenvalues) { return eigenvalues[1] > 0.02 * eigenvalues[2]; }

struct NormalEstimationOptions {
  /// k for the PCA covariance (≥ 3); where those neighbours lie along a line (a scanner's lines
  /// farther apart than their points), 2k, then 4k
  std::size_t neighbours = 16;
  std::size_t mst_neighbours = 8;  ///< k for the orientation graph (≥ 2)
};

struct NormalEstimation {
  std::vector<Eigen::Vector3d> normals;  ///< one unit normal per point, outward
  std::size_t components = 0;            ///< connected components of the kNN graph (each seeded separately)
  std::size_t flipped_components = 0;    ///< components turned round by the global outward test
  std::vector<std::uint32_t> component;  ///< each point's component of the kNN graph
  /// normals pointing the other way after the knife-edge step than after the propagation: a
  /// closed part whose points' rays (ray parity) say one side of a sharp rim faces in, oriented
  /// again from those votes (estimate_normals)
  std::size_t turned_by_parity = 0;
};

/// Unit outward normals for points (N×3, world units). Each kNN-graph component is seeded at its
/// point farthest from the component's centroid, oriented away from it; after propagation a
/// component whose normals mostly point to its centroid is flipped. A closed component whose
/// points' ray parity says one side of a knife edge faces in (the propagation crossed its rim)
/// is oriented again from those votes, and its rim's normals take their own side's plane
/// (fit/normals.cpp orient_by_parity).
/// \throws InvalidInput for fewer than 3 points or non-finite coordinates.
NormalEstimation estimate_normals(std::span<const Eigen::Vector3d> points,
                                  const NormalEstimationOptions& options = {});

/// How a cloud's own normals agree with its points, on up to `samples` points spread over the
/// cloud. A point is off its plane when its normal lies more than 60° from the PCA normal of its
/// `neighbours` nearest points (random or badly estimated normals: noisy ones, such as CGAL's
/// sphere_20k_normal with normals up to 30° off, pass). It is against its neighbours when more
/// than a third of its 8 nearest that lie on its sheet have normals pointing the other way (not
/// oriented consistently: a scanner's unoriented normals). A neighbour with an opposed normal
/// lies on the point's sheet when the direction to it is within 30° of the tangent plane and it
/// lies no farther off that plane than twice the median agreeing neighbour does, so the other
/// side of a thin plate, even a noisy one, mostly does not count. Where the nearest points lie
/// along a line (a scanner's line: every plane through it fits them; a wave scanned in lines 15
/// times farther apart than their points lost its exact normals, "99.5 % off their neighbours'
/// plane"), 2 and 4 times as many are asked, as estimate_normals does; only points whose
/// neighbourhood then spreads over a plane are checked for being off it (`spread`).
struct GivenNormalsCheck {
  std::size_t points = 0, spread = 0, off_plane = 0, against = 0;
  double off_plane_share() const { return spread ? double(off_plane) / double(spread) : 0.0; }
  double against_share() const { return points ? double(against) / double(points) : 0.0; }
};
GivenNormalsCheck check_given_normals(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                                      std::size_t neighbours = 16, std::size_t samples = 20000);

}  // namespace quadrix
