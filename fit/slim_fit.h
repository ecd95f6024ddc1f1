#pragma once
/// SLIM fitting (Ohtake, Belyaev, Alexa 2005; DESIGN §2, issue 4): sphere-bounded local quadrics
/// fitted to an oriented point cloud so that every point lies within a bound E of the blended
/// surface the renderer shows.
#include <cstddef>
#include <cstdint>

#include "core/model.h"
#include "core/points_io.h"

namespace quadrix {

struct SlimFitOptions {
  /// Error bound E, relative to the bounding-box diagonal of the points (absolute when
  /// max_error_is_absolute). Both the per-patch Taubin distance |g|/‖∇g‖ and the blended
  /// surface's distance along each point's normal are kept ≤ E.
  double max_error = 1e-3;
  bool max_error_is_absolute = false;
  /// μ: weight of the normal term ‖∇g(u) − n‖² against g(u)² in the local least squares
  /// (local coordinates u = (x − c)/R, so both terms are dimensionless).
  double normal_weight = 0.01;
  /// A ball needs at least this many points for a general quadric; sparser balls use the
  /// height-function fallback.
  std::size_t min_points = 12;
  /// Candidate centres: this fraction of the points (at least min_candidates, at most all),
  /// drawn at random; uncovered points become candidates later as needed.
  double candidate_fraction = 0.12;
  std::size_t min_candidates = 400;
  std::size_t max_candidates = 8000;
  /// Support radius search: geometric growth by this factor, then this many bisection steps.
  double radius_growth = 2.0;
  int bisection_steps = 3;
  /// At most this many points of a ball enter its least squares (every point is still checked).
  std::size_t max_fit_points = 200;
  /// While searching R, at most this many points of a ball (evenly strided) are checked; the
  /// final verification against the blended surface checks every point and repairs.
  std::size_t max_check_points = 3000;
  /// Probe height h for the blended-surface check, in units of E (rays start at p + h·n).
  double probe_factor = 4.0;
  /// Rounds of verification against the blended surface and repair of the patches at fault.
  int repair_rounds = 6;
  /// Sharp features (issue 4 item 2): where a ball's fit fails and the normals in it split into
  /// two clusters more than sharp_angle_deg apart, the patch fits the cluster of its centre
  /// only and gets a clip plane (SlimPatch::clip) between the two sheets.
  bool sharp = false;
  double sharp_angle_deg = 30.0;
  /// Neighbours for normal estimation when the cloud has no normals (fit/normals.h).
  std::size_t normal_neighbours = 16;
  std::uint64_t seed = 1;
};

struct SlimFitStats {
  std::size_t points = 0;
  std::size_t candidates = 0;        ///< candidate balls evaluated
  std::size_t patches = 0;           ///< balls in the model
  std::size_t patches_before_pruning = 0;
  std::size_t height_patches = 0;    ///< patches using the height-function fallback
  std::size_t unbounded_patches = 0; ///< patches whose smallest ball still exceeded E (noise)
  std::size_t clipped_patches = 0;   ///< patches with a clip plane (--sharp)
  bool normals_estimated = false;
  double max_error_abs = 0;          ///< E in world units
  double diagonal = 0;               ///< bounding-box diagonal of the points
  double max_taubin = 0, rms_taubin = 0;  ///< per-patch Taubin error over each ball's points, world units
  double max_blend = 0, rms_blend = 0;    ///< blended surface vs every point (fit/evaluate.h), world units
  std::size_t blend_failures = 0;    ///< points still farther than E from the blended surface
  int repair_rounds = 0;
  // Wall-clock seconds per stage.
  double time_normals = 0, time_candidates = 0, time_cover = 0, time_verify = 0, time_total = 0;
};

struct SlimFitResult {
  Model model;  ///< slims + metadata (E, measured errors, counts, times)
  SlimFitStats stats;
};

/// Fits a SLIM surface to cloud (points in world units; normals optional, outward, unit —
/// estimated with fit/normals.h when absent). kd-tree, candidate centres among the points, per
/// candidate the largest support radius whose local quadric keeps the error ≤ E, greedy
/// covering (a point is covered within ½R of a chosen centre), pruning of redundant balls, then
/// verification against the blended surface and repair (TBB-parallel throughout).
/// \throws InvalidInput for fewer than 10 points, non-finite coordinates or normals, a normal
///         count that differs from the point count, zero normals, coincident or coplanar points,
///         or bad options.
SlimFitResult fit_slim(const PointCloud& cloud, const SlimFitOptions& options = {});

}  // namespace quadrix
