#include "render/passes/chunks.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/morton.h"

namespace quadrix::render {

Chunks make_chunks(std::span<const Box3> boxes, const ChunkOptions& o) {
  Chunks c;
  const std::size_t n = boxes.size();
  if (n == 0) return c;
  std::vector<Eigen::Vector3d> centres(n);
  for (std::size_t i = 0; i < n; ++i) centres[i] = boxes[i].centre();
  c.order = morton_order(centres);
  const std::size_t size = std::max<std::size_t>(1, o.chunk_size);
  for (std::size_t s = 0; s < n; s += size) {
    const std::size_t e = std::min(n, s + size);
    Box3 box;
    for (std::size_t k = s; k < e; ++k) box.extend(boxes[c.order[k]]);
    c.first.push_back(static_cast<std::uint32_t>(s));
    c.count.push_back(static_cast<std::uint32_t>(e - s));
    c.boxes.push_back(box);
  }
  return c;
}

ChunkSelection select_chunks(const Chunks& chunks, const Camera& cam) {
  ChunkSelection sel;
  const Eigen::Matrix3d R = cam.view().topLeftCorner<3, 3>();
  const double ty = std::tan(0.5 * cam.fov_y_deg * std::numbers::pi / 180.0);
  const double tx = ty * double(cam.width) / cam.height;
  // Eye-space planes a·p ≤ 0 outside-positive: corners p with a·p > 0 lie outside.
  // Side planes through the eye: x − tx·(−z) ≤ 0 etc.; near: z + near ≤ 0; far: −z − far ≤ 0.
  std::vector<std::pair<double, std::uint32_t>> kept;
  kept.reserve(chunks.size());
  for (std::size_t c = 0; c < chunks.size(); ++c) {
    const Box3& b = chunks.boxes[c];
    int outside[6] = {0, 0, 0, 0, 0, 0};
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d w((k & 1) ? b.max.x() : b.min.x(), (k & 2) ? b.max.y() : b.min.y(),
                              (k & 4) ? b.max.z() : b.min.z());
      const Eigen::Vector3d p = R * (w - cam.eye);
      const double depth = -p.z();
      outside[0] += p.x() > tx * depth;
      outside[1] += -p.x() > tx * depth;
      outside[2] += p.y() > ty * depth;
      outside[3] += -p.y() > ty * depth;
      outside[4] += depth < cam.near_plane;
      outside[5] += depth > cam.far_plane;
    }
    if (std::find(std::begin(outside), std::end(outside), 8) != std::end(outside)) {
      ++sel.culled_chunks;
      sel.culled_primitives += chunks.count[c];
      continue;
    }
    const Eigen::Vector3d nearest = cam.eye.cwiseMax(b.min).cwiseMin(b.max);
    kept.emplace_back((nearest - cam.eye).squaredNorm(), static_cast<std::uint32_t>(c));
  }
  std::sort(kept.begin(), kept.end());
  sel.chunks.reserve(kept.size());
  for (const auto& k : kept) sel.chunks.push_back(k.second);
  return sel;
}

void PixelRect::extend(const PixelRect& o) {
  if (o.empty()) return;
  if (empty()) {
    *this = o;
    return;
  }
  x0 = std::min(x0, o.x0), y0 = std::min(y0, o.y0), x1 = std::max(x1, o.x1), y1 = std::max(y1, o.y1);
}

PixelRect box_pixels(const Box3& b, const Camera& cam) {
  const PixelRect all{0, 0, cam.width, cam.height};
  const Eigen::Matrix4d V = cam.view(), P = cam.projection();
  const Eigen::Matrix3d R = V.topLeftCorner<3, 3>();
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d w((k & 1) ? b.max.x() : b.min.x(), (k & 2) ? b.max.y() : b.min.y(),
                            (k & 4) ? b.max.z() : b.min.z());
    const Eigen::Vector3d p = R * (w - cam.eye);
    const double depth = -p.z();
    if (!(depth > cam.near_plane)) return all;
    const double px = (0.5 * P(0, 0) * p.x() / depth + 0.5) * cam.width;
    const double py = (0.5 * P(1, 1) * p.y() / depth + 0.5) * cam.height;
    x0 = std::min(x0, px), x1 = std::max(x1, px), y0 = std::min(y0, py), y1 = std::max(y1, py);
  }
  const auto clamp = [](double v, int hi) { return static_cast<int>(std::clamp(v, 0.0, double(hi))); };
  return {clamp(std::floor(x0) - 1, cam.width), clamp(std::floor(y0) - 1, cam.height),
          clamp(std::ceil(x1) + 2, cam.width), clamp(std::ceil(y1) + 2, cam.height)};
}

DepthTiles depth_tiles(std::span<const float> depth, int width, int height, int tile) {
  DepthTiles t;
  t.width = width, t.height = height, t.tile = tile;
  t.tiles_x = (width + tile - 1) / tile, t.tiles_y = (height + tile - 1) / tile;
  t.max_depth.assign(static_cast<std::size_t>(t.tiles_x) * t.tiles_y, 0.0f);
  for (int y = 0; y < height; ++y) {
    float* row = t.max_depth.data() + static_cast<std::size_t>(y / tile) * t.tiles_x;
    const float* d = depth.data() + static_cast<std::size_t>(y) * width;
    for (int x = 0; x < width; ++x) {
      // NaN (never written) counts as the far plane.
      const float v = d[x] == d[x] ? d[x] : 1.0f;
      row[x / tile] = std::max(row[x / tile], v);
    }
  }
  return t;
}

bool box_occluded(const Box3& b, const Camera& cam, const DepthTiles& t) {
  if (t.tiles_x == 0) return false;
  const Eigen::Matrix4d V = cam.view(), P = cam.projection();
  const Eigen::Matrix3d R = V.topLeftCorner<3, 3>();
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY, nearest = INFINITY;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d w((k & 1) ? b.max.x() : b.min.x(), (k & 2) ? b.max.y() : b.min.y(),
                            (k & 4) ? b.max.z() : b.min.z());
    const Eigen::Vector3d p = R * (w - cam.eye);
    const double depth = -p.z();
    if (!(depth > cam.near_plane)) return false;
    const double px = (0.5 * P(0, 0) * p.x() / depth + 0.5) * t.width;
    const double py = (0.5 * P(1, 1) * p.y() / depth + 0.5) * t.height;
    x0 = std::min(x0, px), x1 = std::max(x1, px), y0 = std::min(y0, py), y1 = std::max(y1, py);
    nearest = std::min(nearest, 0.5 * (P(2, 2) * p.z() + P(2, 3)) / depth + 0.5);
  }
  // Pixels whose centres the bound may cover, one more on each side for rasterisation rules.
  const int ix0 = std::max(0, static_cast<int>(std::floor(x0)) - 1);
  const int ix1 = std::min(t.width - 1, static_cast<int>(std::ceil(x1)) + 1);
  const int iy0 = std::max(0, static_cast<int>(std::floor(y0)) - 1);
  const int iy1 = std::min(t.height - 1, static_cast<int>(std::ceil(y1)) + 1);
  if (ix0 > ix1 || iy0 > iy1) return true;  // covers no pixel
  // A margin of a few float steps of the depth buffer.
  const double limit = nearest - 1e-6;
  for (int ty = iy0 / t.tile; ty <= iy1 / t.tile; ++ty)
    for (int tx = ix0 / t.tile; tx <= ix1 / t.tile; ++tx)
      if (!(double(t.max_depth[static_cast<std::size_t>(ty) * t.tiles_x + tx]) < limit)) return false;
  return true;
}

}  // namespace quadrix::render
