#pragma once
/// Measured error of a SLIM model against points: the distance of each point to the blended
/// surface the renderer shows (per-ray blend of core/slim.h), along the point's normal.
#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "core/model.h"
#include "core/points_io.h"
#include "core/reference.h"
#include "fit/data_surface.h"
#include "fit/point_index.h"

namespace quadrix {

struct SlimErrorOptions {
  /// Probe height h (world units): each point p is measured by the ray from p + h·n along −n,
  /// error |t − h|; no hit counts as a miss (infinite error). 0: 4 × the model's
  /// `max_error_abs` metadata, or 5e-3 × the points' bounding-box diagonal without it.
  double probe_height = 0;
  bool keep_per_point = false;  ///< fill SlimError::per_point
  /// The data's surface (a mesh): each probe then starts at most halfway to the next sheet of it
  /// above the point (probe_heights), not inside another part of the body.
  const DataSurface* surface = nullptr;
};

/// Probe height per point: h, or half the distance along +n to the next sheet of surface when
/// that is nearer (a finger touching another, the gap between legs). surface may be null (all h).
std::vector<double> probe_heights(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                                  double h, const DataSurface* surface);

/// One point's probe against the blended surface: the ray from p + h·n along −n through the
/// scene (core's per-ray blend). A front-facing sheet crossed more than E above p (a crease's
/// far wall, another part of the body passing over the point) is passed: the probe goes on below
/// it, up to 4 times, and the crossing nearest to p along the normal counts.
struct PointProbe {
  double error = std::numeric_limits<double>::infinity();  ///< |t − h| of the counted crossing; +inf: none
  /// How far along the ray (from p + h·n) the blends looked: a patch whose ball misses the ray
  /// up to there cannot change this probe. +inf when nothing was hit.
  double reach = std::numeric_limits<double>::infinity();
};
/// How far along a ray its blend looked, given the samples it blended: the cut
/// t_cut = minᵢ(tᵢ + push(Rᵢ)) (core/slim.h) is at most the minimum over those samples.
double blend_reach(std::span<const SlimSample> blended, const SlimBlendOptions& blend);

/// blended: the SLIM samples of the counted crossing (cleared first). n: unit.
PointProbe probe_point(const ReferenceScene& scene, const TraceOptions& trace, const Eigen::Vector3d& p,
                       const Eigen::Vector3d& n, double h, double E, std::vector<SlimSample>* blended = nullptr);

/// The direction to measure a point along when its own normal is off: the mean normal of its
/// neighbourhood (the 12 nearest points) when those agree among themselves (|Σn| ≥ 0.9·12) and
/// the point's normal lies more than 30° from it — a sliver face in a fold of a mesh, a flipped
/// scan normal. Otherwise none, and the point is measured along its own normal only. The fitter
/// and evaluate_slim both measure min(along n, along this), so they report the same error.
std::optional<Eigen::Vector3d> neighbourhood_normal(const PointIndex& index, std::span<const Eigen::Vector3d> normals,
                                                    const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                                                    std::vector<Neighbour>& scratch);

/// probe_point along n, and along neighbourhood_normal when that exists and the first probe is
/// beyond E; the better of the two. Still beyond E: nearest_along_lines (core/reference.h), which
/// counts when it finds the surface within E (an upper bound of the Euclidean distance too).
/// other: set when a direction other than n counted.
PointProbe measure_point(const ReferenceScene& scene, const TraceOptions& trace, const PointIndex& index,
                         std::span<const Eigen::Vector3d> normals, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                         double h, double E, std::vector<SlimSample>* blended = nullptr, bool* other = nullptr);

struct SlimError {
  std::size_t points = 0;
  std::size_t misses = 0;       ///< rays that found no surface
  double max = 0;               ///< world units; +inf when misses > 0
  double rms = 0;               ///< over the points that were hit
  std::size_t worst = 0;        ///< index of the point with the largest error
  double probe_height = 0;      ///< h actually used
  std::vector<double> per_point;  ///< error per point (+inf for a miss), when asked for
  /// The blended surface's normal where each point's probe met it (core's blend of the patches'
  /// unit normals), against the point's normal: median, 99th percentile and largest angle,
  /// degrees, over the normal_points probes that counted a blend. Facets ("a hammered look":
  /// neighbouring patches crossing at an angle) show here while every point is within E.
  std::size_t normal_points = 0;
  double normal_p50_deg = 0, normal_p99_deg = 0, normal_max_deg = 0;
  std::size_t count_above(double e) const;  ///< needs per_point
};

/// Measures model against cloud (e.g. the fitted points, or held-out ones). Points without
/// normals get estimated ones (fit/normals.h). TBB-parallel over points.
/// \throws InvalidInput when the model has no SLIM patches or the cloud is empty.
SlimError evaluate_slim(const Model& model, const PointCloud& cloud, const SlimErrorOptions& options = {});

}  // namespace quadrix
