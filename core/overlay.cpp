#include "core/overlay.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix {
namespace {

// A 3×5 pixel font for the labels: each row a 3-bit pattern, top row first (bit 2 = left).
struct Glyph5 {
  char c;
  std::array<std::uint8_t, 5> rows;
};
constexpr std::array<Glyph5, 15> kFont = {{{'0', {7, 5, 5, 5, 7}},
                                           {'1', {2, 6, 2, 2, 7}},
                                           {'2', {7, 1, 7, 4, 7}},
                                           {'3', {7, 1, 7, 1, 7}},
                                           {'4', {5, 5, 7, 1, 1}},
                                           {'5', {7, 4, 7, 1, 7}},
                                           {'6', {7, 4, 7, 5, 7}},
                                           {'7', {7, 1, 1, 1, 1}},
                                           {'8', {7, 5, 7, 5, 7}},
                                           {'9', {7, 5, 7, 1, 7}},
                                           {'.', {0, 0, 0, 0, 2}},
                                           {'-', {0, 0, 7, 0, 0}},
                                           {'+', {0, 2, 7, 2, 0}},
                                           {'e', {0, 7, 7, 4, 7}},
                                           {' ', {0, 0, 0, 0, 0}}}};

void put(Image8& img, int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
  std::uint8_t* p = img.pixel(x, y);
  p[0] = c[0], p[1] = c[1], p[2] = c[2], p[3] = 255;
}

void fill(Image8& img, int x0, int y0, int w, int h, Rgb c) {
  for (int y = y0; y < y0 + h; ++y)
    for (int x = x0; x < x0 + w; ++x) put(img, x, y, c);
}

// Text with its top-left corner at (x, y), each font pixel s×s, on a light backing box.
void text(Image8& img, int x, int y, const std::string& s, int scale) {
  const int advance = 4 * scale;
  fill(img, x - scale, y - scale, advance * int(s.size()) + scale, 7 * scale, {255, 255, 255});
  for (std::size_t k = 0; k < s.size(); ++k) {
    const auto it = std::find_if(kFont.begin(), kFont.end(), [&](const Glyph5& g) { return g.c == s[k]; });
    if (it == kFont.end()) continue;
    for (int r = 0; r < 5; ++r)
      for (int b = 0; b < 3; ++b)
        if (it->rows[r] >> (2 - b) & 1) fill(img, x + int(k) * advance + b * scale, y + r * scale, scale, scale, {0, 0, 0});
  }
}

}  // namespace

std::string colour_bar_label(double value) {
  std::string s = fmt::format("{:.3g}", value);
  // "1e-05" → "1e-5": shorter, the same number.
  if (const auto e = s.find("e-0"); e != std::string::npos) s.erase(e + 2, 1);
  if (const auto e = s.find("e+0"); e != std::string::npos) s.erase(e + 2, 1);
  return s;
}

ColourBarBox draw_colour_bar(Image8& img, const ValueRange& range) {
  if (img.width < 48 || img.height < 48) return {};
  const int scale = std::max(1, std::min(img.width, img.height) / 200);
  const int w = std::max(6, img.width / 40), h = img.height * 3 / 5;
  const std::string hi = colour_bar_label(range.hi), lo = colour_bar_label(range.lo);
  const int label_w = 4 * scale * int(std::max(hi.size(), lo.size()));
  const int margin = std::max(4, img.width / 64);
  const int x = img.width - margin - std::max(w, label_w) / 2 - w / 2;
  const int y = (img.height - h) / 2;
  fill(img, x - 1, y - 1, w + 2, h + 2, {0, 0, 0});
  for (int r = 0; r < h; ++r) fill(img, x, y + r, w, 1, scalar_colour(1.0 - (r + 0.5) / h));
  const auto centred = [&](const std::string& s) {
    return std::clamp(x + w / 2 - 2 * scale * int(s.size()), scale, img.width - 4 * scale * int(s.size()));
  };
  text(img, centred(hi), y - 1 - 7 * scale, hi, scale);
  text(img, centred(lo), y + h + 1 + 2 * scale, lo, scale);
  return {x, y, w, h};
}

PointSplatStats draw_points(Image8& img, const Camera& camera, std::span<const float> depth,
                            std::span<const Eigen::Vector3d> points, const PointSplatOptions& o) {
  const std::size_t n = static_cast<std::size_t>(camera.width) * camera.height;
  if (img.width != camera.width || img.height != camera.height || depth.size() != n)
    throw InvalidInput(fmt::format("draw_points: a {}x{} image and {} depths for a {}x{} camera", img.width, img.height,
                                   depth.size(), camera.width, camera.height));
  double tol = o.depth_tolerance;
  if (!(tol > 0)) {
    Box3 box;
    for (const auto& p : points) box.extend(p);
    tol = 0.01 * box.diagonal();
  }
  const Eigen::Matrix4d V = camera.view(), P = camera.projection();
  const double r = std::max(0.5, o.radius_px);
  const int reach = static_cast<int>(std::ceil(r));
  PointSplatStats st;
  for (const auto& p : points) {
    const Eigen::Vector4d e = V * p.homogeneous();
    const double d = -e.z();  // eye depth
    const Eigen::Vector4d c = P * e;
    if (!(d > camera.near_plane) || !(c.w() > 0)) {
      ++st.outside;
      continue;
    }
    const double px = (c.x() / c.w() + 1.0) * 0.5 * camera.width, py = (1.0 - c.y() / c.w()) * 0.5 * camera.height;
    if (px < -r || py < -r || px > camera.width + r || py > camera.height + r) {
      ++st.outside;
      continue;
    }
    bool any = false;
    for (int y = int(std::floor(py)) - reach; y <= int(std::floor(py)) + reach; ++y)
      for (int x = int(std::floor(px)) - reach; x <= int(std::floor(px)) + reach; ++x) {
        if (x < 0 || y < 0 || x >= camera.width || y >= camera.height) continue;
        const double dx = x + 0.5 - px, dy = y + 0.5 - py;
        if (dx * dx + dy * dy > r * r) continue;
        if (!(d <= double(depth[std::size_t(y) * camera.width + x]) + tol)) continue;
        put(img, x, y, o.colour);
        any = true;
      }
    any ? ++st.drawn : ++st.hidden;
  }
  return st;
}

}  // namespace quadrix
