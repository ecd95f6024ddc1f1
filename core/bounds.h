#pragma once
/// Bounding volumes that clip quadric patches, and the per-quadric backface culling tests
/// ([Stoll06] §4.4.4, eq. 17–19).
#include <array>
#include <vector>

#include <Eigen/Core>

#include "core/quadric.h"

namespace quadrix {

struct Sphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 1.0;
  bool contains(const Eigen::Vector3d& p, double eps = 0.0) const {
    return (p - centre).squaredNorm() <= (radius + eps) * (radius + eps);
  }
};

/// Tetrahedron with inward face planes, precomputed for containment tests.
class Tetrahedron {
public:
  explicit Tetrahedron(const std::array<Eigen::Vector3d, 4>& corners);
  const std::array<Eigen::Vector3d, 4>& corners() const { return p_; }
  /// Signed volume (positive when corners 1,2,3 are counter-clockwise seen from corner 0).
  double signed_volume() const;
  /// Barycentric coordinates of x.
  Eigen::Vector4d barycentric(const Eigen::Vector3d& x) const;
  /// True when every barycentric coordinate is ≥ −eps (eps relative: 1e-12 is a tight default).
  bool contains(const Eigen::Vector3d& x, double eps = 1e-12) const;
  /// Largest edge length.
  double diameter() const;

private:
  std::array<Eigen::Vector3d, 4> p_;
  Eigen::Matrix3d inv_;  // maps x − p₀ to barycentric coordinates 1..3 (relative: keeps digits far from 0)
};

/// Can the quadric change sign inside the tetrahedron? q is relative to `origin` (f(y), y = x −
/// origin; e.g. a TetPatch's centroid). Its quadratic Bézier control net over the tetrahedron,
/// b_ij = ỹᵢᵀQ̃ỹⱼ, bounds it: a net of one strict sign means no zero inside. With depth > 0 a
/// straddling net is refined by splitting the tetrahedron at its longest edge (up to 2^depth
/// pieces), which converges to the exact answer from above (never false for a crossed one).
bool quadric_may_vanish(const std::array<Eigen::Vector3d, 4>& corners, const Quadric& q, const Eigen::Vector3d& origin,
                        int depth = 0);

/// The one degeneracy limit for tetrahedra (stored patches, tetrahedral meshes, cells, clipped
/// pieces): a tetrahedron is degenerate when 6|volume| ≤ kDegenerateTetrahedron · L³, L its
/// longest edge. A regular tetrahedron has 6V/L³ ≈ 0.71.
inline constexpr double kDegenerateTetrahedron = 1e-12;

/// True when the tetrahedron is degenerate: 6|volume| ≤ rel_eps · L³ (L the longest edge), or
/// when an edge is not finite.
bool is_degenerate_tetrahedron(const std::array<Eigen::Vector3d, 4>& p, double rel_eps = kDegenerateTetrahedron);

/// The tetrahedron's smallest height: each corner's distance from the plane of the other three,
/// the least of the four (0 for a flat one).
double tetrahedron_thickness(const std::array<Eigen::Vector3d, 4>& p);

/// The part of tetrahedron t inside the half-space {x : x[axis]·side ≤ limit·side} (side = ±1)
/// as 0 to 3 tetrahedra that tile it exactly: 1 corner inside gives one tetrahedron, 2 or 3 give
/// a triangular prism split into three. New corners lie on the plane exactly (their `axis`
/// coordinate is `limit`). Pieces may be degenerate when the plane meets a corner; callers drop
/// them with is_degenerate_tetrahedron.
std::vector<std::array<Eigen::Vector3d, 4>> clip_tetrahedron(const std::array<Eigen::Vector3d, 4>& t, int axis,
                                                             double limit, int side);
/// The part of t inside the axis-aligned box [lo, hi] (six clip_tetrahedron steps), as tetrahedra.
std::vector<std::array<Eigen::Vector3d, 4>> clip_tetrahedron_to_box(const std::array<Eigen::Vector3d, 4>& t,
                                                                    const Eigen::Vector3d& lo,
                                                                    const Eigen::Vector3d& hi);

/// Per-quadric backface test for a bounding sphere ([Stoll06] eq. 18): q_eye is the quadric in
/// eye-at-origin coordinates (Quadric::translated_to_origin), centre_eye the sphere centre
/// relative to the eye. True means no ray from the eye meets the quadric front-facing inside
/// the sphere, so the patch may be culled: c′ < −c′ₛₚₕᵀb′ − r‖b′‖.
bool sphere_backfacing(const Quadric& q_eye, const Eigen::Vector3d& centre_eye, double radius);

/// Per-quadric backface test for a bounding tetrahedron ([Stoll06] eq. 19):
/// c′ < −maxᵢ p′ᵢᵀb′ with corners relative to the eye.
bool tetrahedron_backfacing(const Quadric& q_eye, const std::array<Eigen::Vector3d, 4>& corners_eye);

}  // namespace quadrix
