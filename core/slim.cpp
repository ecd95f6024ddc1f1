#include "core/slim.h"

#include <algorithm>
#include <array>
#include <numbers>
#include <optional>
#include <cmath>
#include <cstdlib>
#include <limits>

#include <Eigen/Eigenvalues>

namespace quadrix {

double slim_weight(double r) {
  if (r < 0.0) r = -r;
  if (r < 0.5) return std::exp(-8.0 * r * r);
  if (r <= 1.0) {
    const double s = 1.0 - r;
    return 16.0 * std::exp(-2.0) * s * s * s * s;
  }
  return 0.0;
}

bool intersect_slim_patch(const SlimPatch& patch, const Ray& ray, double tmin, double tmax, Hit& hit) {
  // Local frame u = (x − c)/R; λ is unchanged when both origin and direction are scaled.
  // The local origin starts at the ray's closest approach to the centre so γ stays O(1).
  const double inv_r = 1.0 / patch.radius;
  Ray local;
  const double t0 = rebase_ray(ray, patch.centre, local);
  local.origin *= inv_r;
  local.dir *= inv_r;
  if (local.origin.squaredNorm() > 1.0) return false;  // the ray misses the ball
  const auto inside = [&](const Eigen::Vector3d& u) {
    return u.squaredNorm() <= 1.0 && patch.clips.keeps(u);
  };
  Hit h;
  if (!intersect_quadric(patch.local, local, tmin - t0, tmax - t0, /*cull_backfaces=*/true, inside, h)) return false;
  hit.t = h.t + t0;
  hit.point = ray.at(hit.t);
  hit.gradient = h.gradient * inv_r;
  hit.front_facing = true;
  return true;
}

SlimSlab slim_patch_slab(const SlimPatch& patch, double max_thickness) {
  SlimSlab slab;
  const Quadric& q = patch.local;
  const double bn = q.b.norm();
  if (!(bn > 0.0) || !q.A.allFinite() || !std::isfinite(q.c)) return slab;
  // Frame (t1, t2, e), e = b/‖b‖: u = s·e + w, g = c + 2‖b‖s + a·s² + 2s·mᵀw + wᵀA⊥w with
  // a = eᵀAe, m = A⊥e (the coupling), A⊥ the 2×2 block, ‖w‖ ≤ ρ(s) = √(1 − s²).
  const Eigen::Vector3d e = q.b / bn;
  const Eigen::Vector3d t1 =
      (std::abs(e.x()) < 0.9 ? e.cross(Eigen::Vector3d::UnitX()) : e.cross(Eigen::Vector3d::UnitY())).normalized();
  const Eigen::Vector3d t2 = e.cross(t1);
  const double a = e.dot(q.A * e);
  const double m = std::hypot(t1.dot(q.A * e), t2.dot(q.A * e));
  Eigen::Matrix2d P;
  P << t1.dot(q.A * t1), t1.dot(q.A * t2), t2.dot(q.A * t1), t2.dot(q.A * t2);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(P, Eigen::EigenvaluesOnly);
  const double mu_lo = eig.eigenvalues()(0), mu_hi = eig.eigenvalues()(1);
  // Interval test per bin of s and per distance r = ‖w‖ from the axis: over the bin, with
  // ‖w‖ = r, g lies in [lo(r), hi(r)]: lo(r) = min h − 2|s|m·r + μ_lo·r² and hi(r) = max h +
  // 2|s|m·r + μ_hi·r² (wᵀA⊥w = r²·(between A⊥'s eigenvalues)). The zero set can reach r only
  // where lo(r) ≤ 0 ≤ hi(r); a bin where no r ≤ ρ does is outside the slab, and the largest r
  // that does bounds the piece's reach from the axis there. Every term is bounded from above and
  // below over the bin, so the test is conservative; a relative margin covers the rounding of
  // the GPU's float copy.
  constexpr int kBins = 64;
  const double scale = std::abs(q.c) + 2.0 * bn + std::abs(a) + 2.0 * m + std::abs(mu_hi) + std::abs(mu_lo);
  const double margin = 1e-6 * scale;
  // The largest r in [0, rho] with lo(r) ≤ 0 ≤ hi(r), or −1: that set's largest point is rho or a
  // root of lo or hi.
  const auto reach = [&](double h_lo, double h_hi, double k, double rho) {
    std::array<double, 6> cand{};
    std::size_t count = 0;
    cand[count++] = rho;
    cand[count++] = 0.0;
    const auto roots = [&](double qa, double qb, double qc) {  // qa r² + qb r + qc = 0
      if (std::abs(qa) <= 1e-300) {
        if (qb != 0.0) cand[count++] = -qc / qb;
        return;
      }
      const double disc = qb * qb - 4.0 * qa * qc;
      if (disc < 0.0) return;
      const double sq = std::sqrt(disc);
      const double t = -0.5 * (qb + (qb >= 0.0 ? sq : -sq));
      cand[count++] = t / qa;
      if (t != 0.0) cand[count++] = qc / t;
    };
    roots(mu_lo, -k, h_lo - margin);
    roots(mu_hi, k, h_hi + margin);
    const double slack = 1e-12 * scale;
    double best = -1.0;
    for (std::size_t i = 0; i < count; ++i) {
      const double r = cand[i];
      if (!(r >= 0.0) || r > rho || r <= best) continue;
      const double lo = h_lo - k * r + mu_lo * r * r - margin, hi = h_hi + k * r + mu_hi * r * r + margin;
      if (lo <= slack && hi >= -slack) best = r;
    }
    return best;
  };
  std::array<double, kBins> bin_reach{};
  int first = -1, last = -1;
  for (int i = 0; i < kBins; ++i) {
    const double sa = -1.0 + 2.0 * i / kBins, sb = -1.0 + 2.0 * (i + 1) / kBins;
    const double s_abs = std::max(std::abs(sa), std::abs(sb));
    const double s_min_abs = (sa <= 0.0 && sb >= 0.0) ? 0.0 : std::min(std::abs(sa), std::abs(sb));
    const double rho = std::sqrt(std::max(0.0, 1.0 - s_min_abs * s_min_abs));
    // c + 2‖b‖s + a s² over [sa, sb]: a quadratic, extremes at the ends or its vertex.
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    const auto h = [&](double s) { return q.c + 2.0 * bn * s + a * s * s; };
    for (const double s : {sa, sb}) lo = std::min(lo, h(s)), hi = std::max(hi, h(s));
    if (a != 0.0) {
      const double sv = -bn / a;
      if (sv > sa && sv < sb) lo = std::min(lo, h(sv)), hi = std::max(hi, h(sv));
    }
    bin_reach[std::size_t(i)] = reach(lo, hi, 2.0 * s_abs * m, rho);
    if (bin_reach[std::size_t(i)] >= 0.0) {
      if (first < 0) first = i;
      last = i;
    }
  }
  slab.axis = e;
  if (first < 0) {  // the zero set misses the ball: nothing to draw, the thinnest slab will do
    slab.s0 = slab.s1 = std::clamp(-q.c / (2.0 * bn), -1.0, 1.0);
    slab.r0 = slab.r1 = std::sqrt(std::max(0.0, 1.0 - slab.s0 * slab.s0));
    slab.tight = true;
    return slab;
  }
  slab.s0 = -1.0 + 2.0 * first / kBins;
  slab.s1 = -1.0 + 2.0 * (last + 1) / kBins;
  slab.tight = slab.s1 - slab.s0 < max_thickness;
  if (!slab.tight) return SlimSlab{};
  // The frustum: the radius at each bin boundary is the larger of its two bins' reach, and a
  // radius linear in s above all of them holds the piece (linear over each bin, above both ends).
  // Of the lines along the upper hull's edges and the flat one at the largest reach, the one
  // whose frustum has the least surface area (four times its mean projected area, Cauchy).
  std::vector<Eigen::Vector2d> hull;  // (s, r), s increasing
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& x, const Eigen::Vector2d& y) {
    return (x - o).x() * (y - o).y() - (x - o).y() * (y - o).x();
  };
  for (int j = first; j <= last + 1; ++j) {
    double r = -1.0;
    if (j - 1 >= first) r = std::max(r, bin_reach[std::size_t(j - 1)]);
    if (j <= last) r = std::max(r, bin_reach[std::size_t(j)]);
    if (r < 0.0) continue;
    const Eigen::Vector2d p(-1.0 + 2.0 * j / kBins, r);
    while (hull.size() >= 2 && cross(hull[hull.size() - 2], hull.back(), p) >= 0.0) hull.pop_back();
    hull.push_back(p);
  }
  // A margin for the renderer's float ray: its hit passes the ball test r ≤ 1 a few float ulps
  // outside the ball (where the piece meets the ball's sphere, the frustum is tight).
  constexpr double kPad = 1e-4;
  for (auto& p : hull) p.y() += kPad;
  double widest = 0.0;
  for (const auto& p : hull) widest = std::max(widest, p.y());
  const double height = slab.s1 - slab.s0;
  const auto area = [&](double r0, double r1) {
    return r0 * r0 + r1 * r1 + (r0 + r1) * std::sqrt((r1 - r0) * (r1 - r0) + height * height);
  };
  slab.r0 = slab.r1 = widest;
  double best = area(widest, widest);
  for (std::size_t k = 0; k + 1 < hull.size(); ++k) {
    const Eigen::Vector2d &x = hull[k], &y = hull[k + 1];
    const double slope = (y.y() - x.y()) / (y.x() - x.x());
    const double r0 = std::max(0.0, x.y() + slope * (slab.s0 - x.x())), r1 = std::max(0.0, x.y() + slope * (slab.s1 - x.x()));
    if (const double f = area(r0, r1); f < best) best = f, slab.r0 = r0, slab.r1 = r1;
  }
  return slab;
}

