#include "convert/quads.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <span>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/bounds.h"
#include "core/culling.h"
#include "core/error.h"
#include "core/log.h"

namespace quadrix {
namespace {

using Eigen::Vector3d;
using Corners = std::array<Vector3d, 4>;

constexpr double kEps = std::numeric_limits<double>::epsilon();
// Stored quadric tetrahedra must be thicker than the .qxm reader's degeneracy limit, with margin.
constexpr double kMinTetVolume6 = 4 * kDegenerateTetrahedron;
// Safety factor on the first-order rounding bound of a quadric's coefficients.
constexpr double kRoundingFactor = 1.0;
// Smallest relative distance to a paraboloid's second sheet (quadric_quality) that ray casting in
// double resolves: the discriminant keeps ~separation² / eps ≈ 5e5 of margin (1e-6 still lost
// rays at 1.1e-6 in the random-quad test).
constexpr double kMinSeparation = 1e-5;

double diameter(std::span<const Vector3d> p) {
  double d = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) d = std::max(d, (p[i] - p[j]).norm());
  return d;
}

double det3(const Corners& p) { return (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]); }

// The tetrahedron's corners in positive orientation (a swap leaves the clip volume unchanged).
std::array<Vector3d, 4> oriented(std::array<Vector3d, 4> t) {
  if ((t[1] - t[0]).cross(t[2] - t[0]).dot(t[3] - t[0]) < 0.0) std::swap(t[2], t[3]);
  return t;
}

struct Emitter {
  const QuadConvertOptions& options;
  std::vector<TetPatch>& out;
  double deviation = 0.0;  // largest relative deviation estimate of this face

  /// q already relative to the tetrahedron's centroid (TetPatch's convention).
  void push_local(const std::array<Vector3d, 4>& corners, const Quadric& q) {
    out.push_back({oriented(corners), q, options.colour});
  }

  /// The triangle's plane clipped by the tetrahedron with apex a = centroid + h·n and base
  /// bᵢ = 2vᵢ − a: the triangle is exactly its cross-section (vᵢ = midpoints of a–bᵢ).
  void flat_triangle(const Vector3d& v0, const Vector3d& v1, const Vector3d& v2) {
    const Vector3d n = (v1 - v0).cross(v2 - v0).normalized();
    const Vector3d c = (v0 + v1 + v2) / 3.0;
    const double edge = std::max({(v1 - v0).norm(), (v2 - v1).norm(), (v0 - v2).norm()});
    const Vector3d a = c + options.flat_height * edge * n;
    const std::array<Vector3d, 4> corners = {a, 2.0 * v0 - a, 2.0 * v1 - a, 2.0 * v2 - a};
    // The plane through the vᵢ relative to the tetrahedron's centroid o, from the (exact, for a
    // small triangle far from the origin) differences vᵢ − o: a world-space offset −n·c would
    // cost the digits of ‖c‖ (2e-8 of a 1e-4 triangle at 1e4 from the origin).
    const Vector3d o = 0.25 * ((corners[0] + corners[1]) + (corners[2] + corners[3]));  // centroid()
    const double d = -n.dot(((v0 - o) + (v1 - o) + (v2 - o)) / 3.0);
    push_local(corners, Quadric::plane(n, d));
  }
};

