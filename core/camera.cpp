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

Eigen::Vector3d front_axis(const Eigen::Vector3d& up) {
  const Eigen::Vector3d a = up.cwiseAbs();
  if (a.y() >= a.x() && a.y() >= a.z()) return Eigen::Vector3d::UnitZ();
  if (a.z() >= a.x()) return -Eigen::Vector3d::UnitY();
  return Eigen::Vector3d::UnitY();
}

Eigen::Vector3d parse_axis(std::string_view text) {
  double sign = 1.0;
  std::string_view t = text;
  if (!t.empty() && (t[0] == '+' || t[0] == '-')) {
    sign = t[0] == '-' ? -1.0 : 1.0;
    t.remove_prefix(1);
  }
  if (t == "x" || t == "X") return sign * Eigen::Vector3d::UnitX();
  if (t == "y" || t == "Y") return sign * Eigen::Vector3d::UnitY();
  if (t == "z" || t == "Z") return sign * Eigen::Vector3d::UnitZ();
  throw InvalidInput("axis '" + std::string(text) + "' is not one of +x -x +y -y +z -z");
}

Camera frame_view(const Box3& box, const ViewOptions& o) {
  if (box.empty()) throw InvalidInput("cannot frame an empty model (no primitives)");
  for (const double fov : {o.fov_y_deg, o.fit_fov_y_deg})
    if (!(fov > 0.0 && fov < 179.0))
      throw InvalidInput("field of view must be in (0, 179) degrees, got " + std::to_string(fov));
  if (!(o.zoom > 0.0 && std::isfinite(o.zoom))) throw InvalidInput("zoom must be positive, got " + std::to_string(o.zoom));
  if (o.width <= 0 || o.height <= 0) throw InvalidInput("image size must be positive");
  if (!(o.up.norm() > 0.0)) throw InvalidInput("the up axis is zero");
  Camera c;
  c.width = o.width;
  c.height = o.height;
  c.target = box.centre();
  double radius = 0.5 * box.diagonal();
  if (!(radius > 0.0)) radius = 1.0;
  const double fit_half_y = radians(o.fit_fov_y_deg) / 2.0;
  const double fit_half_x = std::atan(std::tan(fit_half_y) * o.width / o.height);
  const double dist = radius * o.margin / std::sin(std::min(fit_half_x, fit_half_y));
  // The lens: fov_y relative to the fitted one, narrowed by the zoom.
  const double tan_half = std::tan(radians(o.fov_y_deg) / 2.0) / o.zoom;
  c.fov_y_deg = 2.0 * std::atan(tan_half) * 180.0 / std::numbers::pi;
  const Eigen::Vector3d up = o.up.normalized();
  const Eigen::Vector3d front = front_axis(up);
  const Eigen::Vector3d right = up.cross(front);
  const double az = radians(o.azimuth_deg), el = radians(o.elevation_deg);
  const Eigen::Vector3d dir = std::cos(el) * (std::cos(az) * front + std::sin(az) * right) + std::sin(el) * up;
  c.eye = c.target + dist * dir;
  // Straight down (or up): the image's up is the far side (the back, away from the front).
  c.up = std::abs(std::cos(el)) < 1e-6 ? Eigen::Vector3d(-(std::sin(el) > 0 ? 1.0 : -1.0) *
                                                         (std::cos(az) * front + std::sin(az) * right))
                                       : up;
  c.near_plane = std::max(dist - 1.5 * radius, dist * 1e-3);
  c.far_plane = dist + 1.5 * radius;
  return c;
}

Camera fit_points(const Camera& camera, std::span<const Eigen::Vector3d> points, double fill) {
  if (points.empty()) return camera;
  Camera c = camera;
  const double tan_y = std::tan(radians(c.fov_y_deg) / 2.0);
  const double aspect = static_cast<double>(c.width) / c.height;
  for (int iteration = 0; iteration < 4; ++iteration) {
    Eigen::Vector3d r, u, f;
    basis(c, r, u, f);
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, zmin = 1e300, zmax = -1e300;
    for (const auto& p : points) {
      const Eigen::Vector3d d = p - c.eye;
      const double z = d.dot(f);
      if (!(z > 0)) continue;
      x0 = std::min(x0, d.dot(r) / z);
      x1 = std::max(x1, d.dot(r) / z);
      y0 = std::min(y0, d.dot(u) / z);
      y1 = std::max(y1, d.dot(u) / z);
      zmin = std::min(zmin, z);
      zmax = std::max(zmax, z);
    }
    if (!(x1 >= x0 && y1 >= y0)) break;
    const double dist = (c.target - c.eye).norm();
    // Centre: move the target and eye sideways so the bounds' centre slope, taken at the points'
    // middle depth, comes onto the axis. (At the target's depth instead, points well in front of
    // it were pushed off-centre by the parallax of the zoom that follows, and a probe that saw one
    // speck of a model sent the camera 10 diagonals away, looking at nothing.)
    const double zc = 0.5 * (zmin + zmax);
    const Eigen::Vector3d shift = zc * (0.5 * (x0 + x1) * r + 0.5 * (y0 + y1) * u);
    // The larger of the fractions of width and height the bounds span becomes `fill`: the
    // nearest point's distance scales by extent/fill (the rest of the depth kept).
    const double extent = std::max((x1 - x0) / (2.0 * tan_y * aspect), (y1 - y0) / (2.0 * tan_y));
    if (!(extent > 0)) break;
    const double front_gap = zmin;  // eye to the nearest point
    const double depth_span = dist - front_gap;
    const double new_dist = depth_span + front_gap * extent / fill;
    c.target += shift;
    c.eye = c.target - new_dist * f;
    c.near_plane = std::max(0.5 * (new_dist - (dist - zmin)), new_dist * 1e-3);
    c.far_plane = 2.0 * (new_dist + (zmax - dist));
  }
  return c;
}

}  // namespace quadrix
