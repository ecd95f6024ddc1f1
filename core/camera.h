#pragma once
/// The pinhole camera shared by the CPU reference and the GL renderer: the same rays, the
/// same view and projection matrices, the same framing of a bounding box.
#include <span>
#include <string_view>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/model.h"
#include "core/ray.h"

namespace quadrix {

struct Camera {
  Eigen::Vector3d eye = Eigen::Vector3d(0, 0, 5);
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  double fov_y_deg = 40.0;  ///< vertical field of view, degrees, in (0, 180)
  int width = 512;          ///< pixels
  int height = 512;
  double near_plane = 0.01;  ///< world units, > 0
  double far_plane = 100.0;

  /// Right-handed view matrix (world → eye, camera looks down −z).
  Eigen::Matrix4d view() const;
  /// OpenGL projection (clip z in [−w, w] between near and far).
  Eigen::Matrix4d projection() const;
  /// Primary ray through image point (px, py) in pixels, y down from the top edge; pixel (i, j)
  /// has its centre at (i + ½, j + ½). dir has unit length, so t is the distance from the eye.
  Ray pixel_ray(double px, double py) const;
  /// Unit viewing direction.
  Eigen::Vector3d forward() const { return (target - eye).normalized(); }
};

struct FramingOptions {
  double azimuth_deg = 30.0;    ///< rotation about the up axis (+y), from +z towards +x
  double elevation_deg = 20.0;  ///< above the horizontal plane
  double fov_y_deg = 40.0;
  double margin = 1.05;  ///< the bounding sphere fills 1/margin of the smaller image extent
  int width = 512;
  int height = 512;
};

/// Places the camera on a sphere around the box so that the box's bounding sphere fits the view;
/// near/far bracket the sphere. \throws InvalidInput for an empty box or an invalid field of view.
Camera frame_box(const Box3& box, const FramingOptions& options);

/// A view about any world up axis, for the CLI's --up, --view, --zoom and --fov.
struct ViewOptions {
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();  ///< world up (a unit axis: ±x, ±y, ±z)
  double azimuth_deg = 30.0;    ///< about up, from the front axis (up +y: +z) towards the right
  double elevation_deg = 20.0;  ///< above the plane normal to up; ±90 looks straight down / up
  double fov_y_deg = 40.0;      ///< the lens: narrower zooms in
  double fit_fov_y_deg = 40.0;  ///< the distance is fitted for this field of view (so --fov zooms)
  double zoom = 1.0;            ///< magnification on top of the fit (> 0)
  double margin = 1.05;         ///< the bounding sphere fills 1/margin of the smaller side at zoom 1
  int width = 512;
  int height = 512;
};

/// The front axis seen from the front for a world up axis: up +y → +z, +z → −y, +x → +y
/// (a cyclic turn of the axes), negated ups → the same front.
Eigen::Vector3d front_axis(const Eigen::Vector3d& up);

/// Parses ±x|±y|±z (a missing sign is +). \throws InvalidInput.
Eigen::Vector3d parse_axis(std::string_view text);

/// Places the camera like frame_box, about `up`, with zoom applied as a narrower lens.
/// \throws InvalidInput for an empty box, a bad field of view or zoom.
Camera frame_view(const Box3& box, const ViewOptions& options);

/// Re-targets and moves the camera along its viewing direction (orientation, lens and image
/// kept) so the projected bounds of `points` (the visible geometry, world units) are centred and
/// fill `fill` of the smaller image side. Returns the camera unchanged for no points.
Camera fit_points(const Camera& camera, std::span<const Eigen::Vector3d> points, double fill);

}  // namespace quadrix
