#pragma once
// Comparing a GL G-buffer with the CPU reference: coverage away from silhouettes, depth and
// normal errors where both are covered.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/reference.h"
#include "render/renderer.h"

namespace quadrix::testing_gl {

struct Comparison {
  double coverage_agreement = 0;  // outside the 1-pixel silhouette band
  double depth_p99 = 0;           // relative to the reference's depth range
  double normal_median_deg = 0;
  double normal_p99_deg = 0;
  int covered = 0;
  int compared = 0;
};

inline bool near_silhouette(const std::vector<std::uint8_t>& m, int w, int h, int x, int y) {
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
      if (m[yy * w + xx] != m[y * w + x]) return true;
    }
  return false;
}

inline Comparison compare(const ReferenceImage& ref, const render::GBuffer& gl) {
  Comparison c;
  const int w = ref.width, h = ref.height;
  float dmin = INFINITY, dmax = -INFINITY;
  for (std::size_t i = 0; i < ref.depth.size(); ++i)
    if (ref.coverage[i]) dmin = std::min(dmin, ref.depth[i]), dmax = std::max(dmax, ref.depth[i]);
  std::vector<double> depth_err, normal_err;
  int agree = 0, counted = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      c.covered += ref.coverage[i];
      if (near_silhouette(ref.coverage, w, h, x, y)) continue;
      ++counted;
      agree += ref.coverage[i] == gl.coverage[i];
      if (!(ref.coverage[i] && gl.coverage[i])) continue;
      // A single glyph's depth range can be tiny: relative to the depth itself where larger.
      const double range = std::max(double(dmax - dmin), 1e-3 * double(dmax));
      depth_err.push_back(std::abs(double(gl.depth[i]) - ref.depth[i]) / std::max(1e-30, range));
      const double cosang = std::clamp(double(gl.normal[i].normalized().dot(ref.normal[i])), -1.0, 1.0);
      normal_err.push_back(std::acos(cosang) * 180.0 / std::numbers::pi);
    }
  c.compared = counted;
  c.coverage_agreement = counted ? double(agree) / counted : 0;
  if (!depth_err.empty()) {
    std::sort(depth_err.begin(), depth_err.end());
    c.depth_p99 = depth_err[depth_err.size() * 99 / 100];
    std::sort(normal_err.begin(), normal_err.end());
    c.normal_median_deg = normal_err[normal_err.size() / 2];
    c.normal_p99_deg = normal_err[normal_err.size() * 99 / 100];
  }
  return c;
}

}  // namespace quadrix::testing_gl
