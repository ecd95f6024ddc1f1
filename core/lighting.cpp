#include "core/lighting.h"

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
  // The bounding sphere subtends 2·asin(r/d); 2 % margin so its rim stays inside the map.
  c.fov_y_deg = 2.0 * std::asin(1.02 / kShadowLightDistance) * 180.0 / std::numbers::pi;
  c.width = c.height = size;
  c.near_plane = distance - 1.05 * r;
  c.far_plane = distance + 1.05 * r;
  return c;
}

}  // namespace quadrix
