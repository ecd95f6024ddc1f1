#include "core/bounds.h"

#include <Eigen/LU>
#include <algorithm>
#include <limits>
#include <utility>

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

namespace {

using Eigen::Vector3d;

// Range of the quadric's Bézier control net over a tetrahedron (corners relative to the centroid).
std::pair<double, double> net_range(const std::array<Vector3d, 4>& y, const Eigen::Matrix4d& M) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector4d a = (Eigen::Vector4d() << y[i], 1.0).finished();
    const Eigen::Vector4d Ma = M * a;
    for (int j = i; j < 4; ++j) {
      const double v = Ma.dot((Eigen::Vector4d() << y[j], 1.0).finished());
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  return {lo, hi};
}

// The net of each half of a tetrahedron split at its longest edge's midpoint is tighter: recurse
// while a net straddles zero.
bool net_can_cross(const std::array<Vector3d, 4>& y, const Eigen::Matrix4d& M, int depth) {
  const auto [lo, hi] = net_range(y, M);
  if (lo > 0 || hi < 0) return false;
  if (depth == 0 || lo == 0 || hi == 0) return true;
  int a = 0, b = 1;
  double longest = -1;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (const double l = (y[i] - y[j]).squaredNorm(); l > longest) longest = l, a = i, b = j;
  const Vector3d m = 0.5 * (y[a] + y[b]);
  std::array<Vector3d, 4> half = y;
  half[a] = m;
  if (net_can_cross(half, M, depth - 1)) return true;
  half = y;
  half[b] = m;
  return net_can_cross(half, M, depth - 1);
}

}  // namespace

bool quadric_may_vanish(const std::array<Eigen::Vector3d, 4>& corners, const Quadric& q, const Eigen::Vector3d& origin,
                        int depth) {
  std::array<Eigen::Vector3d, 4> y;
  for (int i = 0; i < 4; ++i) y[i] = corners[i] - origin;
  return net_can_cross(y, q.matrix(), depth);
}

bool is_degenerate_tetrahedron(const std::array<Eigen::Vector3d, 4>& p, double rel_eps) {
  double diam = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) diam = std::max(diam, (p[i] - p[j]).norm());
  if (!(diam > 0.0) || !std::isfinite(diam)) return true;
  const double vol6 = std::abs((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]));
  return !(vol6 > rel_eps * diam * diam * diam);
}

double tetrahedron_thickness(const std::array<Eigen::Vector3d, 4>& p) {
  double thickness = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d &a = p[(i + 1) % 4], &b = p[(i + 2) % 4], &c = p[(i + 3) % 4];
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() > 0) thickness = std::min(thickness, std::abs(n.normalized().dot(p[i] - a)));
  }
  return std::isfinite(thickness) ? thickness : 0.0;
}

std::vector<std::array<Eigen::Vector3d, 4>> clip_tetrahedron(const std::array<Eigen::Vector3d, 4>& t, int axis,
                                                             double limit, int side) {
  using V = Eigen::Vector3d;
  std::array<int, 4> in{}, out{};
  int ni = 0, no = 0;
  for (int i = 0; i < 4; ++i) (side * t[i][axis] <= side * limit ? in[ni++] : out[no++]) = i;
  if (no == 0) return {t};
  if (ni == 0) return {};
  // Where edge a (inside) → b (outside) crosses the plane; the axis coordinate is set exactly.
  const auto cut = [&](int a, int b) {
    const double s = (limit - t[a][axis]) / (t[b][axis] - t[a][axis]);
    V p = t[a] + s * (t[b] - t[a]);
    p[axis] = limit;
    return p;
  };
  // Prism with triangles (a, b, c) and (a', b', c') and planar quads, split without a cyclic
  // choice of diagonals.
  const auto prism = [](const V& a, const V& b, const V& c, const V& a2, const V& b2, const V& c2) {
    return std::vector<std::array<V, 4>>{{a, b, c, a2}, {b, c, a2, b2}, {c, a2, b2, c2}};
  };
  if (ni == 1) return {{t[in[0]], cut(in[0], out[0]), cut(in[0], out[1]), cut(in[0], out[2])}};
  if (ni == 3) {
    const int d = out[0];
    return prism(t[in[0]], t[in[1]], t[in[2]], cut(in[0], d), cut(in[1], d), cut(in[2], d));
  }
  // Two inside (a, b), two outside (c, d): triangles (a, ac, ad) and (b, bc, bd).
  const int a = in[0], b = in[1], c = out[0], d = out[1];
  return prism(t[a], cut(a, c), cut(a, d), t[b], cut(b, c), cut(b, d));
}

std::vector<std::array<Eigen::Vector3d, 4>> clip_tetrahedron_to_box(const std::array<Eigen::Vector3d, 4>& t,
                                                                    const Eigen::Vector3d& lo,
                                                                    const Eigen::Vector3d& hi) {
  std::vector<std::array<Eigen::Vector3d, 4>> pieces{t}, next;
  for (int axis = 0; axis < 3; ++axis)
    for (const int side : {-1, 1}) {
      next.clear();
      for (const auto& p : pieces) {
        const auto clipped = clip_tetrahedron(p, axis, side < 0 ? lo[axis] : hi[axis], side);
        next.insert(next.end(), clipped.begin(), clipped.end());
      }
      pieces.swap(next);
    }
  return pieces;
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
