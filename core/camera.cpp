#include "core/camera.h"

#include <cmath>
#include <numbers>

#include "core/error.h"

namespace quadrix {
namespace {
double radians(double deg) { return deg * std::numbers::pi / 180.0; }

// Orthonormal camera frame: right, true up, backward (−forward).
void basis(const Camera& c, Eigen::Vector3d& r, Eigen::Vector3d& u, Eigen::Vector3d& f) {
  f = c.forward();
  r = f.cross(c.up);
  if (r.squaredNorm() < 1e-24) r = f.cross(std::abs(f.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
  r.normalize();
  u = r.cross(f);
}
}  // namespace

Eigen::Matrix4d Camera::view() const {
  Eigen::Vector3d r, u, f;
  basis(*this, r, u, f);
  Eigen::Matrix4d V = Eigen::Matrix4d::Identity();
  V.row(0).head<3>() = r.transpose();
  V.row(1).head<3>() = u.transpose();
  V.row(2).head<3>() = -f.transpose();
  V(0, 3) = -r.dot(eye);
  V(1, 3) = -u.dot(eye);
  V(2, 3) = f.dot(eye);
  return V;
}

Eigen::Matrix4d Camera::projection() const {
  const double t = 1.0 / std::tan(radians(fov_y_deg) / 2.0);
  const double aspect = static_cast<double>(width) / height;
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  P(0, 0) = t / aspect;
  P(1, 1) = t;
  P(2, 2) = -(far_plane + near_plane) / (far_plane - near_plane);
  P(2, 3) = -2.0 * far_plane * near_plane / (far_plane - near_plane);
  P(3, 2) = -1.0;
  return P;
}

Ray Camera::pixel_ray(double px, double py) const {
  Eigen::Vector3d r, u, f;
  basis(*this, r, u, f);
  const double th = std::tan(radians(fov_y_deg) / 2.0);
  const double aspect = static_cast<double>(width) / height;
  const double x = (2.0 * px / width - 1.0) * th * aspect;
  const double y = (1.0 - 2.0 * py / height) * th;
  return {eye, (f + x * r + y * u).normalized()};
}

Camera frame_box(const Box3& box, const FramingOptions& o) {
  if (box.empty()) throw InvalidInput("cannot frame an empty model (no primitives)");
  if (!(o.fov_y_deg > 0.0 && o.fov_y_deg < 179.0))
    throw InvalidInput("field of view must be in (0, 179) degrees, got " + std::to_string(o.fov_y_deg));
  if (o.width <= 0 || o.height <= 0) throw InvalidInput("image size must be positive");
  Camera c;
  c.width = o.width;
  c.height = o.height;
  c.fov_y_deg = o.fov_y_deg;
  c.target = box.centre();
  double radius = 0.5 * box.diagonal();
  if (!(radius > 0.0)) radius = 1.0;
  const double half_y = radians(o.fov_y_deg) / 2.0;
  const double half_x = std::atan(std::tan(half_y) * o.width / o.height);
  const double dist = radius * o.margin / std::sin(std::min(half_x, half_y));
  const double az = radians(o.azimuth_deg), el = radians(o.elevation_deg);
  const Eigen::Vector3d dir(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
  c.eye = c.target + dist * dir;
  c.up = Eigen::Vector3d::UnitY();
  c.near_plane = std::max(dist - 1.5 * radius, dist * 1e-3);
  c.far_plane = dist + 1.5 * radius;
  return c;
}

}  // namespace quadrix