// The hyperbolic paraboloid of the bilinear patch over p ([Stoll06] eq. 1, 20). In the affine
// frame x = p0 + y₁a + y₂b + y₃w (a = p1 − p0, b = p3 − p0, w = L·unit normal of a×b) the corners
// are (0,0,0), (1,0,0), (1+e, 1+f, g), (0,1,0) with d = p0 − p1 + p2 − p3 = e·a + f·b + g·w, and
// s(u,v) = (u(1+ve), v(1+uf), uvg) lies on g²y₁y₂ − fg·y₁y₃ − eg·y₂y₃ + ef·y₃² − g·y₃ = 0
// (eq. 20 halved). e, f, g come from d directly (no cancellation as the quad flattens), so the
// coefficients keep their relative precision; the frame is then moved to (x − o)/L and to world.
// Equivalently λ₀λ₂ = λ₁λ₃ in the tetrahedron's barycentric coordinates, which are the bilinear
// weights of s(u,v): the paraboloid meets the tetrahedron exactly in the patch.
Quadric paraboloid(const Corners& p, const Vector3d& o, double L) {
  const Vector3d a = (p[1] - p[0]) / L, b = (p[3] - p[0]) / L;
  const Vector3d w = a.cross(b).normalized();
  const Vector3d d = ((p[0] - p[1]) + (p[2] - p[3])) / L;
  Eigen::Matrix3d T;
  T << a, b, w;
  const Vector3d efg = T.partialPivLu().solve(d);
  const double e = efg.x(), f = efg.y(), g = efg.z();
  Eigen::Matrix4d Q = Eigen::Matrix4d::Zero();  // symmetric, in y
  Q(0, 1) = Q(1, 0) = 0.5 * g * g;
  Q(0, 2) = Q(2, 0) = -0.5 * f * g;
  Q(1, 2) = Q(2, 1) = -0.5 * e * g;
  Q(2, 2) = e * f;
  Q(2, 3) = Q(3, 2) = -0.5 * g;
  const double scale = Q.cwiseAbs().maxCoeff();
  Quadric canonical = Quadric::from_matrix(Q / scale);
  // y ↦ local coordinates (x − o)/L = (p0 − o)/L + T·y.
  Eigen::Affine3d M = Eigen::Affine3d::Identity();
  M.linear() = T;
  M.translation() = (p[0] - o) / L;
  Quadric local = canonical.transformed(M);
  const Vector3d centre = (0.25 * (p[0] + p[1] + p[2] + p[3]) - o) / L;
  if (local.gradient(centre).dot((p[2] - p[0]).cross(p[3] - p[1])) < 0.0) local = local * -1.0;
  // Relative to o (the caller passes the centroid), unscaled: TetPatch's convention.
  return local.normalized().from_local(Vector3d::Zero(), L).normalized();
}

// How well a stored paraboloid piece (relative to its centroid, y = x − o) can be evaluated and
// ray cast in double, from ‖∇f‖ sampled at the piece's corners, edge midpoints and centre (its
// minimum over the piece):
// - deviation: first-order bound on how far rounding the coefficients moves the surface,
//   eps · (‖A‖R² + 2‖b‖R + |c|) / min ‖∇f‖ (R = the farthest sample), world units. Measured
//   deviations are 10–50× smaller.
// - separation: min ‖∇f‖ / (‖A‖ · ℓ), ℓ = the piece's diameter. A paraboloid close to a double
//   plane (g ≪ 1, or near a corner whose two edges are nearly collinear) has a second sheet about
//   separation · ℓ from the patch, so every ray meets two roots that close together: the
//   discriminant β² − αγ loses its digits to cancellation (relative error ~ eps / separation²),
//   turns negative (a hole) or moves the hit by ~ eps·ℓ / separation.
struct QuadricQuality {
  double deviation = std::numeric_limits<double>::infinity();
  double separation = 0.0;
};
QuadricQuality quadric_quality(const Quadric& f, std::span<const Vector3d> y, double ell) {
  double R = 0, g = std::numeric_limits<double>::infinity();
  for (const auto& x : y) {
    R = std::max(R, x.norm());
    g = std::min(g, f.gradient(x).norm());
  }
  QuadricQuality q;
  if (!(g > 0.0)) return q;
  const double size = f.A.cwiseAbs().sum() * R * R + 2.0 * f.b.cwiseAbs().sum() * R + std::abs(f.c);
  q.deviation = kRoundingFactor * kEps * size / g;
  const double curvature = f.A.norm() * ell;
  q.separation = curvature > 0.0 ? g / curvature : std::numeric_limits<double>::infinity();
  return q;
}

struct QuadCase {
  bool flat = false;
  bool split = false;
};

class QuadConverter {
public:
  QuadConverter(const Corners& p, Emitter& emit) : p_(p), emit_(emit), L_(diameter(p)) {}

  /// Returns whether it was stored flat, as a quadric, or needed splitting.
  QuadCase run() {
    QuadCase result;
    piece(0, 1, 0, 1, 0, result);
    return result;
  }

private:
  Vector3d s(double u, double v) const {  // [Stoll06] eq. 1
    return (1 - v) * ((1 - u) * p_[0] + u * p_[1]) + v * ((1 - u) * p_[3] + u * p_[2]);
  }

