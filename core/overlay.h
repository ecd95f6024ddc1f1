#pragma once
/// What `render` draws over a finished image on every backend alike: a colour bar (legend with
/// min/max labels) for a scalar colouring, and a point cloud as small splats depth-tested
/// against the surface's eye-depth buffer.
#include <cstddef>
#include <span>
#include <string>

#include <Eigen/Core>

#include "core/camera.h"
#include "core/colour_map.h"
#include "core/image.h"

namespace quadrix {

/// The colour bar's place in the image (pixels, row 0 at the top); all zero when not drawn.
struct ColourBarBox {
  int x = 0, y = 0, width = 0, height = 0;
};

/// Draws a vertical bar of scalar_colour (bottom 0, top 1) near the right edge, framed, with
/// range.hi printed above it and range.lo below (3 significant digits). Returns where the bar
/// itself lies (its inside, without frame or labels). Images smaller than 48×48 get no bar.
ColourBarBox draw_colour_bar(Image8& image, const ValueRange& range);

/// The label text draw_colour_bar prints for a value ("%.3g").
std::string colour_bar_label(double value);

struct PointSplatOptions {
  double radius_px = 1.5;       ///< splat radius, pixels (a disc)
  Rgb colour{230, 30, 30};      ///< splat colour
  /// A point is drawn where its eye depth ≤ the surface's + this (world units): points on the
  /// surface stay visible, points behind it are hidden. 0: 1 % of the points' bounding-box diagonal.
  double depth_tolerance = 0;
};

struct PointSplatStats {
  std::size_t drawn = 0;   ///< points with at least one visible splat pixel
  std::size_t hidden = 0;  ///< points in the view wholly behind the surface
  std::size_t outside = 0; ///< points outside the view (or behind the eye)
};

/// Splats the points into image through camera, each splat pixel depth-tested against depth
/// (eye-space depth per pixel, +inf where no surface; camera.width × camera.height).
/// \throws InvalidInput when the image or depth size differs from the camera's.
PointSplatStats draw_points(Image8& image, const Camera& camera, std::span<const float> depth,
                            std::span<const Eigen::Vector3d> points, const PointSplatOptions& options = {});

}  // namespace quadrix
