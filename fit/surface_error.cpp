#include "fit/surface_error.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/camera.h"
#include "core/reference.h"
#include "core/slim.h"

namespace quadrix {
namespace {

std::vector<Camera> views_of(const Box3& box, const SurfaceErrorOptions& o) {
  std::vector<std::pair<double, double>> dirs;  // azimuth, elevation in degrees
  const double corner = std::atan(1.0 / std::numbers::sqrt2) * 180.0 / std::numbers::pi;
  for (const double el : {corner, -corner})
    for (int k = 0; k < 4; ++k) dirs.push_back({45.0 + 90.0 * k, el});
  for (const auto& d : std::initializer_list<std::pair<double, double>>{{0, 0}, {90, 0}, {180, 0}, {270, 0}, {0, 89}, {0, -89}})
    dirs.push_back(d);
  std::vector<Camera> cams;
  for (int v = 0; v < o.views; ++v) {
    const auto [az, el] = dirs[static_cast<std::size_t>(v) % dirs.size()];
    cams.push_back(frame_box(box, {.azimuth_deg = az, .elevation_deg = el, .width = o.resolution, .height = o.resolution}));
  }
  return cams;
}

// What the data shows along a ray: its first front-facing crossing; the crossing of that sheet
// that stands for it; the next crossing of another sheet, when the surface's hit (t_surface ≥ 0)
// lies more than the bound behind the first (the walk stops past it); and whether the ray only
// grazes the data there: it leaves the solid again at that next crossing, never deeper inside
// than the bound (a ridge seen edge-on, in front of another part: a surface within the bound of
// the data may pass just under it). Data seen from behind (an open sheet's back) is not
// something the surface must show (SLIM patches are culled from behind as well): nothing.
// A mesh's first crossing stands for its sheet and its next crossing is the next sheet. A cloud's
// tangent discs overlap, and the one nearest its own point is the surface's best estimate (the
// first one in front is the one that stands off the most). Each disc lies off the next by up to
// their radii along the normal, turned by up to 90° where the sampling is coarse for the
// curvature (the kitten at 1e-3: discs 22E wide), so a crossing within the bound or the two
// discs' radii of the first along its normal is the same sheet unless it faces the other way (a
// thin part's far side, a body's back wall seen from inside).
// The walk through a cloud's sheet gives up after kMaxCrossings discs (a ray along widened discs,
// a scanner's lines): such a ray is not sure enough to count.
constexpr int kMaxCrossings = 64;
struct DataView {
  DataSurface::RayHit first, best;
  std::optional<DataSurface::RayHit> next_sheet;
  bool grazed = false;
  bool walked = true;  // the sheet's crossings were all seen (within kMaxCrossings)
};
std::optional<DataView> view_data(const DataSurface& data, const Ray& ray, double bound, double t_surface) {
  const auto first = data.first_hit(ray);
  if (!first || !first->front) return std::nullopt;
  DataView v{*first, *first, std::nullopt};
  const bool discs = first->reach > 0;
  const bool next = bound > 0 && t_surface > first->t + bound;
  const double tmax = next ? t_surface + bound : std::numeric_limits<double>::infinity();
  if (!discs && !next) return v;
  double from = first->t;
  for (int k = 0;; ++k) {
    if (k == kMaxCrossings) {
      v.walked = false;
      break;
    }
    const auto hit = data.first_hit(ray, from * (1 + 1e-12) + 1e-12, tmax);
    if (!hit) break;
    const double offset = (hit->t - first->t) * std::abs(first->normal.dot(ray.dir));
    if (!discs || hit->normal.dot(first->normal) <= -0.5 || offset > std::max(bound, first->reach + hit->reach)) {
      v.next_sheet = hit;
      break;
    }
    if (hit->front && hit->from_sample * v.best.spacing < v.best.from_sample * hit->spacing) v.best = *hit;
    from = hit->t;
  }
  // Grazed: the ray leaves the solid again, never deeper inside than the bound (a ridge or a bump
  // seen edge-on). A thin part crossed within 60° of its normal, from one side to the opposite one
  // (normals over 145° apart), is not grazed: holes through it count.
  const bool across_thin = v.next_sheet && std::abs(first->normal.dot(ray.dir)) >= 0.5 &&
                           first->normal.dot(v.next_sheet->normal) < -0.8;
  if (v.next_sheet && !v.next_sheet->front && !across_thin)
    v.grazed = data.distance(ray.at(0.5 * (v.best.t + v.next_sheet->t)), 2.0 * bound) <= bound;
  return v;
}

}  // namespace

RayVerdict judge_ray(const DataSurface& data, const Ray& ray, double t_surface, double bound) {
  RayVerdict out;
  const auto view = view_data(data, ray, bound, t_surface);
  if (!view) return out;
  out.data_t = view->best.t;
  out.reach = view->first.reach;
  // A cloud's ray counts only where some disc of its first sheet there holds it within its own
  // point's spacing: farther out a disc stands off the surface (past an ear's rim over the head
  // behind it, the kitten's discs at 1e-3 reach 22E), and neither a hole nor a view through is
  // sure.
  if (view->best.from_sample > view->best.spacing || view->grazed || !view->walked) return out;
  out.counts = true;
  // Behind the data by more than the bound, nearer the data's next sheet than the first: seen
  // through a slit (the far side of a head through its mouth, a groove's lower lip through its
  // upper one). A cloud's next sheet counts only where the ray leaves the solid there (seen from
  // behind): its discs bridge a concave crease in front of the surface, which then lies behind
  // them, facing the view (the kitten's paw against its body at 1e-3, points 19E apart: the fit's
  // surface 76E behind the discs' bridge).
  const auto& next = view->next_sheet;
  out.through = bound > 0 && t_surface > view->best.t + bound && next && (view->first.reach == 0 || !next->front) &&
                t_surface > 0.5 * (view->best.t + next->t);
  out.hole = t_surface < 0 || out.through;
  return out;
}

SurfaceViews render_surface_views(const TraceFn& trace, const Box3& data_box, const SurfaceErrorOptions& o) {
  SurfaceViews out;
  out.cameras = views_of(data_box, o);
  for (const Camera& cam : out.cameras) {
    const int W = cam.width, H = cam.height;
    std::vector<double>& hit_t = out.t.emplace_back(std::size_t(W) * H, -1.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 2), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < W; ++x)
          if (const auto t = trace(cam.pixel_ray(x + 0.5, y + 0.5))) hit_t[std::size_t(y) * W + x] = *t;
    });
  }
  return out;
}