double slim_offset_of(const Model& model) {
  if (const auto v = metadata_number(model, "slim_offset"); v && std::isfinite(*v) && *v >= 0.0) return *v;
  return SlimBlendOptions{}.offset;
}

SlimBlendOptions slim_blend_of(const Model& model, double offset) {
  SlimBlendOptions b;
  b.offset = offset >= 0 ? offset : slim_offset_of(model);
  if (const auto v = metadata_number(model, "slim_max_push"); v && *v > 0.0) b.max_push = *v;
  return b;
}

void sample_slim_patch(const SlimPatch& patch, int grid, std::vector<SlimSurfaceSample>& out) {
  constexpr int kRimRefine = 3;
  constexpr double kRim2 = 0.8 * 0.8;
  const int fine = grid * kRimRefine;
  const double step = 2.0 / fine;
  const std::size_t first = out.size();
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (int i = 0; i < fine; ++i)
      for (int j = 0; j < fine; ++j) {
        // Lines of the coarse lattice keep every root; the others only roots in the rim.
        const bool coarse = i % kRimRefine == kRimRefine / 2 && j % kRimRefine == kRimRefine / 2;
        Ray line;
        line.origin = Eigen::Vector3d::Zero();
        line.origin[a1] = -1.0 + (i + 0.5) * step;
        line.origin[a2] = -1.0 + (j + 0.5) * step;
        if (line.origin.squaredNorm() >= 1.0) continue;
        line.dir = Eigen::Vector3d::Unit(axis);
        const Roots roots = solve_ray_quadratic(ray_quadratic(patch.local, line));
        for (int k = 0; k < roots.count; ++k) {
          const Eigen::Vector3d u = line.at(roots.t[k]);
          const double r2 = u.squaredNorm();
          if (!(r2 < 1.0) || (!coarse && r2 <= kRim2) || !patch.clips.keeps(u)) continue;
          const Eigen::Vector3d g = patch.local.gradient(u);
          const double gn = g.norm();
          if (!(gn > 0.0)) continue;
          out.push_back({patch.centre + patch.radius * u, g / gn, std::sqrt(r2)});
        }
      }
  }
  if (out.size() - first < 4)
    for_thin_zero_set(patch, step / 16.0, [&](const Eigen::Vector3d& u) {
      const Eigen::Vector3d g = patch.local.gradient(u);
      if (const double gn = g.norm(); gn > 0.0) out.push_back({patch.centre + patch.radius * u, g / gn, u.norm()});
      return true;
    });
}

