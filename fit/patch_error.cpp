#include "fit/patch_error.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/reference.h"
#include "core/slim.h"
#include "fit/normals.h"

namespace quadrix {

PatchErrors slim_patch_errors(const Model& model, const PointCloud& cloud, const SlimErrorOptions& options) {
  if (model.slims.empty()) throw InvalidInput("slim_patch_errors: the model has no SLIM patches");
  if (cloud.points.empty()) throw InvalidInput("slim_patch_errors: no points to measure");
  std::vector<Eigen::Vector3d> estimated;
  if (!cloud.has_normals()) estimated = estimate_normals(cloud.points).normals;
  else if (cloud.normals.size() != cloud.points.size())
    throw InvalidInput(fmt::format("slim_patch_errors: {} normals for {} points", cloud.normals.size(), cloud.points.size()));
  const auto& normals = cloud.has_normals() ? cloud.normals : estimated;

  // The probe height and sheet-passing E of evaluate_slim (fit/evaluate.h).
  double h = options.probe_height;
  double E_fit = 0;
  if (const auto e = metadata_number(model, "max_error_abs"); e && std::isfinite(*e)) E_fit = *e;
  if (!(h > 0)) h = 4.0 * E_fit;
  if (!(h > 0)) {
    Box3 box;
    for (const auto& p : cloud.points) box.extend(p);
    h = 5e-3 * box.diagonal();
  }
  const double E = E_fit > 0 && E_fit < h ? E_fit : 0.25 * h;
  const ReferenceScene scene(model);
  TraceOptions trace;
  trace.slim = slim_blend_of(model);
  const std::vector<double> heights = probe_heights(cloud.points, normals, h, options.surface);

  const std::size_t n = model.slims.size();
  // Per thread: the largest error per patch so far (−1: none).
  tbb::enumerable_thread_specific<std::vector<double>> local([n] { return std::vector<double>(n, -1.0); });
  tbb::enumerable_thread_specific<std::size_t> misses(0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.points.size(), 512), [&](const tbb::blocked_range<std::size_t>& r) {
    auto& worst = local.local();
    std::vector<SlimSample> blended;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const PointProbe probe = probe_point(scene, trace, cloud.points[i], normals[i].normalized(), heights[i], E, &blended);
      if (!std::isfinite(probe.error)) {
        ++misses.local();
        continue;
      }
      for (const SlimSample& s : blended)
        if (s.weight > 0 && s.index >= 0) worst[std::size_t(s.index)] = std::max(worst[std::size_t(s.index)], probe.error);
    }
  });
  PatchErrors out;
  out.points = cloud.points.size();
  for (const std::size_t m : misses) out.misses += m;
  std::vector<double> worst(n, -1.0);
  for (const auto& w : local)
    for (std::size_t k = 0; k < n; ++k) worst[k] = std::max(worst[k], w[k]);
  out.per_patch.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    if (worst[k] >= 0) {
      out.per_patch[k] = worst[k];
      out.max = std::max(out.max, worst[k]);
    }
  return out;
}

void set_measured_errors(Model& model, const PatchErrors& errors) {
  if (errors.per_patch.size() != model.slims.size())
    throw InvalidInput(fmt::format("set_measured_errors: {} values for {} SLIM patches", errors.per_patch.size(),
                                   model.slims.size()));
  for (std::size_t k = 0; k < model.slims.size(); ++k) model.slims[k].measured_error = errors.per_patch[k];
}

}  // namespace quadrix
