#include "core/colour_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix {
namespace {

// Viridis (matplotlib's default map, CC0) sampled at 9 stops; linear in between.
constexpr std::array<std::array<double, 3>, 9> kViridis = {{{68, 1, 84},
                                                            {71, 44, 122},
                                                            {59, 81, 139},
                                                            {44, 113, 142},
                                                            {33, 144, 141},
                                                            {39, 173, 129},
                                                            {92, 200, 99},
                                                            {170, 220, 50},
                                                            {253, 231, 37}}};

std::uint8_t byte(double v) { return static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0) + 0.5); }

// HSV (h in turns) to RGB.
Rgb hsv(double h, double s, double v) {
  h = (h - std::floor(h)) * 6.0;
  const int i = static_cast<int>(h) % 6;
  const double f = h - std::floor(h), p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  const double r[6] = {v, q, p, p, t, v}, g[6] = {t, v, v, q, p, p}, b[6] = {p, p, t, v, v, q};
  return {byte(255 * r[i]), byte(255 * g[i]), byte(255 * b[i])};
}

}  // namespace

ColourMode parse_colour_mode(std::string_view text) {
  if (text == "none") return ColourMode::none;
  if (text == "error") return ColourMode::error;
  if (text == "patch") return ColourMode::patch;
  if (text == "normal") return ColourMode::normal;
  if (text == "depth") return ColourMode::depth;
  throw InvalidInput(fmt::format("colour-by '{}' is not one of none, error, patch, normal, depth", text));
}

double ValueRange::normalise(double v) const {
  if (!(hi > lo) || !std::isfinite(v)) return 0.0;
  return std::clamp((v - lo) / (hi - lo), 0.0, 1.0);
}

Rgb scalar_colour(double t) {
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
  const double x = t * (kViridis.size() - 1);
  const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(x), kViridis.size() - 2);
  const double f = x - double(i);
  Rgb c;
  for (int k = 0; k < 3; ++k) c[k] = byte((1 - f) * kViridis[i][k] + f * kViridis[i + 1][k]);
  return c;
}

Rgb patch_colour(std::size_t id) {
  constexpr double kGolden = 0.6180339887498949;
  // Hue by the golden ratio; saturation and value alternate so that hues that come round again
  // still differ.
  const double h = 0.07 + kGolden * double(id);
  const double s = (id / 7) % 2 ? 0.55 : 0.8, v = (id / 3) % 2 ? 0.8 : 0.95;
  return hsv(h, s, v);
}

Rgb normal_colour(const Eigen::Vector3f& n) {
  return {byte(127.5 * (n.x() + 1.0)), byte(127.5 * (n.y() + 1.0)), byte(127.5 * (n.z() + 1.0))};
}

Model colour_by_patch(const Model& model) {
  Model m = model;
  std::size_t id = 0;
  for (auto& s : m.slims) s.colour = patch_colour(id++);
  for (auto& t : m.tets) t.colour = patch_colour(id++);
  for (auto& g : m.glyphs) g.colour = patch_colour(id++);
  for (auto& s : m.implicits) s.colour = patch_colour(id++);
  return m;
}

Model colour_by_values(const Model& model, std::span<const std::optional<double>> values, const ValueRange& range) {
  if (values.size() != model.slims.size())
    throw InvalidInput(fmt::format("colour by values: {} values for {} SLIM patches", values.size(), model.slims.size()));
  Model m = model;
  for (std::size_t i = 0; i < values.size(); ++i)
    m.slims[i].colour = values[i] ? scalar_colour(range.normalise(*values[i])) : Rgb{128, 128, 128};
  return m;
}

void colour_pixels(Image8& image, ColourMode mode, std::span<const std::uint8_t> coverage, std::span<const float> depth,
                   std::span<const Eigen::Vector3f> normal, const ValueRange& range) {
  if (mode != ColourMode::normal && mode != ColourMode::depth)
    throw InvalidInput("colour_pixels: only normal and depth are per-pixel modes");
  const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
  if (coverage.size() != n || depth.size() != n || normal.size() != n || image.rgba.size() != 4 * n)
    throw InvalidInput(fmt::format("colour_pixels: buffers of {}, {}, {} pixels for a {}x{} image", coverage.size(),
                                   depth.size(), normal.size(), image.width, image.height));
  for (std::size_t i = 0; i < n; ++i) {
    if (!coverage[i]) continue;
    const Rgb c = mode == ColourMode::normal ? normal_colour(normal[i]) : scalar_colour(range.normalise(depth[i]));
    std::copy(c.begin(), c.end(), image.rgba.begin() + 4 * i);
    image.rgba[4 * i + 3] = 255;
  }
}

ValueRange covered_depth_range(std::span<const std::uint8_t> coverage, std::span<const float> depth) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < coverage.size() && i < depth.size(); ++i)
    if (coverage[i] && std::isfinite(depth[i])) lo = std::min(lo, double(depth[i])), hi = std::max(hi, double(depth[i]));
  return lo <= hi ? ValueRange{lo, hi} : ValueRange{0, 0};
}

}  // namespace quadrix