namespace {

// A quadric's principal axes (the eigenvectors of A, as columns) and its centre A c = −b, over
// the axes that bend within the ball (|λ| above 1e-3 of the largest); none for a plane or a
// centre that is not finite.
struct PrincipalFrame {
  Eigen::Matrix3d axes;
  Eigen::Vector3d centre;
};
std::optional<PrincipalFrame> principal_frame(const Quadric& q) {
  if (q.A.isZero(0.0)) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(q.A);
  const Eigen::Vector3d lambda = es.eigenvalues();
  const Eigen::Matrix3d V = es.eigenvectors();
  const double big = lambda.cwiseAbs().maxCoeff();
  Eigen::Vector3d c0 = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i)
    if (std::abs(lambda[i]) > 1e-3 * big) c0 -= V.col(i) * (V.col(i).dot(q.b) / lambda[i]);
  if (!c0.allFinite()) return std::nullopt;
  return PrincipalFrame{V, c0};
}

}  // namespace

void for_thin_zero_set(const SlimPatch& patch, double step, const std::function<bool(const Eigen::Vector3d&)>& f) {
  if (!(step > 0.0)) return;
  const auto frame = principal_frame(patch.local);
  if (!frame || !(frame->centre.squaredNorm() < 1.0)) return;
  const Eigen::Matrix3d& V = frame->axes;
  const Eigen::Vector3d& c0 = frame->centre;
  const int lines = static_cast<int>(std::ceil(2.0 / std::max(step, 2.0 / 4096.0)));
  const double h = 2.0 / lines;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      if (i == j) continue;
      for (int m = 0; m < lines; ++m) {
        const Ray line{c0 + (-1.0 + (m + 0.5) * h) * V.col(j), V.col(i)};
        if (line.origin.squaredNorm() >= 1.0) continue;
        const Roots roots = solve_ray_quadratic(ray_quadratic(patch.local, line));
        for (int k = 0; k < roots.count; ++k) {
          const Eigen::Vector3d u = line.at(roots.t[k]);
          if (!(u.squaredNorm() < 1.0) || !patch.clips.keeps(u)) continue;
          if (!f(u)) return;
        }
      }
    }
}

