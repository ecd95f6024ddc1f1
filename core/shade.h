#pragma once
/// Shading of G-buffers on the CPU (Phong with a head light and a key light), the same model
/// the GL deferred pass uses, so CPU and GL images can be compared by eye.
#include "core/camera.h"
#include "core/image.h"
#include "core/outlines.h"
#include "core/reference.h"

namespace quadrix {

struct ShadeOptions {
  Rgb background{255, 255, 255};
  double ambient = 0.15;
  double specular = 0.35;
  double shininess = 40.0;
  /// Black silhouette and crease lines (core/outlines.h) over the shading.
  bool outlines = false;
  OutlineOptions outline{};
};

/// Shaded RGBA image; background pixels get the opaque background colour. Where the image has
/// key-light visibility (ReferenceRenderOptions::shadows) it scales the key light's terms.
Image8 shade_phong(const ReferenceImage& image, const Camera& camera, const ShadeOptions& options = {});

/// Depth image as a 1-channel float image (eye-space depth, +inf background).
FloatImage depth_image(const ReferenceImage& image);
/// Normals as a 3-channel float image (world space, 0 background).
FloatImage normal_image(const ReferenceImage& image);

}  // namespace quadrix
