#pragma once
/// Lone points off a cloud's surface (a scanner's stray returns): each would get a patch of its
/// own, a speck floating beside the surface (1 % random outliers around the bunny's 35,947
/// vertices at 1e-3: 2,310 patches instead of 1,799, a disc at every outlier).
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

struct OutlierOptions {
  std::size_t neighbours = 8;  ///< the points whose plane the point is measured against
  /// A point is an outlier when it lies farther than spacings × its neighbours' median spacing
  /// (the distance to their 6th nearest point) and roughness × their RMS distance from their own
  /// plane off that plane.
  double spacings = 2.0;
  double roughness = 4.0;
  /// A point is an outlier when its nearest point lies farther than this × its neighbours'
  /// median spacing (alone in space, whatever the plane).
  double isolated = 5.0;
  int passes = 4;  ///< each pass without the outliers found before (a scatter of them)
};

/// Exact copies: `position` gets each point's index among the distinct positions, which are
/// returned as the index of their first copy in the input (ascending).
std::vector<std::uint32_t> distinct_positions(std::span<const Eigen::Vector3d> points, std::vector<std::uint32_t>& position);

/// Indices of the outliers among points (ascending). Copies of a point are judged once, together. Density-adaptive: each point is measured
/// against its own neighbours' spacing and roughness, so the sparse side of an unevenly sampled
/// cloud is no outlier (a global distance threshold, as in CGAL's remove_outliers or Open3D's
/// statistical filter, drops it), nor is a noisy scan's noise, a thin part's other side (its
/// neighbours straddle both) or a point on a wire (its neighbours span no plane).
std::vector<std::uint32_t> find_outliers(std::span<const Eigen::Vector3d> points, const OutlierOptions& options = {});

/// Outliers nearer each other than a fifth of their distance to any other point, linked into clumps (a small separate
/// object, or a burst of stray returns: a neighbourhood test cannot tell them apart). Each clump
/// of at least `least` outliers, largest first, as indices into points.
std::vector<std::vector<std::uint32_t>> outlier_clumps(std::span<const Eigen::Vector3d> points,
                                                       std::span<const std::uint32_t> outliers, std::size_t least = 5);

class PointIndex;

/// The cloud's noise: how far its points scatter about their local surface, as the median over
/// up to `samples` points (every ⌈n/samples⌉-th) of the RMS residual of a height quadric through
/// each one's `neighbours` nearest points (in their PCA frame; with normals, the nearest whose
/// normals lie within 60° of its own, so not the other side of a thin part), scaled by
/// √(k/(k − 6)) for the quadric's six coefficients. A smooth surface sampled densely gives nearly 0 (the quadric
/// follows its curvature); Gaussian noise of deviation σ gives about σ; a surface sampled too
/// sparsely for a quadric over 16 points gives its higher-order bending (so the figure is what
/// the data resolves either way).
double estimate_noise(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                      const PointIndex& index, std::size_t samples = 5000, std::size_t neighbours = 16);

}  // namespace quadrix
