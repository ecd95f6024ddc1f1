#pragma once
/// The pinhole camera shared by the CPU reference and the GL renderer: the same rays, the
/// same view and projection matrices, the same framing of a bounding box.
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

}  // namespace quadrix
