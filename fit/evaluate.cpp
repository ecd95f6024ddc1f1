#include "fit/evaluate.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/reference.h"
#include "core/slim.h"
#include "fit/normals.h"

namespace quadrix {
std::vector<double> probe_heights(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                                  double h, const DataSurface* surface) {
  std::vector<double> out(points.size(), h);
  if (!surface || !surface->has_faces()) return out;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 512), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Eigen::Vector3d n = normals[i].normalized();
      // The next sheet facing back at the point (another part of the body); sheets crossed from
      // behind (the point's own, when it lies a little inside the data) are passed through.
      double from = 1e-3 * h;
      for (int k = 0; k < 8 && from < 2.0 * h; ++k) {
        bool front = false;
        const auto t = surface->intersect(Ray{points[i], n}, from, &front, 2.0 * h);  // farther: h stays
        if (!t) break;
        if (front) {
          out[i] = std::min(h, 0.5 * *t);
          break;
        }
        from = *t * (1 + 1e-9) + 1e-12 * h;
      }
    }
  });
  return out;
}

double blend_reach(std::span<const SlimSample> blended, const SlimBlendOptions& blend) {
  double reach = std::numeric_limits<double>::infinity();
  for (const auto& s : blended) reach = std::min(reach, s.hit.t + blend.push(s.radius, s.max_push));
  return reach;
}

PointProbe probe_point(const ReferenceScene& scene, const TraceOptions& trace, const Eigen::Vector3d& p,
                       const Eigen::Vector3d& n, double h, double E, std::vector<SlimSample>* blended) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Ray ray{p + h * n, -n};
  thread_local std::vector<SlimSample> samples;
  PointProbe out;
  if (blended) blended->clear();
  double from = 0.0;
  for (int k = 0; k < 5; ++k) {
    const auto hit = scene.trace(ray, from, kInf, trace, &samples);
    if (!hit || hit->kind != PrimitiveKind::slim) break;
    const double reach = blend_reach(samples, trace.slim);
    out.reach = k == 0 ? reach : std::max(out.reach, reach);
    if (const double e = std::abs(hit->t - h); !(e >= out.error)) {
      out.error = e;
      if (blended) *blended = samples;
    }
    if (hit->t >= h - E) break;  // at or below p + E·n: nothing nearer lies further down
    from = hit->t * (1.0 + 1e-12) + 1e-9 * E;
  }
  return out;
}

std::optional<Eigen::Vector3d> neighbourhood_normal(const PointIndex& index, std::span<const Eigen::Vector3d> normals,
                                                    const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                                                    std::vector<Neighbour>& scratch) {
  constexpr std::size_t kNeighbours = 12;
  index.nearest(p, kNeighbours, scratch);
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (const auto& [j, d2] : scratch) m += normals[j];
  if (!(m.norm() >= 0.9 * double(scratch.size())) || scratch.size() < kNeighbours) return std::nullopt;
  m.normalize();
  if (m.dot(n) >= std::cos(30.0 * std::numbers::pi / 180.0)) return std::nullopt;
  return m;
}

PointProbe measure_point(const ReferenceScene& scene, const TraceOptions& trace, const PointIndex& index,
                         std::span<const Eigen::Vector3d> normals, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                         double h, double E, std::vector<SlimSample>* blended, bool* other) {
  if (other) *other = false;
  PointProbe probe = probe_point(scene, trace, p, n, h, E, blended);
  if (probe.error <= E) return probe;
  thread_local std::vector<Neighbour> near;
  thread_local std::vector<SlimSample> again_blended;
  if (const auto m = neighbourhood_normal(index, normals, p, n, near)) {
    const PointProbe again = probe_point(scene, trace, p, *m, h, E, blended ? &again_blended : nullptr);
    if (again.error < probe.error) {
      if (other) *other = true;
      if (blended) blended->swap(again_blended);
      probe = {again.error, std::max(probe.reach, again.reach)};
      if (probe.error <= E) return probe;
    }
  }
  // Still beyond E: the surface may lie at a slant to both directions (a folded face of a
  // decimated mesh, its normal along the surface: 10E along it and 0.04E away, dragon_10k at
  // 1e-2). Any drawn point along any line through p bounds its distance from above.
  // Counted only within E: beyond it the probe's own blended samples name the patches at fault.
  if (const double d = nearest_along_lines(scene, trace, p, n, E, E); d >= 0 && d <= E) {
    if (other) *other = true;
    if (blended) blended->clear();
    probe.error = d;
  }
  return probe;
}

