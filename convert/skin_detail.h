#pragma once
/// Internals shared by the two skin-surface builders (convert/skin_cgal.cpp: CGAL's triangulated
/// mixed complex; convert/skin_regular.cpp: our own mixed complex over CGAL's regular
/// triangulation). Not a public header: it includes CGAL's kernel.
#include <array>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <Eigen/Core>

#include "convert/skin.h"
#include "core/quadric.h"

namespace quadrix::skin_detail {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using WeightedPoint = K::Weighted_point_3;

inline Eigen::Vector3d to_eigen(const K::Point_3& p) { return {p.x(), p.y(), p.z()}; }

/// The weighted points as CGAL's Skin_surface_3 inserts them (grow_balls): weight r²/s, so that
/// an isolated ball's skin is its own sphere.
std::vector<WeightedPoint> grown_weighted_points(const std::vector<Ball>& balls, double shrink);

/// The skin quadric of a simplex of the regular triangulation (1 to 4 grown weighted points) in
/// world coordinates: value(x) = (x − p)ᵀQ(x − p) + c, the closed forms of CGAL's
/// Skin_surface_quadratic_surface_3.h (p the weighted circumcentre, c = s(1−s)·squared radius of
/// the smallest orthogonal sphere, Q from the simplex's direction).
struct SkinQuadric {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Matrix3d Q = Eigen::Matrix3d::Zero();
  double c = 0;

  double value(const Eigen::Vector3d& x) const { return (x - p).dot(Q * (x - p)) + c; }
  /// The quadric relative to the point g: f(y) = value(y + g).
  Quadric relative_to(const Eigen::Vector3d& g) const;
};
SkinQuadric skin_quadric(const std::vector<WeightedPoint>& simplex, double shrink);

/// The refinement depth of quadric_may_vanish (core/bounds.h) patches are kept with.
inline constexpr int kCrossingDepth = 6;

/// Turns the tetrahedra of a mixed cell into patches of `out.model`: clipped to the box of the
/// simplex's balls (the skin body inside a mixed cell lies in the union of those balls), slivers
/// and tetrahedra the surface cannot cross skipped, coloured by the simplex's ball nearest in
/// power distance to the tetrahedron's centroid, and per corner by the simplex's balls blended
/// (skin_corner_colour) so neighbouring atoms' colours meet smoothly.
class PatchEmitter {
 public:
  /// shrink: the skin's s (the corner colours' blend follows the mixed cells it makes).
  PatchEmitter(const std::vector<Ball>& balls, SkinConversion& out, double shrink = 0.5);
  /// Returns the number of patches written.
  std::size_t emit(const std::vector<int>& simplex_balls, const SkinQuadric& q,
                   const std::array<Eigen::Vector3d, 4>& corners);

 private:
  std::size_t emit_piece(const std::vector<int>& simplex_balls, const SkinQuadric& q,
                         const std::array<Eigen::Vector3d, 4>& corners);
  const std::vector<Ball>& balls_;
  SkinConversion& out_;
  double size_ = 0;  // diagonal of the balls' centres' box
  double shrink_ = 0.5;
};

/// The colour at x inside the mixed cell of a simplex of balls (1 to 4, weighted circumcentre p,
/// shrink s): x = s·v + (1 − s)·e with v on the dual Voronoi face and e in the simplex, so e's
/// barycentric coordinates in the simplex (from (x − s·p)/(1 − s) projected onto its hull) blend
/// the balls' colours: the pure ball colour at a ball's own cell, continuous across cells.
Rgb skin_corner_colour(const std::vector<Ball>& balls, const std::vector<int>& simplex, const Eigen::Vector3d& p,
                       double shrink, const Eigen::Vector3d& x);

/// SkinTetrahedra::regular: our own mixed complex over CGAL's regular triangulation
/// (convert/skin_regular.cpp). Balls and options already validated.
SkinConversion convert_skin_regular(const std::vector<Ball>& balls, const SkinOptions& options);

}  // namespace quadrix::skin_detail