// The rim beside where each principal axis of the quadric, through its centre (over the axes
// that bend within the ball), leaves the ball: along the great circle the gradient's part on the
// sphere points along there (uphill where g is negative, downhill where positive), angles
// doubling until g changes sign, then bisected. An ellipsoid's tip just past the sphere leaves a
// nub inside whose rim is a loop smaller than the meridians' steps (a capsule fitted at 1e-2: a
// ball 50E across whose prolate zero set poked 2.9E past the capsule's end met its sphere in a
// loop 0.7E across, drawn as a nub while the fit's check said 0.7E).
void sample_slim_rim_at_axes(const SlimPatch& patch, std::vector<SlimSurfaceSample>& out) {
  const Quadric& q = patch.local;
  const auto frame = principal_frame(q);
  if (!frame) return;
  const Eigen::Matrix3d& V = frame->axes;
  const Eigen::Vector3d& c0 = frame->centre;
  constexpr double kRho = 1.0 - 1e-9;  // on the sphere, still drawn
  for (int i = 0; i < 3; ++i) {
    // Where the axis meets the sphere: |c0 + tV|² = 1.
    const Eigen::Vector3d v = V.col(i);
    const double pb = c0.dot(v), disc = pb * pb - (c0.squaredNorm() - 1.0);
    if (!(disc > 0.0)) continue;
    for (const double t : {-pb - std::sqrt(disc), -pb + std::sqrt(disc)}) {
      const Eigen::Vector3d u0 = (c0 + t * v).normalized();
      const double g0 = q.eval(u0);
      const Eigen::Vector3d grad = q.gradient(u0), gt = grad - grad.dot(u0) * u0;
      if (!(gt.squaredNorm() > 0.0) || g0 == 0.0) continue;
      const Eigen::Vector3d dir = (g0 < 0.0 ? 1.0 : -1.0) * gt.normalized();
      const auto on_circle = [&](double a) { return Eigen::Vector3d(std::cos(a) * u0 + std::sin(a) * dir); };
      double lo = 0.0, hi = 1e-4;
      while (hi < 1.0 && (q.eval(on_circle(hi)) < 0.0) == (g0 < 0.0)) lo = hi, hi *= 2.0;
      if (!(hi < 1.0)) continue;
      for (int it = 0; it < 40; ++it) {
        const double mid = 0.5 * (lo + hi);
        ((q.eval(on_circle(mid)) < 0.0) == (g0 < 0.0) ? lo : hi) = mid;
      }
      const Eigen::Vector3d u = kRho * on_circle(hi);
      const Eigen::Vector3d gu = q.gradient(u);
      if (patch.clips.keeps(u) && gu.norm() > 0.0) out.push_back({patch.centre + patch.radius * u, gu.normalized(), kRho});
    }
  }
}