std::size_t SlimError::count_above(double e) const {
  return std::size_t(std::count_if(per_point.begin(), per_point.end(), [e](double x) { return x > e; }));
}

SlimError evaluate_slim(const Model& model, const PointCloud& cloud, const SlimErrorOptions& options) {
  if (model.slims.empty()) throw InvalidInput("evaluate_slim: the model has no SLIM patches");
  if (cloud.points.empty()) throw InvalidInput("evaluate_slim: no points to measure");
  std::vector<Eigen::Vector3d> estimated;
  if (!cloud.has_normals()) estimated = estimate_normals(cloud.points).normals;
  else if (cloud.normals.size() != cloud.points.size())
    throw InvalidInput(fmt::format("evaluate_slim: {} normals for {} points", cloud.normals.size(), cloud.points.size()));
  const auto& normals = cloud.has_normals() ? cloud.normals : estimated;

  SlimError out;
  out.points = cloud.points.size();
  double h = options.probe_height;
  if (!(h > 0)) {
    if (const auto e = metadata_number(model, "max_error_abs"); e && std::isfinite(*e)) h = 4.0 * *e;
    if (!(h > 0)) {
      Box3 box;
      for (const auto& p : cloud.points) box.extend(p);
      h = 5e-3 * box.diagonal();
    }
  }
  out.probe_height = h;
  out.per_point.assign(out.points, 0.0);
  // The core's reference ray caster: the same per-ray blend every renderer is tested against.
  const ReferenceScene scene(model);
  TraceOptions trace;
  trace.slim = slim_blend_of(model);
  const std::vector<double> heights = probe_heights(cloud.points, normals, h, options.surface);
  // Sheets crossed more than E above a point are passed (probe_point): the fit's E, else h/4.
  double E = 0.25 * h;
  if (const auto e = metadata_number(model, "max_error_abs"); e && *e > 0 && *e < h) E = *e;
  std::vector<Eigen::Vector3d> unit(normals.size());
  for (std::size_t i = 0; i < normals.size(); ++i) unit[i] = normals[i].normalized();
  const PointIndex index{std::span<const Eigen::Vector3d>(cloud.points)};
  // The blended surface's normal where each point's probe counted it, against the point's own
  // normal (−1: no blend to compare, e.g. a probe settled along another line).
  std::vector<double> angle(out.points, -1.0);
  const auto order = index.order();  // visited in Morton order (PointIndex::order)
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.points, 512), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<SlimSample> blended;
    for (std::size_t o = r.begin(); o != r.end(); ++o) {
      const std::size_t i = order[o];
      out.per_point[i] = measure_point(scene, trace, index, unit, cloud.points[i], unit[i], heights[i], E, &blended).error;
      if (!std::isfinite(out.per_point[i]) || blended.empty()) continue;
      if (const auto b = blend_slim_samples(blended, trace.slim))
        angle[i] = std::acos(std::clamp(b->normal.dot(unit[i]), -1.0, 1.0)) * 180.0 / std::numbers::pi;
    }
  });
  std::erase_if(angle, [](double a) { return a < 0; });
  out.normal_points = angle.size();
  if (!angle.empty()) {
    const auto at = [&](double q) {
      const auto k = std::min(angle.size() - 1, static_cast<std::size_t>(q * double(angle.size())));
      std::nth_element(angle.begin(), angle.begin() + std::ptrdiff_t(k), angle.end());
      return angle[k];
    };
    out.normal_p50_deg = at(0.5);
    out.normal_p99_deg = at(0.99);
    out.normal_max_deg = *std::max_element(angle.begin(), angle.end());
  }
  double sum = 0;
  std::size_t hits = 0;
  for (std::size_t i = 0; i < out.points; ++i) {
    const double e = out.per_point[i];
    if (std::isinf(e)) ++out.misses;
    else {
      sum += e * e;
      ++hits;
    }
    if (e > out.per_point[out.worst]) out.worst = i;
  }
  out.max = out.per_point[out.worst];
  out.rms = hits ? std::sqrt(sum / double(hits)) : 0.0;
  if (!options.keep_per_point) out.per_point.clear();
  return out;
}

}  // namespace quadrix
