#include "bench/plot.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace quadrix {
namespace {

// Classic 5×7 font: five column bytes per glyph, bit 0 the top row.
struct FontGlyph {
  char c;
  std::array<std::uint8_t, 5> columns;
};
constexpr FontGlyph kFont[] = {
    {'0', {0x3E, 0x51, 0x49, 0x45, 0x3E}}, {'1', {0x00, 0x42, 0x7F, 0x40, 0x00}}, {'2', {0x42, 0x61, 0x51, 0x49, 0x46}},
    {'3', {0x21, 0x41, 0x45, 0x4B, 0x31}}, {'4', {0x18, 0x14, 0x12, 0x7F, 0x10}}, {'5', {0x27, 0x45, 0x45, 0x45, 0x39}},
    {'6', {0x3C, 0x4A, 0x49, 0x49, 0x30}}, {'7', {0x01, 0x71, 0x09, 0x05, 0x03}}, {'8', {0x36, 0x49, 0x49, 0x49, 0x36}},
    {'9', {0x06, 0x49, 0x49, 0x29, 0x1E}}, {'A', {0x7E, 0x11, 0x11, 0x11, 0x7E}}, {'B', {0x7F, 0x49, 0x49, 0x49, 0x36}},
    {'C', {0x3E, 0x41, 0x41, 0x41, 0x22}}, {'D', {0x7F, 0x41, 0x41, 0x22, 0x1C}}, {'E', {0x7F, 0x49, 0x49, 0x49, 0x41}},
    {'F', {0x7F, 0x09, 0x09, 0x09, 0x01}}, {'G', {0x3E, 0x41, 0x49, 0x49, 0x7A}}, {'H', {0x7F, 0x08, 0x08, 0x08, 0x7F}},
    {'I', {0x00, 0x41, 0x7F, 0x41, 0x00}}, {'J', {0x20, 0x40, 0x41, 0x3F, 0x01}}, {'K', {0x7F, 0x08, 0x14, 0x22, 0x41}},
    {'L', {0x7F, 0x40, 0x40, 0x40, 0x40}}, {'M', {0x7F, 0x02, 0x0C, 0x02, 0x7F}}, {'N', {0x7F, 0x04, 0x08, 0x10, 0x7F}},
    {'O', {0x3E, 0x41, 0x41, 0x41, 0x3E}}, {'P', {0x7F, 0x09, 0x09, 0x09, 0x06}}, {'Q', {0x3E, 0x41, 0x51, 0x21, 0x5E}},
    {'R', {0x7F, 0x09, 0x19, 0x29, 0x46}}, {'S', {0x46, 0x49, 0x49, 0x49, 0x31}}, {'T', {0x01, 0x01, 0x7F, 0x01, 0x01}},
    {'U', {0x3F, 0x40, 0x40, 0x40, 0x3F}}, {'V', {0x1F, 0x20, 0x40, 0x20, 0x1F}}, {'W', {0x3F, 0x40, 0x38, 0x40, 0x3F}},
    {'X', {0x63, 0x14, 0x08, 0x14, 0x63}}, {'Y', {0x07, 0x08, 0x70, 0x08, 0x07}}, {'Z', {0x61, 0x51, 0x49, 0x45, 0x43}},
    {'.', {0x00, 0x60, 0x60, 0x00, 0x00}}, {'-', {0x08, 0x08, 0x08, 0x08, 0x08}}, {'+', {0x08, 0x08, 0x3E, 0x08, 0x08}},
    {'(', {0x00, 0x1C, 0x22, 0x41, 0x00}}, {')', {0x00, 0x41, 0x22, 0x1C, 0x00}}, {'/', {0x20, 0x10, 0x08, 0x04, 0x02}},
    {':', {0x00, 0x36, 0x36, 0x00, 0x00}}, {',', {0x00, 0x50, 0x30, 0x00, 0x00}}, {'=', {0x14, 0x14, 0x14, 0x14, 0x14}},
    {'%', {0x23, 0x13, 0x08, 0x64, 0x62}}, {'<', {0x08, 0x14, 0x22, 0x41, 0x00}}, {'>', {0x00, 0x41, 0x22, 0x14, 0x08}},
};

const FontGlyph* find_glyph(char c) {
  c = char(std::toupper(static_cast<unsigned char>(c)));
  for (const auto& g : kFont)
    if (g.c == c) return &g;
  return nullptr;
}

void put(Image8& im, int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= im.width || y >= im.height) return;
  std::uint8_t* p = im.pixel(x, y);
  p[0] = c[0];
  p[1] = c[1];
  p[2] = c[2];
  p[3] = 255;
}

