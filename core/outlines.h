#pragma once
/// Outline detection on a G-buffer ([Sigg06] §5: silhouettes and creases from depth and normal
/// discontinuities), the same test the GL outline pass (render/shaders/outline.frag) runs, so
/// the CPU reference and the GPU draw the same lines.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/camera.h"

namespace quadrix {

struct OutlineOptions {
  /// A depth discontinuity: the pixel's eye depth departs from the depth its two neighbours
  /// predict (linear in 1/depth, exact on planes) by more than this fraction of the scene's
  /// bounding radius...
  double depth_gap = 0.01;
  /// ...and by more than this many pixel footprints at its depth (so distant or grazing smooth
  /// surfaces stay clean).
  double depth_pixels = 3.0;
  /// A crease: the normals of 4-neighbours differ by more than this angle, degrees.
  double crease_deg = 50.0;
};

/// The G-buffer the detector reads (row-major, width·height each; row order does not matter).
struct OutlineInput {
  int width = 0, height = 0;
  const std::uint8_t* coverage = nullptr;   ///< 1 where a surface was hit
  const float* depth = nullptr;             ///< eye-space depth, world units
  const Eigen::Vector3f* normal = nullptr;  ///< unit normals (any fixed frame)
  double fov_y_deg = 40.0;                  ///< the camera's, for the pixel footprint
  double scene_radius = 1.0;                ///< bounding radius of the scene, world units
};

/// 1 on outline pixels, one pixel wide and on the surface: covered pixels next to background
/// (silhouettes), on the nearer side of depth discontinuities, and before a crease along +x or +y
/// (OutlineOptions). \throws InvalidInput for a bad size.
std::vector<std::uint8_t> detect_outlines(const OutlineInput& input, const OutlineOptions& options = {});

}  // namespace quadrix
