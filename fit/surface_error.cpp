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

}  // namespace

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
  out.has_holes_measure = o.holes && data.has_faces();
  std::vector<double> all;
  for (std::size_t v = 0; v < views.cameras.size(); ++v) {
    const Camera& cam = views.cameras[v];
    const std::vector<double>& hit_t = views.t[v];
    const int W = cam.width, H = cam.height;
    const std::size_t n = std::size_t(W) * H;
    std::vector<double> dist(n, -1.0);        // −1: surface missed the pixel
    std::vector<double> data_t(n, -1.0);      // −1: data missed the pixel
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 2), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < W; ++x) {
          const Ray ray = cam.pixel_ray(x + 0.5, y + 0.5);
          const std::size_t i = std::size_t(y) * W + x;
          if (hit_t[i] >= 0) dist[i] = data.distance(ray.at(hit_t[i]));
          // Data seen from behind (an open sheet's back) is not something the surface must show:
          // SLIM patches are culled from behind as well.
          bool front = false;
          if (out.has_holes_measure)
            if (const auto t = data.intersect(ray, 0.0, &front); t && front) data_t[i] = *t;
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
    const double pixel_angle = 2.0 * std::tan(cam.fov_y_deg * std::numbers::pi / 360.0) / H;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const std::size_t i = std::size_t(y) * W + x;
        if (data_t[i] < 0) continue;
        const int band = static_cast<int>(std::ceil(std::max(o.band_px, o.bound / (data_t[i] * pixel_angle))));
        bool interior = true;
        for (int dy = -band; dy <= band && interior; ++dy)
          for (int dx = -band; dx <= band && interior; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (dx * dx + dy * dy > band * band) continue;
            if (xx < 0 || yy < 0 || xx >= W || yy >= H || data_t[std::size_t(yy) * W + xx] < 0) interior = false;
          }
        if (!interior) continue;
        ++out.data_pixels;
        if (dist[i] < 0 && ++out.holes <= o.keep_hole_points) {
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
