#pragma once
/// The lights the Phong shading uses on the CPU (core/shade.h) and in GL (shade.frag), and the
/// point the key light casts shadows from ([Sigg06] §5: shadow map on the GPU, shadow rays in the
/// reference), so both renderers shadow the same scene the same way.
#include <Eigen/Core>

#include "core/camera.h"
#include "core/model.h"

namespace quadrix {

/// Key light direction in eye space (towards the light; upper left, in front). The head light is
/// (0, 0, 1) and casts no visible shadow.
inline Eigen::Vector3d key_light_eye() { return Eigen::Vector3d(-0.5, 0.8, 0.6).normalized(); }

/// The key light's direction in world space for a view (unit, towards the light).
Eigen::Vector3d key_light_world(const Camera& view);

/// The camera at the shadow-casting point light: kShadowLightDistance bounding radii from the
/// box centre along key_light_world(view), looking at the centre, a square image of `size`
/// pixels that frames the box's eight corners as the light sees them (2 % margin; at most the
/// bounding sphere), near/far bracketing the sphere. Shadow rays go to its eye.
/// \throws InvalidInput for an empty box or size < 1.
Camera shadow_light_camera(const Camera& view, const Box3& box, int size);

/// Shadow-map texels per view pixel, at the scene's centre, of the default map size: two keep
/// the soft edges (PCF over 1.5 texels) about a pixel wide; the light's view costs about its area.
inline constexpr double kShadowTexelsPerPixel = 2.0;

/// The shadow-map side (pixels) with `texels_per_pixel` texels across each of the view's pixels
/// at the box centre, clamped to [256, 4096].
/// \throws InvalidInput as shadow_light_camera.
int matched_shadow_map_size(const Camera& view, const Box3& box, double texels_per_pixel = kShadowTexelsPerPixel);

/// The light's distance from the box centre in bounding radii: far enough that its rays are
/// within 6° of the (directional) shading key light.
inline constexpr double kShadowLightDistance = 10.0;

}  // namespace quadrix
