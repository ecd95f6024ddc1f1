#pragma once
/// Log–log line charts drawn into an Image8 (benchmark reports: run time and size against
/// error), with a built-in 5×7 pixel font for titles, tick labels and legends.
#include <span>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/model.h"

namespace quadrix {

enum class PlotStyle { solid, dashed, markers };

/// One line: points (x, y), both > 0 (others are skipped); markers at every point.
struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  Rgb colour{0, 0, 0};
  PlotStyle style = PlotStyle::solid;
};

/// One chart with logarithmic x and y axes fitted to its data (whole decades where possible).
struct PlotPanel {
  std::string title;    ///< above the chart (the font has upper case only; text is upper-cased)
  std::string x_label;  ///< below the x axis
  std::vector<PlotSeries> series;
};

struct PlotOptions {
  int panel_width = 560;   ///< pixels per panel, legend included
  int panel_height = 560;
  int text_scale = 2;      ///< font pixels per glyph pixel
};

/// Panels side by side, each with its legend underneath. Panels without positive data are
/// drawn empty with their title.
Image8 plot_log_log(std::span<const PlotPanel> panels, const PlotOptions& options = {});

/// Draws text (5×7 glyphs, scale pixels each; unknown characters as blanks) with its top left
/// at (x, y), clipped to the image.
void draw_text(Image8& image, int x, int y, const std::string& text, Rgb colour, int scale = 2);

}  // namespace quadrix
