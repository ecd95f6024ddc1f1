#pragma once
/// Per-patch measured error of a SLIM model against points (the points side of the fit's
/// contract, attributed to patches): each point is probed against the blended surface as in
/// fit/evaluate.h, and its error counts for every patch that took part in its blend.
#include <cstddef>
#include <optional>
#include <vector>

#include "core/model.h"
#include "core/points_io.h"
#include "fit/evaluate.h"

namespace quadrix {

struct PatchErrors {
  /// Per Model::slims: the largest error of the points whose blend the patch entered (weight
  /// > 0), world units; empty for a patch that served no point.
  std::vector<std::optional<double>> per_patch;
  std::size_t points = 0;
  std::size_t misses = 0;  ///< points whose probe found no surface (attributed to no patch)
  double max = 0;          ///< over the patches' values
};

/// Measures every point of cloud against model (probe height and sheet passing as
/// evaluate_slim, options.keep_per_point ignored). TBB-parallel over points.
/// \throws InvalidInput when the model has no SLIM patches or the cloud is empty.
PatchErrors slim_patch_errors(const Model& model, const PointCloud& cloud, const SlimErrorOptions& options = {});

/// Stores errors.per_patch into the model's patches (SlimPatch::measured_error).
/// \throws InvalidInput when the sizes differ.
void set_measured_errors(Model& model, const PatchErrors& errors);

}  // namespace quadrix