void sample_slim_rim(const SlimPatch& patch, double spacing, std::vector<SlimSurfaceSample>& out) {
  const Quadric& q = patch.local;
  const Eigen::Vector3d g0 = q.gradient(Eigen::Vector3d::Zero());
  if (!(g0.norm() > 0.0) || !(spacing > 0.0)) return;
  const Eigen::Vector3d n = g0.normalized(), e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  constexpr double kRho = 1.0 - 1e-9;  // on the sphere, still drawn
  constexpr int kSteps = 48, kBisections = 12;
  // The steps' (cos θ, sin θ), θ = πk/kSteps, once.
  static const std::array<Eigen::Vector2d, kSteps + 1> kStep = [] {
    std::array<Eigen::Vector2d, kSteps + 1> a;
    for (int k = 0; k <= kSteps; ++k) a[k] = {std::cos(std::numbers::pi * k / kSteps), std::sin(std::numbers::pi * k / kSteps)};
    return a;
  }();
  // Along the meridian x(θ) = ρ(cos θ n + sin θ t), g is a trigonometric polynomial of degree 2:
  // ρ²(c² nAn + 2cs nAt + s² tAt) + 2ρ(c b·n + s b·t) + c₀, evaluated from (c, s) alone; a
  // bisection step takes the midpoint on the circle as the normalised sum of its ends.
  const Eigen::Vector3d An = q.A * n, Ae1 = q.A * e1, Ae2 = q.A * e2;
  const double nAn = n.dot(An), e1Ae1 = e1.dot(Ae1), e2Ae2 = e2.dot(Ae2), e1Ae2 = e1.dot(Ae2);
  const double nAe1 = n.dot(Ae1), nAe2 = n.dot(Ae2), bn = q.b.dot(n), be1 = q.b.dot(e1), be2 = q.b.dot(e2);
  const int meridians = std::clamp(static_cast<int>(std::ceil(2.0 * std::numbers::pi * patch.radius / spacing)), 16, 4096);
  if (q.A.isZero(0.0)) {
    // A plane (b ∥ n): g = 2ρ|b| cos θ + c₀ on every meridian, one crossing where the ends'
    // signs differ, at cos θ = −c₀ / 2ρ|b|: the same circle for all of them.
    const double bb = q.b.norm(), cos_theta = -q.c / (2.0 * kRho * bb);
    if (!(std::abs(cos_theta) < 1.0)) return;
    const double sin_theta = std::sqrt(1.0 - cos_theta * cos_theta);
    for (int m = 0; m < meridians; ++m) {
      const double phi = 2.0 * std::numbers::pi * m / meridians;
      const Eigen::Vector3d u = kRho * (cos_theta * n + sin_theta * (std::cos(phi) * e1 + std::sin(phi) * e2));
      const Eigen::Vector3d gu = q.gradient(u);
      if (patch.clips.keeps(u) && gu.norm() > 0.0) out.push_back({patch.centre + patch.radius * u, gu.normalized(), kRho});
    }
    return;
  }
  for (int m = 0; m < meridians; ++m) {
    const double phi = 2.0 * std::numbers::pi * m / meridians, cp = std::cos(phi), sp = std::sin(phi);
    const Eigen::Vector3d t = cp * e1 + sp * e2;
    const double tAt = cp * cp * e1Ae1 + 2.0 * cp * sp * e1Ae2 + sp * sp * e2Ae2, nAt = cp * nAe1 + sp * nAe2,
                 bt = cp * be1 + sp * be2;
    const auto g = [&](const Eigen::Vector2d& cs) {
      const double c = cs[0], s = cs[1];
      return kRho * (kRho * (c * c * nAn + 2.0 * c * s * nAt + s * s * tAt) + 2.0 * (c * bn + s * bt)) + q.c;
    };
    // A step's arc whose two ends one clip plane drops by more than the arc's bulge beyond its
    // chord (1 − cos(π/2kSteps) < 5.4e-4) holds no kept point: no bisection there.
    const auto clipped = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      const Eigen::Vector3d ua = kRho * (a[0] * n + a[1] * t), ub = kRho * (b[0] * n + b[1] * t);
      for (const ClipPlane& c : patch.clips) {
        const double m = -1e-3 * c.n.norm();
        if (c.n.dot(ua) + c.d < m && c.n.dot(ub) + c.d < m) return true;
      }
      return false;
    };
    // |g′(θ)| ≤ D: no root lies within |g|/D of θ, so the scan jumps over whole steps there; it
    // visits the same grid points where it looks, and finds the same brackets.
    const double D = 2.0 * kRho * std::hypot(bn, bt) + kRho * kRho * std::hypot(nAn - tAt, 2.0 * nAt);
    constexpr double kStepAngle = std::numbers::pi / kSteps;
    double g_prev = g(kStep[0]);
    for (int k = 0; k < kSteps;) {
      int jump = 1;
      if (D > 0.0) jump = static_cast<int>(std::clamp(std::floor(std::abs(g_prev) / (D * (1.0 + 1e-6)) / kStepAngle), 1.0, double(kSteps - k)));
      const int k1 = k + jump;
      const double g1 = g(kStep[k1]);
      if ((g_prev < 0.0) != (g1 < 0.0) && (jump > 1 || !clipped(kStep[k], kStep[k1]))) {
        Eigen::Vector2d lo = kStep[k], hi = kStep[k1];
        double glo = g_prev;
        double ghi = g1;
        for (int it = 0; it < kBisections; ++it) {
          const Eigen::Vector2d mid = (lo + hi).normalized();
          const double gm = g(mid);
          if ((gm < 0.0) == (glo < 0.0)) lo = mid, glo = gm;
          else hi = mid, ghi = gm;
        }
        // Then one secant step inside the bracket (π/48 / 2^12 wide, where g is linear to ~1e-10 of it).
        const double w = glo / (glo - ghi);
        const Eigen::Vector2d cs =
            std::isfinite(w) && w >= 0.0 && w <= 1.0 ? Eigen::Vector2d((1.0 - w) * lo + w * hi).normalized() : Eigen::Vector2d((lo + hi).normalized());
        const Eigen::Vector3d u = kRho * (cs[0] * n + cs[1] * t);
        const Eigen::Vector3d gu = q.gradient(u);
        if (patch.clips.keeps(u) && gu.norm() > 0.0) out.push_back({patch.centre + patch.radius * u, gu.normalized(), kRho});
      }
      k = k1;
      g_prev = g1;
    }
  }
}

