#include "core/bounds.h"

#include <Eigen/LU>
#include <algorithm>

namespace quadrix {

Tetrahedron::Tetrahedron(const std::array<Eigen::Vector3d, 4>& corners) : p_(corners) {
  Eigen::Matrix3d M;
  M << p_[1] - p_[0], p_[2] - p_[0], p_[3] - p_[0];
  inv_ = M.inverse();
}

double Tetrahedron::signed_volume() const {
  return (p_[1] - p_[0]).cross(p_[2] - p_[0]).dot(p_[3] - p_[0]) / 6.0;
}

Eigen::Vector4d Tetrahedron::barycentric(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d l = inv_ * (x - p_[0]);
  return {1.0 - l.sum(), l.x(), l.y(), l.z()};
}

bool Tetrahedron::contains(const Eigen::Vector3d& x, double eps) const {
  return (barycentric(x).array() >= -eps).all();
}

double Tetrahedron::diameter() const {
  double d = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) d = std::max(d, (p_[i] - p_[j]).norm());
  return d;
}

bool is_degenerate_tetrahedron(const std::array<Eigen::Vector3d, 4>& p, double rel_eps) {
  double diam = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) diam = std::max(diam, (p[i] - p[j]).norm());
  if (!(diam > 0.0) || !std::isfinite(diam)) return true;
  const double vol6 = std::abs((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]));
  return !(vol6 > rel_eps * diam * diam * diam);
}

bool sphere_backfacing(const Quadric& q_eye, const Eigen::Vector3d& centre_eye, double radius) {
  // [Stoll06] eq. 18: c′ < −c′ₛₚₕᵀb′ − r‖b′‖.
  return q_eye.c < -centre_eye.dot(q_eye.b) - radius * q_eye.b.norm();
}

bool tetrahedron_backfacing(const Quadric& q_eye, const std::array<Eigen::Vector3d, 4>& corners_eye) {
  // [Stoll06] eq. 19: c′ < −maxᵢ p′ᵢᵀb′.
  double m = -std::numeric_limits<double>::infinity();
  for (const auto& p : corners_eye) m = std::max(m, p.dot(q_eye.b));
  return q_eye.c < -m;
}

}  // namespace quadrix
