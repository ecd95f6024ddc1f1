// Internals shared by the skin-surface builders. See convert/skin_detail.h.
#include "convert/skin_detail.h"

#include <algorithm>

#include <Eigen/QR>
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

Rgb skin_corner_colour(const std::vector<Ball>& balls, const std::vector<int>& simplex, const Vector3d& p,
                       double shrink, const Vector3d& x) {
  const int k = static_cast<int>(simplex.size());
  Eigen::VectorXd w = Eigen::VectorXd::Ones(1);
  if (k > 1) {
    const Vector3d e = (x - shrink * p) / (1.0 - shrink);
    const Vector3d p0 = balls[simplex[0]].centre;
    Eigen::MatrixXd M(3, k - 1);
    for (int i = 1; i < k; ++i) M.col(i - 1) = balls[simplex[i]].centre - p0;
    const Eigen::VectorXd a = M.colPivHouseholderQr().solve(e - p0);  // least squares: onto the hull
    w.resize(k);
    w[0] = 1.0 - a.sum();
    w.tail(k - 1) = a;
    w = w.cwiseMax(0.0);
    if (!(w.sum() > 0)) w.setOnes();
    w /= w.sum();
  }
  Rgb out;
  for (int ch = 0; ch < 3; ++ch) {
    double v = 0;
    for (int i = 0; i < std::max(k, 1); ++i) v += w[i] * balls[simplex[i]].colour[ch];
    out[ch] = static_cast<std::uint8_t>(std::clamp(v + 0.5, 0.0, 255.0));
  }
  return out;
}

PatchEmitter::PatchEmitter(const std::vector<Ball>& balls, SkinConversion& out, double shrink)
    : balls_(balls), out_(out), shrink_(shrink) {
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
  std::array<Rgb, 4> corner_colours;
  for (std::size_t k = 0; k < 4; ++k)
    corner_colours[k] = skin_corner_colour(balls_, simplex_balls, sq.p, shrink_, corners[k]);
  t.corner_colours = corner_colours;
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