std::optional<SlimBlend> blend_slim_samples(std::span<const SlimSample> samples, const SlimBlendOptions& options,
                                            std::vector<SlimSample>* used) {
  if (used) used->clear();
  double t_cut = std::numeric_limits<double>::infinity();
  for (const auto& s : samples) t_cut = std::min(t_cut, s.hit.t + options.push(s.radius, s.max_push));
  SlimBlend b;
  double t_first = std::numeric_limits<double>::infinity();
  for (const auto& s : samples) {
    if (s.hit.t > t_cut || !(s.weight > 0.0)) continue;
    const double g = s.hit.gradient.norm();
    if (!(g > 0.0)) continue;
    b.weight_sum += s.weight;
    b.t += s.weight * s.hit.t;
    b.point += s.weight * s.hit.point;
    b.normal += (s.weight / g) * s.hit.gradient;
    ++b.count;
    if (used) used->push_back(s);
    if (s.hit.t < t_first) {
      t_first = s.hit.t;
      b.first_index = s.index;
    }
  }
  if (!(b.weight_sum > 0.0)) return std::nullopt;
  b.t /= b.weight_sum;
  b.point /= b.weight_sum;
  const double n = b.normal.norm();
  if (!(n > 0.0)) return std::nullopt;
  b.normal /= n;
  return b;
}

}  // namespace quadrix