  // One piece [u0,u1]×[v0,v1] of the patch: flat when its triangles are within the tolerance,
  // else the quadric when its coefficients are accurate enough (rounding_deviation), else halved
  // (along a ruling: exact, straight split lines). Both errors shrink 4× per halving in both
  // directions (the twist and the piece's extent relative to its centroid go as its size²), so
  // the halving ends; at max_split_depth the better of the two is stored and reported.
  void piece(double u0, double u1, double v0, double v1, int depth, QuadCase& result) {
    const Corners c = {s(u0, v0), s(u1, v0), s(u1, v1), s(u0, v1)};
    const double L = diameter(c);
    const double tolerance = emit_.options.planar_threshold * L_;  // relative to the whole quad
    // Split along the diagonal whose smaller triangle (signed, along the quad normal) is largest.
    const Vector3d n = (c[2] - c[0]).cross(c[3] - c[1]);
    const auto area = [&](int i, int j, int k) { return 0.5 * (c[j] - c[i]).cross(c[k] - c[i]).dot(n.normalized()); };
    const double min02 = std::min(area(0, 1, 2), area(0, 2, 3));
    const double min13 = std::min(area(0, 1, 3), area(1, 2, 3));
    const bool along02 = min02 >= min13;
    const double a_min = std::max(min02, min13);
    const double vol6 = std::abs(det3(c));
    const double flat_dev = a_min > 0.0 ? vol6 / (8.0 * a_min) : std::numeric_limits<double>::infinity();
    const auto flat = [&] {
      const double floor = emit_.options.degenerate_area * L * L;
      const auto tri = [&](int i, int j, int k) {
        if (area(i, j, k) > floor) emit_.flat_triangle(c[i], c[j], c[k]);
      };
      if (along02) {
        tri(0, 1, 2), tri(0, 2, 3);
      } else {
        tri(0, 1, 3), tri(1, 2, 3);
      }
      emit_.deviation = std::max(emit_.deviation, flat_dev / L_);
    };
    if (flat_dev <= tolerance) {
      if (depth == 0) result.flat = true;
      flat();
      return;
    }
    // The quadric, relative to the tetrahedron's centroid (TetPatch's convention).
    const Vector3d o = 0.25 * ((c[0] + c[1]) + (c[2] + c[3]));  // == TetPatch::centroid()
    std::optional<Quadric> f;
    bool separated = false;
    double quadric_dev = std::numeric_limits<double>::infinity();
    if (vol6 > kMinTetVolume6 * L * L * L) {
      f = paraboloid(c, o, L);
      const double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1);
      const std::array<Vector3d, 9> y = {c[0] - o,          c[1] - o,          c[2] - o,
                                         c[3] - o,          s(um, v0) - o,     s(u1, vm) - o,
                                         s(um, v1) - o,     s(u0, vm) - o,     s(um, vm) - o};
      const QuadricQuality quality = quadric_quality(*f, y, L);
      quadric_dev = quality.deviation;
      separated = quality.separation >= kMinSeparation;
    }
    const auto quadric = [&] {
      emit_.push_local(c, *f);
      emit_.deviation = std::max(emit_.deviation, quadric_dev / L_);
    };
    // A quadric too close to its second sheet would lose rays' roots to it (splitting raises the
    // separation in proportion to 1/size, flattening lowers the twist): split while allowed.
    if (quadric_dev <= tolerance && separated) {
      quadric();
      return;
    }
    if (depth >= emit_.options.max_split_depth) {
      // Fold lines of self-intersecting quads keep the separation ~g² there at every size.
      if (f && (quadric_dev <= tolerance || quadric_dev < flat_dev)) {
        quadric();
      } else {
        flat();
      }
      return;
    }
    // Halve along the longer parameter direction; the split line is a ruling (a straight line).
    result.split = true;
    const double du = (c[1] - c[0]).norm() + (c[2] - c[3]).norm();
    const double dv = (c[3] - c[0]).norm() + (c[2] - c[1]).norm();
    if (du >= dv) {
      const double um = 0.5 * (u0 + u1);
      piece(u0, um, v0, v1, depth + 1, result);
      piece(um, u1, v0, v1, depth + 1, result);
    } else {
      const double vm = 0.5 * (v0 + v1);
      piece(u0, u1, v0, vm, depth + 1, result);
      piece(u0, u1, vm, v1, depth + 1, result);
    }
  }

  Corners p_;
  Emitter& emit_;
  double L_;
};

