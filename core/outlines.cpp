#include "core/outlines.h"

#include <cmath>
#include <numbers>

#include "core/error.h"

namespace quadrix {

std::vector<std::uint8_t> detect_outlines(const OutlineInput& in, const OutlineOptions& o) {
  if (in.width < 1 || in.height < 1 || !in.coverage || !in.depth || !in.normal)
    throw InvalidInput("outline detection: empty G-buffer");
  const int w = in.width, h = in.height;
  std::vector<std::uint8_t> edge(static_cast<std::size_t>(w) * h, 0);
  const double footprint = 2.0 * std::tan(0.5 * in.fov_y_deg * std::numbers::pi / 180.0) / h;
  const double min_gap = o.depth_gap * in.scene_radius;
  const double cos_crease = std::cos(o.crease_deg * std::numbers::pi / 180.0);
  const auto at = [w](int x, int y) { return static_cast<std::size_t>(y) * w + x; };
  const auto covered = [&](int x, int y) { return x >= 0 && y >= 0 && x < w && y < h && in.coverage[at(x, y)] != 0; };
  const auto inside = [&](int x, int y) { return x >= 0 && y >= 0 && x < w && y < h; };
  constexpr int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = at(x, y);
      bool is_edge = false;
      if (!in.coverage[i]) continue;  // lines lie on the surface side of silhouettes
      for (int k = 0; k < 4 && !is_edge; ++k)
        is_edge = inside(x + dx[k], y + dy[k]) && !covered(x + dx[k], y + dy[k]);
      const double d0 = in.depth[i];
      const double gap_limit = std::max(min_gap, o.depth_pixels * d0 * footprint);
      for (int axis = 0; axis < 2 && !is_edge; ++axis) {
        const int ax = axis == 0, ay = axis == 1;
        if (!covered(x - ax, y - ay) || !covered(x + ax, y + ay)) continue;
        const double wa = 1.0 / in.depth[at(x - ax, y - ay)], wb = 1.0 / in.depth[at(x + ax, y + ay)];
        const double predicted = 2.0 / (wa + wb);
        is_edge = predicted - d0 > gap_limit;  // the nearer side of a step only: 1-pixel lines
      }
      const Eigen::Vector3f& n = in.normal[i];
      for (int k = 0; k < 4 && !is_edge; k += 2)  // +x and +y: one side of a crease
        if (covered(x + dx[k], y + dy[k])) is_edge = n.dot(in.normal[at(x + dx[k], y + dy[k])]) < cos_crease;
      edge[i] = is_edge;
    }
  return edge;
}

}  // namespace quadrix