SurfaceError measure_surface_error(const TraceFn& trace, const DataSurface& data, const Box3& data_box,
                                   const SurfaceErrorOptions& o) {
  return measure_surface_error(render_surface_views(trace, data_box, o), data, o);
}

SurfaceError measure_surface_error(const SurfaceViews& views, const DataSurface& data, const SurfaceErrorOptions& o) {
  SurfaceError out;
  out.has_holes_measure = o.holes;
  std::vector<double> all;
  for (std::size_t v = 0; v < views.cameras.size(); ++v) {
    const Camera& cam = views.cameras[v];
    const std::vector<double>& hit_t = views.t[v];
    const int W = cam.width, H = cam.height;
    const std::size_t n = std::size_t(W) * H;
    std::vector<double> dist(n, -1.0);        // −1: surface missed the pixel
    std::vector<double> data_t(n, -1.0);      // −1: data missed the pixel
    std::vector<double> data_reach(n, 0.0);   // the hit disc's radius (points), else 0
    std::vector<std::uint8_t> through(n, 0);  // the surface shows another sheet than the data's first
    std::vector<std::uint8_t> counts(n, 0);   // a data pixel sure enough to count (mesh: all)
    const double pixel_angle = 2.0 * std::tan(cam.fov_y_deg * std::numbers::pi / 360.0) / H;
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 2), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < W; ++x) {
          const Ray ray = cam.pixel_ray(x + 0.5, y + 0.5);
          const std::size_t i = std::size_t(y) * W + x;
          if (hit_t[i] >= 0) dist[i] = data.distance(ray.at(hit_t[i]));
          if (!out.has_holes_measure) continue;
          const RayVerdict v = judge_ray(data, ray, hit_t[i], o.bound);
          if (!(v.data_t >= 0)) continue;
          data_t[i] = v.data_t;
          data_reach[i] = v.reach;
          // The edge of a sheet is a silhouette of it, whatever lies behind in view.
          counts[i] = v.counts && !(o.rim_band && data.near_open_boundary(ray.at(v.data_t),
                                                                         std::max({o.band_px * v.data_t * pixel_angle, o.bound, v.reach})));
          through[i] = v.through;
        }
    });
    for (std::size_t i = 0; i < n; ++i) {
      if (dist[i] < 0) continue;
      all.push_back(dist[i]);
      if (o.bound > 0 && dist[i] > o.bound && out.beyond_points.size() < o.keep_beyond_points) {
        const Ray ray = cam.pixel_ray(double(i % W) + 0.5, double(i / W) + 0.5);
        out.beyond_points.push_back({ray.at(hit_t[i]), dist[i]});
      }
    }
    if (!out.has_holes_measure) continue;
    // Holes: data pixels whose neighbourhood (the band) is all data, left empty by the surface.
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const std::size_t i = std::size_t(y) * W + x;
        if (!counts[i]) continue;
        // A cloud's discs reach up to their radius past its silhouette.
        const double reach = std::max(o.bound, data_reach[i]);
        const int band = static_cast<int>(std::ceil(std::max(o.band_px, reach / (data_t[i] * pixel_angle))));
        bool interior = true;
        for (int dy = -band; dy <= band && interior; ++dy)
          for (int dx = -band; dx <= band && interior; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (dx * dx + dy * dy > band * band) continue;
            if (xx < 0 || yy < 0 || xx >= W || yy >= H || data_t[std::size_t(yy) * W + xx] < 0) interior = false;
          }
        if (!interior) continue;
        ++out.data_pixels;
        out.see_through += through[i];
        if ((dist[i] < 0 || through[i]) && ++out.holes <= o.keep_hole_points) {
          const Ray ray = cam.pixel_ray(x + 0.5, y + 0.5);
          out.hole_points.push_back(ray.at(data_t[i]));
          out.hole_dirs.push_back(ray.dir);
        }
      }
  }
  out.pixels = all.size();
  if (!all.empty()) {
    double sum = 0;
    for (const double d : all) {
      sum += d * d;
      if (o.bound > 0 && d > o.bound) ++out.beyond;
    }
    out.rms = std::sqrt(sum / double(all.size()));
    const auto at = [&](double q) {
      const std::size_t k = std::min(all.size() - 1, static_cast<std::size_t>(std::floor(q * double(all.size() - 1))));
      std::nth_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(k), all.end());
      return all[k];
    };
    out.p99 = at(0.99);
    out.p999 = at(0.999);
    out.max = *std::max_element(all.begin(), all.end());
    out.share_beyond = double(out.beyond) / double(all.size());
  }
  out.hole_share = out.data_pixels ? double(out.holes) / double(out.data_pixels) : 0.0;
  return out;
}

SurfaceError measure_surface_error(const Model& model, const DataSurface& data, const Box3& data_box,
                                   const SurfaceErrorOptions& options) {
  const ReferenceScene scene(model);
  TraceOptions trace;
  trace.slim = slim_blend_of(model);
  return measure_surface_error(
      [&](const Ray& ray) -> std::optional<double> {
        if (const auto hit = scene.trace(ray, 0.0, std::numeric_limits<double>::infinity(), trace)) return hit->t;
        return std::nullopt;
      },
      data, data_box, options);
}

}  // namespace quadrix