// Newell's normal: twice the vector area of a polygon, relative to its first corner (world
// coordinates far from the origin would cancel every digit of a small face's area).
Vector3d newell(std::span<const Vector3d> p) {
  Vector3d n = Vector3d::Zero();
  for (std::size_t i = 1; i + 1 < p.size(); ++i) n += (p[i] - p[0]).cross(p[i + 1] - p[0]);
  return n;
}

// Ear clipping in the polygon's Newell plane; a fan where no ear is found (self-intersecting).
std::vector<std::array<int, 3>> triangulate(std::span<const Vector3d> p) {
  const Vector3d n = newell(p).normalized();
  const Vector3d ex = n.unitOrthogonal(), ey = n.cross(ex);
  std::vector<Eigen::Vector2d> q;
  for (const auto& x : p) q.emplace_back(x.dot(ex), x.dot(ey));
  const auto cross = [&](int a, int b, int c) {
    const Eigen::Vector2d u = q[b] - q[a], v = q[c] - q[a];
    return u.x() * v.y() - u.y() * v.x();
  };
  std::vector<int> ring(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) ring[i] = static_cast<int>(i);
  std::vector<std::array<int, 3>> tris;
  while (ring.size() > 3) {
    bool found = false;
    for (std::size_t i = 0; i < ring.size() && !found; ++i) {
      const int a = ring[(i + ring.size() - 1) % ring.size()], b = ring[i], c = ring[(i + 1) % ring.size()];
      if (cross(a, b, c) <= 0.0) continue;
      bool empty = true;
      for (int r : ring) {
        if (r == a || r == b || r == c) continue;
        if (cross(a, b, r) >= 0.0 && cross(b, c, r) >= 0.0 && cross(c, a, r) >= 0.0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      tris.push_back({a, b, c});
      ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(i));
      found = true;
    }
    if (!found) {  // fan over what is left
      for (std::size_t i = 1; i + 1 < ring.size(); ++i) tris.push_back({ring[0], ring[i], ring[i + 1]});
      return tris;
    }
  }
  tris.push_back({ring[0], ring[1], ring[2]});
  return tris;
}

enum class FaceCase { quadric, flat, split, collapsed, triangle, polygon, skipped };

struct FaceResult {
  std::vector<TetPatch> tets;
  FaceCase kind = FaceCase::triangle;
  double deviation = 0.0;
};

FaceResult convert_face(const PolygonMesh& mesh, std::size_t f, const QuadConvertOptions& options) {
  FaceResult r;
  Emitter emit{options, r.tets};
  std::vector<int> idx;
  for (int i : mesh.face(f)) {
    if (i < 0 || static_cast<std::size_t>(i) >= mesh.vertices.size())
      throw InvalidInput(fmt::format("{}: face {}: vertex index {} out of range (0..{})", options.source, f, i,
                                     mesh.vertices.size()));
    if (!mesh.vertices[i].allFinite())
      throw InvalidInput(fmt::format("{}: face {}: vertex {} has a non-finite coordinate", options.source, f, i));
    idx.push_back(i);
  }
  const std::size_t sides = idx.size();
  std::vector<Vector3d> p;
  for (int i : idx) p.push_back(mesh.vertices[i]);
  const double L = diameter(p);
  const double area = 0.5 * newell(p).norm();
  // Repeated corners (same index or same position), cyclically adjacent, collapse.
  std::vector<Vector3d> distinct;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vector3d& next = p[(i + 1) % p.size()];
    // Corners within the tolerance of each other merge (moves the surface by less than it).
    if ((p[i] - next).norm() > std::max(options.degenerate_area, options.planar_threshold) * L) distinct.push_back(p[i]);
  }
  if (!(L > 0.0) || !(area > options.degenerate_area * L * L) || distinct.size() < 3) {
    if (!options.skip_degenerate)
      throw InvalidInput(fmt::format("{}: face {} ({} sides, vertices {}) has zero area ({:.3g}, diameter {:.3g})",
                                     options.source, f, sides, fmt::join(idx, " "), area, L));
    r.kind = FaceCase::skipped;
    return r;
  }
  if (distinct.size() == 3) {
    emit.flat_triangle(distinct[0], distinct[1], distinct[2]);
    r.kind = sides == 3 ? FaceCase::triangle : FaceCase::collapsed;
  } else if (distinct.size() == 4) {
    QuadConverter quad({distinct[0], distinct[1], distinct[2], distinct[3]}, emit);
    const QuadCase c = quad.run();
    r.kind = c.split ? FaceCase::split : c.flat ? FaceCase::flat : FaceCase::quadric;
    if (sides != 4) r.kind = FaceCase::polygon;
  } else {
    const double floor = options.degenerate_area * L * L;
    for (const auto& t : triangulate(distinct)) {
      const Vector3d& a = distinct[t[0]];
      const Vector3d& b = distinct[t[1]];
      const Vector3d& c = distinct[t[2]];
      if (0.5 * (b - a).cross(c - a).norm() > floor) emit.flat_triangle(a, b, c);
    }
    r.kind = FaceCase::polygon;
  }
  r.deviation = emit.deviation;
  return r;
}


