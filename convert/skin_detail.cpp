// Internals shared by the skin-surface builders. See convert/skin_detail.h.
#include "convert/skin_detail.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/bounds.h"
#include "core/error.h"

namespace quadrix::skin_detail {

using Eigen::Vector3d;

std::vector<WeightedPoint> grown_weighted_points(const std::vector<Ball>& balls, double shrink) {
  std::vector<WeightedPoint> wp;
  wp.reserve(balls.size());
  for (const auto& b : balls)
    wp.emplace_back(K::Point_3(b.centre.x(), b.centre.y(), b.centre.z()), b.radius * b.radius / shrink);
  return wp;
}

Quadric SkinQuadric::relative_to(const Vector3d& g) const {
  const Vector3d d = g - p;
  Quadric q;
  q.A = Q;
  q.b = Q * d;
  q.c = d.dot(Q * d) + c;
  return q;
}

SkinQuadric skin_quadric(const std::vector<WeightedPoint>& w, double s) {
  const K k;
  const auto centre = k.construct_weighted_circumcenter_3_object();
  const auto orthogonal_r2 = k.compute_squared_radius_smallest_orthogonal_sphere_3_object();
  SkinQuadric q;
  const auto I = Eigen::Matrix3d::Identity();
  switch (w.size()) {
    case 1:
      q.p = to_eigen(w[0].point());
      q.Q = (1 - s) * I;
      q.c = -s * (1 - s) * w[0].weight();
      break;
    case 2: {
      q.p = to_eigen(centre(w[0], w[1]));
      q.c = s * (1 - s) * orthogonal_r2(w[0], w[1]);
      const Vector3d t = (to_eigen(w[0].point()) - to_eigen(w[1].point())).normalized();
      q.Q = (1 - s) * I - t * t.transpose();
      break;
    }
    case 3: {
      q.p = to_eigen(centre(w[0], w[1], w[2]));
      q.c = s * (1 - s) * orthogonal_r2(w[0], w[1], w[2]);
      const Vector3d a = to_eigen(w[0].point()), b = to_eigen(w[1].point()), cc = to_eigen(w[2].point());
      const Vector3d t = (b - a).cross(cc - a).normalized();
      q.Q = t * t.transpose() - s * I;
      break;
    }
    case 4:
      q.p = to_eigen(centre(w[0], w[1], w[2], w[3]));
      q.c = s * (1 - s) * orthogonal_r2(w[0], w[1], w[2], w[3]);
      q.Q = -s * I;
      break;
    default: throw SolverError("skin: a simplex with no vertices");
  }
  return q;
}

PatchEmitter::PatchEmitter(const std::vector<Ball>& balls, SkinConversion& out) : balls_(balls), out_(out) {
  Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& b : balls) lo = lo.cwiseMin(b.centre), hi = hi.cwiseMax(b.centre);
  size_ = (hi - lo).norm();
}

std::size_t PatchEmitter::emit_piece(const std::vector<int>& simplex_balls, const SkinQuadric& sq,
                                     const std::array<Vector3d, 4>& corners) {
  // Slivers (corners coplanar on a cell face) hold no surface of positive area; the .qxm reader
  // rejects them (its test: 1e-12 of diameter³).
  if (is_degenerate_tetrahedron(corners)) {
    ++out_.slivers_skipped;
    return 0;
  }
  TetPatch t{corners, {}, std::nullopt};
  const Vector3d g = t.centroid();
  const Quadric q = sq.relative_to(g);
  if (!quadric_may_vanish(corners, q, g, kCrossingDepth)) return 0;
  t.quadric = q.normalized();
  // Colour: the simplex's ball nearest in power distance to the centroid.
  int best = simplex_balls[0];
  double bd = std::numeric_limits<double>::infinity();
  for (const int b : simplex_balls) {
    const double d = (g - balls_[b].centre).squaredNorm() - balls_[b].radius * balls_[b].radius;
    if (d < bd) bd = d, best = b;
  }
  t.colour = balls_[best].colour;
  out_.model.tets.push_back(t);
  return 1;
}

std::size_t PatchEmitter::emit(const std::vector<int>& simplex_balls, const SkinQuadric& q,
                               const std::array<Vector3d, 4>& corners) {
  // The skin body lies inside the union of the balls (a convex combination of balls lies inside
  // their union and shrinking only shrinks it), and inside a mixed cell only the balls of the
  // cell's simplex take part: each tetrahedron is clipped to the box of those balls. The model's
  // bounds, automatic framing and rasterised area then follow the molecule, not the bounding
  // octahedron, and no tetrahedron is much larger than its patch (float precision on the GPU).
  Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double rmax = 0;
  for (const int b : simplex_balls) {
    lo = lo.cwiseMin(balls_[b].centre - Vector3d::Constant(balls_[b].radius));
    hi = hi.cwiseMax(balls_[b].centre + Vector3d::Constant(balls_[b].radius));
    rmax = std::max(rmax, balls_[b].radius);
  }
  const double margin = 1e-3 * std::max(rmax, 1e-3 * size_);
  lo -= Vector3d::Constant(margin), hi += Vector3d::Constant(margin);
  bool inside = true;
  for (const auto& c : corners) inside = inside && (c.array() >= lo.array()).all() && (c.array() <= hi.array()).all();
  if (inside) return emit_piece(simplex_balls, q, corners);
  ++out_.tets_clipped_to_box;
  std::size_t n = 0;
  for (const auto& piece : clip_tetrahedron_to_box(corners, lo, hi)) n += emit_piece(simplex_balls, q, piece);
  return n;
}

}  // namespace quadrix::skin_detail
