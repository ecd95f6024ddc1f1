#include "fit/evaluate.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/reference.h"
#include "fit/blend_probe.h"
#include "fit/local_fit.h"
#include "fit/normals.h"

namespace quadrix {
namespace {

// SLIM weight (DESIGN §2): exp(−8r²) for r < ½, 16e⁻²(1 − r)⁴ for ½ ≤ r ≤ 1, 0 beyond.
double weight(double r) {
  if (r < 0.5) return std::exp(-8.0 * r * r);
  if (r <= 1.0) {
    const double s = 1.0 - r;
    return 16.0 * std::exp(-2.0) * s * s * s * s;
  }
  return 0.0;
}

std::vector<Eigen::Vector3d> centres_of(const Model& m) {
  std::vector<Eigen::Vector3d> c;
  c.reserve(m.slims.size());
  for (const auto& s : m.slims) c.push_back(s.centre);
  return c;
}

}  // namespace

BlendProbe::BlendProbe(const Model& model)
    : model_(&model), centres_(centres_of(model)), index_(std::span<const Eigen::Vector3d>(centres_)) {
  for (const auto& s : model.slims) max_radius_ = std::max(max_radius_, s.radius);
}

double BlendProbe::probe(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double h, double bound,
                         std::vector<int>* culprits) const {
  struct Sample {
    double t, w, R;
    int i;
  };
  thread_local std::vector<Neighbour> near;
  thread_local std::vector<Sample> samples;
  samples.clear();
  // Samples that can be blended when the first hit is near p lie within 1.5·Rmax + 2h of p.
  index_.radius(p, 1.5 * max_radius_ + 2.0 * h, near);
  const Eigen::Vector3d origin = p + h * n;
  const double inf = std::numeric_limits<double>::infinity();
  for (const auto& [i, d2] : near) {
    const SlimPatch& s = model_->slims[i];
    const Eigen::Vector3d o = (origin - s.centre) / s.radius;
    // Quick reject: the line misses the ball.
    const double along = -o.dot(n);
    if (o.squaredNorm() - along * along > 1.0) continue;
    double t;
    if (!s.clip) {
      const auto hit = first_front_hit(s.local, o, -n, 0.0, inf);
      if (!hit) continue;
      t = *hit;
    } else {
      // With a clip plane, the near root may be clipped away and the far one kept ([Stoll06] eq. 15).
      double tmin = 0.0;
      bool found = false;
      for (int k = 0; k < 2 && !found; ++k) {
        const auto hit = first_front_hit(s.local, o, -n, tmin, inf);
        if (!hit) break;
        if (s.clip->keeps(o - *hit * n)) {
          t = *hit;
          found = true;
        }
        tmin = *hit;
      }
      if (!found) continue;
    }
    const double w = weight((o - t * n).norm());
    if (w > 0) samples.push_back({t * s.radius, w, s.radius, int(i)});
  }
  if (samples.empty()) {
    if (culprits)
      for (const auto& [i, d2] : near)
        if (d2 <= model_->slims[i].radius * model_->slims[i].radius) culprits->push_back(int(i));
    return inf;
  }
  double cut = inf;
  for (const auto& s : samples) cut = std::min(cut, s.t + 0.5 * s.R);
  double sw = 0, st = 0;
  for (const auto& s : samples)
    if (s.t <= cut) {
      sw += s.w;
      st += s.w * s.t;
      if (culprits && std::abs(s.t - h) > bound) culprits->push_back(s.i);
    }
  return std::abs(st / sw - h);
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
    if (auto it = model.metadata.find("max_error_abs"); it != model.metadata.end()) h = 4.0 * std::stod(it->second);
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
  const TraceOptions trace;
  const double inf = std::numeric_limits<double>::infinity();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.points, 512), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Eigen::Vector3d n = normals[i].normalized();
      const Ray ray{cloud.points[i] + h * n, -n};
      const auto hit = scene.trace(ray, 0.0, inf, trace);
      out.per_point[i] = hit && hit->kind == PrimitiveKind::slim ? std::abs(hit->t - h) : inf;
    }
  });
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