// A closed, consistently oriented surface with outward normals: every directed edge (a, b) is
// used once and its reverse once (no boundary, no non-manifold or flipped edge), and the
// enclosed signed volume is positive. Back sides of such a surface are never seen from outside.
bool is_closed_outward(const PolygonMesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  double volume6 = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto face = mesh.face(f);
    if (face.size() < 3) return false;
    for (std::size_t i = 0; i < face.size(); ++i) {
      const int a = face[i], b = face[(i + 1) % face.size()];
      if (a == b || ++directed[{a, b}] > 1) return false;
    }
    const Vector3d& p0 = mesh.vertices[face[0]];
    for (std::size_t i = 1; i + 1 < face.size(); ++i)
      volume6 += p0.dot(mesh.vertices[face[i]].cross(mesh.vertices[face[i + 1]]));
  }
  for (const auto& [edge, count] : directed)
    if (!directed.contains({edge.second, edge.first})) return false;
  return !directed.empty() && volume6 > 0.0;
}

}  // namespace

QuadConversion convert_quads(const PolygonMesh& mesh, const QuadConvertOptions& options) {
  if (!(options.planar_threshold >= 0.0) || !(options.flat_height > 0.0) || !(options.degenerate_area >= 0.0))
    throw InvalidInput(fmt::format("convert quads: bad options (planar_threshold {}, flat_height {}, degenerate_area {})",
                                   options.planar_threshold, options.flat_height, options.degenerate_area));
  const std::size_t n = mesh.face_count();
  std::vector<FaceResult> faces(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f < r.end(); ++f) faces[f] = convert_face(mesh, f, options);
  });
  QuadConversion out;
  out.tet_offsets.reserve(n + 1);
  out.tet_offsets.push_back(0);
  std::size_t total = 0;
  for (const auto& r : faces) total += r.tets.size();
  out.model.tets.reserve(total);
  auto& c = out.counts;
  std::size_t polygons_logged = 0;
  for (std::size_t f = 0; f < n; ++f) {
    FaceResult& r = faces[f];
    switch (r.kind) {
      case FaceCase::quadric: ++c.quadric_quads; break;
      case FaceCase::flat: ++c.flat_quads; break;
      case FaceCase::split: ++c.split_quads; break;
      case FaceCase::collapsed: ++c.collapsed_quads; break;
      case FaceCase::triangle: ++c.triangles; break;
      case FaceCase::skipped: ++c.degenerate_skipped; break;
      case FaceCase::polygon:
        ++c.polygons_triangulated;
        if (polygons_logged++ < 5)
          log::warn("{}: face {} has {} sides; triangulated", options.source, f, mesh.face(f).size());
        break;
    }
    out.max_relative_deviation = std::max(out.max_relative_deviation, r.deviation);
    out.model.tets.insert(out.model.tets.end(), r.tets.begin(), r.tets.end());
    out.tet_offsets.push_back(out.model.tets.size());
  }
  if (c.polygons_triangulated > polygons_logged)
    log::warn("{}: {} faces with more than four sides triangulated in all", options.source, c.polygons_triangulated);
  if (c.degenerate_skipped > 0) log::warn("{}: {} zero-area faces skipped", options.source, c.degenerate_skipped);
  if (c.degenerate_skipped == 0 && is_closed_outward(mesh)) out.model.metadata[kClosedKey] = "1";
  return out;
}

}  // namespace quadrix