void fill_rect(Image8& im, int x0, int y0, int x1, int y1, Rgb c) {
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) put(im, x, y, c);
}

// A 2-pixel-wide line; dashed lines draw 8 pixels of every 14 along the line (phase carried).
void draw_line(Image8& im, double x0, double y0, double x1, double y1, Rgb c, bool dashed, double& phase) {
  const double len = std::hypot(x1 - x0, y1 - y0);
  const int steps = std::max(1, int(std::ceil(len)));
  for (int k = 0; k <= steps; ++k) {
    const double t = double(k) / steps;
    if (dashed && std::fmod(phase + t * len, 14.0) >= 8.0) continue;
    const int x = int(std::lround(x0 + t * (x1 - x0))), y = int(std::lround(y0 + t * (y1 - y0)));
    fill_rect(im, x, y, x + 1, y + 1, c);
  }
  phase += len;
}

void draw_marker(Image8& im, int x, int y, Rgb c, PlotStyle style) {
  if (style == PlotStyle::markers) {  // a cross
    for (int k = -5; k <= 5; ++k) {
      fill_rect(im, x + k, y + k, x + k + 1, y + k + 1, c);
      fill_rect(im, x + k, y - k, x + k + 1, y - k + 1, c);
    }
  } else if (style == PlotStyle::dashed) {  // an open square
    for (int k = -4; k <= 4; ++k) {
      put(im, x + k, y - 4, c), put(im, x + k, y + 4, c), put(im, x - 4, y + k, c), put(im, x + 4, y + k, c);
      put(im, x + k, y - 3, c), put(im, x + k, y + 3, c), put(im, x - 3, y + k, c), put(im, x + 3, y + k, c);
    }
  } else {
    fill_rect(im, x - 3, y - 3, x + 3, y + 3, c);
  }
}

std::string tick_label(double v) {
  const double e = std::round(std::log10(v));
  if (std::abs(std::log10(v) - e) < 1e-9 && (e < -2 || e > 4)) return fmt::format("1E{}", int(e));
  return fmt::format("{:g}", v);
}

struct Axis {
  double lo = 1, hi = 10;  // log10 range
  void fit(double mn, double mx) {
    if (!(mn > 0) || !(mx > 0) || !std::isfinite(mn) || !std::isfinite(mx)) mn = 1, mx = 10;
    lo = std::floor(std::log10(mn) + 1e-9);
    hi = std::ceil(std::log10(mx) - 1e-9);
    if (hi <= lo) hi = lo + 1;
  }
  // Ticks: every decade, plus 2 and 5 when the axis spans at most two decades.
  std::vector<double> ticks() const {
    std::vector<double> t;
    for (int e = int(lo); e <= int(hi); ++e)
      for (double m : (hi - lo <= 2 ? std::vector<double>{1, 2, 5} : std::vector<double>{1})) {
        const double v = m * std::pow(10.0, e);
        if (std::log10(v) <= hi + 1e-9) t.push_back(v);
      }
    return t;
  }
};

