#include "core/lighting.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix {

Eigen::Vector3d key_light_world(const Camera& view) {
  const Eigen::Matrix3d R = view.view().topLeftCorner<3, 3>();
  return (R.transpose() * key_light_eye()).normalized();
}

Camera shadow_light_camera(const Camera& view, const Box3& box, int size) {
  if (box.empty()) throw InvalidInput("shadow light: the scene is empty");
  if (size < 1) throw InvalidInput(fmt::format("shadow light: map size {} is below 1", size));
  const double r = std::max(0.5 * box.diagonal(), 1e-12 * std::max(1.0, box.centre().norm()));
  const double distance = kShadowLightDistance * r;
  const Eigen::Vector3d l = key_light_world(view);
  Camera c;
  c.target = box.centre();
  c.eye = c.target + distance * l;
  // Any up not parallel to the light direction; the view's up keeps the map upright.
  const Eigen::Vector3d up = view.view().topLeftCorner<3, 3>().transpose().col(1);
  c.up = std::abs(up.dot(l)) < 0.99 ? up : Eigen::Vector3d(view.view().topLeftCorner<3, 3>().row(0).transpose());
  c.width = c.height = size;
  c.near_plane = distance - 1.05 * r;
  c.far_plane = distance + 1.05 * r;
  // The widest tangent of a corner off the light's axis, 2 % margin; the bounding sphere
  // (2·asin(r/d)) bounds it.
  c.fov_y_deg = 90;  // any: only the view matrix is used here
  const Eigen::Matrix4d V = c.view();
  double reach = 0;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d p((k & 1 ? box.max : box.min).x(), (k & 2 ? box.max : box.min).y(),
                            (k & 4 ? box.max : box.min).z());
    const Eigen::Vector4d e = V * p.homogeneous();
    reach = std::max({reach, std::abs(e.x()) / -e.z(), std::abs(e.y()) / -e.z()});
  }
  const double sphere = std::tan(std::asin(1.0 / kShadowLightDistance));
  c.fov_y_deg = 2.0 * std::atan(1.02 * std::min(reach, sphere)) * 180.0 / std::numbers::pi;
  return c;
}

int matched_shadow_map_size(const Camera& view, const Box3& box, double texels_per_pixel) {
  const Camera light = shadow_light_camera(view, box, 1);
  const double deg = std::numbers::pi / 180.0;
  const double view_pixel = 2.0 * std::max((box.centre() - view.eye).dot(view.forward()), view.near_plane) *
                            std::tan(0.5 * view.fov_y_deg * deg) / std::max(view.height, 1);
  const double light_extent = 2.0 * (light.eye - light.target).norm() * std::tan(0.5 * light.fov_y_deg * deg);
  return static_cast<int>(std::clamp(std::ceil(texels_per_pixel * light_extent / view_pixel), 256.0, 4096.0));
}

}  // namespace quadrix