void draw_panel(Image8& im, int ox, const PlotPanel& panel, const PlotOptions& o) {
  const int s = o.text_scale, ch = 6 * s, line = 10 * s;
  const Rgb black{0, 0, 0}, grid{225, 225, 225};
  const int legend_rows = int(panel.series.size() + 1) / 2;
  const int left = ox + 8 * ch, right = ox + o.panel_width - 3 * ch;
  const int top = 2 * line, bottom = o.panel_height - (legend_rows + 2) * line - line;
  draw_text(im, ox + (o.panel_width - int(panel.title.size()) * ch) / 2, s * 3, panel.title, black, s);
  Axis ax, ay;
  double xmin = std::numeric_limits<double>::infinity(), xmax = 0, ymin = xmin, ymax = 0;
  for (const auto& sr : panel.series)
    for (std::size_t i = 0; i < std::min(sr.x.size(), sr.y.size()); ++i)
      if (sr.x[i] > 0 && sr.y[i] > 0 && std::isfinite(sr.x[i]) && std::isfinite(sr.y[i])) {
        xmin = std::min(xmin, sr.x[i]), xmax = std::max(xmax, sr.x[i]);
        ymin = std::min(ymin, sr.y[i]), ymax = std::max(ymax, sr.y[i]);
      }
  ax.fit(xmin, xmax);
  ay.fit(ymin, ymax);
  auto px = [&](double x) { return left + (std::log10(x) - ax.lo) / (ax.hi - ax.lo) * (right - left); };
  auto py = [&](double y) { return bottom - (std::log10(y) - ay.lo) / (ay.hi - ay.lo) * (bottom - top); };
  for (double t : ax.ticks()) {
    const int x = int(std::lround(px(t)));
    fill_rect(im, x, top, x, bottom, grid);
    fill_rect(im, x, bottom, x, bottom + 5, black);
    const std::string label = tick_label(t);
    draw_text(im, x - int(label.size()) * ch / 2, bottom + 8, label, black, s);
  }
  for (double t : ay.ticks()) {
    const int y = int(std::lround(py(t)));
    fill_rect(im, left, y, right, y, grid);
    fill_rect(im, left - 5, y, left, y, black);
    const std::string label = tick_label(t);
    draw_text(im, left - 8 - int(label.size()) * ch, y - 7 * s / 2, label, black, s);
  }
  fill_rect(im, left, top, left + 1, bottom, black);
  fill_rect(im, left, bottom - 1, right, bottom, black);
  draw_text(im, (left + right - int(panel.x_label.size()) * ch) / 2, bottom + 8 + line, panel.x_label, black, s);
  for (const auto& sr : panel.series) {
    double phase = 0;
    bool has_prev = false;
    double x0 = 0, y0 = 0;
    for (std::size_t i = 0; i < std::min(sr.x.size(), sr.y.size()); ++i) {
      if (!(sr.x[i] > 0 && sr.y[i] > 0 && std::isfinite(sr.x[i]) && std::isfinite(sr.y[i]))) {
        has_prev = false;
        continue;
      }
      const double x = px(sr.x[i]), y = py(sr.y[i]);
      if (has_prev && sr.style != PlotStyle::markers)
        draw_line(im, x0, y0, x, y, sr.colour, sr.style == PlotStyle::dashed, phase);
      draw_marker(im, int(std::lround(x)), int(std::lround(y)), sr.colour, sr.style);
      x0 = x, y0 = y, has_prev = true;
    }
  }
  // Legend: two columns under the chart.
  const int ly = bottom + 3 * line, col = (o.panel_width - 2 * ch) / 2;
  for (std::size_t k = 0; k < panel.series.size(); ++k) {
    const auto& sr = panel.series[k];
    const int x = ox + ch + int(k % 2) * col, y = ly + int(k / 2) * line;
    double phase = 0;
    if (sr.style != PlotStyle::markers) draw_line(im, x, y + 3.5 * s, x + 4 * ch, y + 3.5 * s, sr.colour, sr.style == PlotStyle::dashed, phase);
    draw_marker(im, x + 2 * ch, int(y + 3.5 * s), sr.colour, sr.style);
    draw_text(im, x + 5 * ch, y, sr.label, black, s);
  }
}

}  // namespace

void draw_text(Image8& image, int x, int y, const std::string& text, Rgb colour, int scale) {
  for (char c : text) {
    if (const FontGlyph* g = find_glyph(c))
      for (int col = 0; col < 5; ++col)
        for (int row = 0; row < 7; ++row)
          if (g->columns[col] >> row & 1)
            fill_rect(image, x + col * scale, y + row * scale, x + (col + 1) * scale - 1, y + (row + 1) * scale - 1, colour);
    x += 6 * scale;
  }
}

Image8 plot_log_log(std::span<const PlotPanel> panels, const PlotOptions& options) {
  Image8 im;
  im.width = std::max<int>(1, int(panels.size()) * options.panel_width);
  im.height = options.panel_height;
  im.rgba.assign(std::size_t(im.width) * im.height * 4, 255);
  for (std::size_t k = 0; k < panels.size(); ++k) draw_panel(im, int(k) * options.panel_width, panels[k], options);
  return im;
}

}  // namespace quadrix
