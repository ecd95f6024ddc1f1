#include "fit/slim_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>
#include <span>
#include <queue>
#include <random>
#include <memory>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/log.h"
#include "fit/blend_probe.h"
#include "fit/local_fit.h"
#include "fit/normals.h"
#include "fit/point_index.h"

namespace quadrix {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Weight of a point in the local least squares, r = ‖p − c‖/R: the SLIM blend weight's shape
// (DESIGN §2) plus a floor so rim points, which are checked too, still pull on the fit.
double fit_weight(double r, double floor) {
  if (r < 0.5) return std::exp(-8.0 * r * r) + floor;
  const double s = 1.0 - std::min(r, 1.0);
  return 16.0 * std::exp(-2.0) * (s * s) * (s * s) + floor;
}

struct Ball {
  std::uint32_t centre = 0;  // point index
  double R = 0;
  Quadric g;                 // local: u = (x − c)/R
  bool is_height = false;
  bool is_bounded = true;    // error ≤ E was reached
  double max_taubin = 0, sum_sq_taubin = 0;  // local units × R = world
  std::size_t count = 0;     // points in the ball
  std::optional<ClipPlane> clip;  // sharp features: the patch keeps the sheet of its centre
  Eigen::Vector3d sheet = Eigen::Vector3d::Zero(), other = Eigen::Vector3d::Zero();  // cluster normals
  // A point of the ball (local u, normal n) belongs to this patch's sheet.
  bool owns(const Eigen::Vector3d& u, const Eigen::Vector3d& n) const {
    return !clip || (clip->keeps(u) && n.dot(sheet) >= n.dot(other));
  }
};

// Two clusters of unit normals (2-means on the sphere, seeded with the centre's normal and the
// normal farthest from it). Returns the cluster means, or nothing when they are closer than
// min_angle_cos or a cluster is too small.
std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> split_normals(std::span<const Eigen::Vector3d> n,
                                                                         const Eigen::Vector3d& seed,
                                                                         double min_angle_cos, std::size_t min_size) {
  Eigen::Vector3d a = seed, b = seed;
  double worst = 2;
  for (const auto& x : n)
    if (x.dot(seed) < worst) worst = x.dot(seed), b = x;
  if (worst > min_angle_cos) return std::nullopt;
  for (int it = 0; it < 4; ++it) {
    Eigen::Vector3d sa = Eigen::Vector3d::Zero(), sb = Eigen::Vector3d::Zero();
    std::size_t ca = 0, cb = 0;
    for (const auto& x : n)
      if (x.dot(a) >= x.dot(b)) sa += x, ++ca;
      else sb += x, ++cb;
    if (ca < min_size || cb < min_size || !(sa.norm() > 0) || !(sb.norm() > 0)) return std::nullopt;
    a = sa.normalized(), b = sb.normalized();
  }
  if (a.dot(b) > min_angle_cos) return std::nullopt;
  return std::pair{a, b};
}

// Nested random subsamples of the cloud (level k holds n/4^k points), each with its own kd-tree:
// a large ball's fit and check use at most max_fit_points and max_check_points of its points, so
// its radius query can run on the coarsest level that still returns max_check_points, not on
// all n (1M torus points: balls of 10⁵ points, queried ~10 times per candidate).
struct Subsamples {
  struct Level {
    std::vector<Eigen::Vector3d> points;
    std::vector<std::uint32_t> ids;  // into the full cloud
    std::unique_ptr<PointIndex> index;
    double scale = 1;  // full-cloud points per point of this level
  };
  std::vector<Level> levels;  // coarsest first; the full cloud is not among them

  Subsamples(const std::vector<Eigen::Vector3d>& P, std::size_t min_points, std::uint64_t seed) {
    const std::size_t n = P.size();
    if (n / 4 < min_points) return;
    std::vector<std::uint32_t> order(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::uint32_t>(i);
    std::mt19937_64 rng(seed ^ 0x5eed5eedULL);
    std::shuffle(order.begin(), order.end(), rng);
    for (std::size_t m = n / 4; m >= min_points; m /= 4) {
      Level l;
      l.ids.assign(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(m));
      l.points.reserve(m);
      for (const auto i : l.ids) l.points.push_back(P[i]);
      l.index = std::make_unique<PointIndex>(l.points);
      l.scale = double(n) / double(m);
      levels.insert(levels.begin(), std::move(l));
    }
  }
};

struct Fitter {
  const std::vector<Eigen::Vector3d>& P;
  const std::vector<Eigen::Vector3d>& N;
  const PointIndex& index;
  const SlimFitOptions& opt;
  double E;       // world
  double probe;   // world

  struct Scratch {
    std::vector<Neighbour> nb;
    std::vector<Eigen::Vector3d> u, n, fu, fn;
    std::vector<double> fw, fe;
  };
  const Subsamples* subsamples = nullptr;

  // The points of ball (c, R) into s.nb (full-cloud ids): from the coarsest subsample that holds
  // at least max_check_points of them, else from the whole cloud. Returns the estimated number of
  // cloud points in the ball.
  std::size_t ball_points(const Eigen::Vector3d& c, double R, Scratch& s) const {
    if (subsamples)
      for (const auto& l : subsamples->levels) {
        l.index->radius(c, R, s.nb);
        if (s.nb.size() >= opt.max_check_points) {
          for (auto& [id, d2] : s.nb) id = l.ids[id];
          return static_cast<std::size_t>(double(s.nb.size()) * l.scale);
        }
      }
    index.radius(c, R, s.nb);
    return s.nb.size();
  }

  // Fits and checks one ball (c, R); the fit with the smaller error when both kinds are tried.
  std::optional<Ball> try_ball(std::uint32_t ci, double R, Scratch& s, bool accept_any = false) const {
    const Eigen::Vector3d& c = P[ci];
    const std::size_t in_ball = ball_points(c, R, s);
    const std::size_t m = s.nb.size();
    s.u.resize(m);
    s.n.resize(m);
    for (std::size_t j = 0; j < m; ++j) {
      s.u[j] = (P[s.nb[j].first] - c) / R;
      s.n[j] = N[s.nb[j].first];
    }
    // Fit on at most max_fit_points (evenly strided), check on all.
    const std::size_t stride = std::max<std::size_t>(1, (m + opt.max_fit_points - 1) / opt.max_fit_points);
    s.fu.clear();
    s.fn.clear();
    s.fw.clear();
    for (std::size_t j = 0; j < m; j += stride) {
      s.fu.push_back(s.u[j]);
      s.fn.push_back(s.n[j]);
      s.fw.push_back(fit_weight(s.u[j].norm(), opt.weight_floor));
    }
    const LocalSample sample{s.fu, s.fn, s.fw};
    if (m > opt.max_check_points) {  // strided subset for the check (in place: u, n are scratch)
      const std::size_t cs = (m + opt.max_check_points - 1) / opt.max_check_points;
      std::size_t w = 0;
      for (std::size_t j = 0; j < m; j += cs, ++w) {
        s.u[w] = s.u[j];
        s.n[w] = s.n[j];
      }
      s.u.resize(w);
      s.n.resize(w);
    }
    const double bound = E / R, h = probe / R;
    std::optional<Ball> best;
    double best_err = std::numeric_limits<double>::infinity();
    auto consider = [&](const std::optional<Quadric>& g, bool is_height) {
      if (!g) return false;
      const LocalError e = local_error(*g, s.u, s.n, h, accept_any ? std::numeric_limits<double>::infinity() : bound);
      const double err = std::max(e.max_taubin, e.max_probe);
      if (!(e.within || accept_any) || (best && !(err < best_err))) return e.within;
      best_err = err;
      best = Ball{ci, R, *g, is_height, err <= bound, e.max_taubin * R, e.sum_sq_taubin * R * R, in_ball, std::nullopt};
      return e.within && err <= bound;
    };
    if (m >= opt.min_points) {
      auto g = fit_general_quadric(sample, opt.normal_weight);
      if (consider(g, false)) return best;
      // The bound is a maximum: reweight towards the minimax fit (Lawson), the points the fit
      // misses most gaining weight.
      for (int it = 0; it < opt.reweight_rounds && g && !accept_any; ++it) {
        double emax = 0;
        s.fe.resize(s.fu.size());
        for (std::size_t j = 0; j < s.fu.size(); ++j) emax = std::max(emax, s.fe[j] = g->taubin_distance(s.fu[j]));
        if (!(emax > 0)) break;
        for (std::size_t j = 0; j < s.fu.size(); ++j) {
          const double e = s.fe[j] / emax;
          s.fw[j] *= 0.1 + e * e;
        }
        g = fit_general_quadric(sample, opt.normal_weight);
        if (consider(g, false)) return best;
      }
    }
    if (consider(fit_height_quadric(sample, opt.normal_weight), true)) return best;
    if (opt.sharp && !accept_any)
      if (auto b = try_sharp(ci, R, s)) return b;
    if (best && !best->is_bounded && !accept_any) return std::nullopt;
    return best;
  }

  // The centre's sheet only, clipped by the plane where the two sheets' tangent planes are
  // equally far (dA(u) = dB(u): it separates the sheets at convex and concave creases alike).
  // Uses the check subset s.u, s.n that try_ball left behind.
  std::optional<Ball> try_sharp(std::uint32_t ci, double R, Scratch& s) const {
    const auto split = split_normals(s.n, N[ci], std::cos(opt.sharp_angle_deg * std::numbers::pi / 180.0), opt.min_points / 2);
    if (!split) return std::nullopt;
    const auto& [na, nb] = *split;
    Eigen::Vector3d pa = Eigen::Vector3d::Zero(), pb = Eigen::Vector3d::Zero();
    std::size_t ca = 0, cb = 0;
    for (std::size_t j = 0; j < s.u.size(); ++j)
      if (s.n[j].dot(na) >= s.n[j].dot(nb)) pa += s.u[j], ++ca;
      else pb += s.u[j], ++cb;
    pa /= double(ca), pb /= double(cb);
    ClipPlane clip;
    clip.n = na - nb;
    clip.d = -(na.dot(pa) - nb.dot(pb));
    const double len = clip.n.norm();
    clip.n /= len, clip.d /= len;
    Ball probe_ball;
    probe_ball.clip = clip, probe_ball.sheet = na, probe_ball.other = nb;
    // The patch must own its centre, or covering could never reach that point.
    if (!probe_ball.owns(Eigen::Vector3d::Zero(), N[ci])) return std::nullopt;
    std::vector<Eigen::Vector3d> u, n, fu, fn;
    std::vector<double> fw;
    for (std::size_t j = 0; j < s.u.size(); ++j)
      if (probe_ball.owns(s.u[j], s.n[j])) u.push_back(s.u[j]), n.push_back(s.n[j]);
    if (u.size() < opt.min_points / 2) return std::nullopt;
    const std::size_t stride = std::max<std::size_t>(1, (u.size() + opt.max_fit_points - 1) / opt.max_fit_points);
    for (std::size_t j = 0; j < u.size(); j += stride) fu.push_back(u[j]), fn.push_back(n[j]), fw.push_back(fit_weight(u[j].norm(), opt.weight_floor));
    const LocalSample sample{fu, fn, fw};
    const double bound = E / R, h = probe / R;
    for (const bool is_height : {false, true}) {
      const auto g = is_height ? fit_height_quadric(sample, opt.normal_weight) : fit_general_quadric(sample, opt.normal_weight);
      if (!g) continue;
      const LocalError e = local_error(*g, u, n, h, bound);
      if (!e.within) continue;
      Ball b{ci, R, *g, is_height, true, e.max_taubin * R, e.sum_sq_taubin * R * R, u.size(), clip, na, nb};
      return b;
    }
    return std::nullopt;
  }

  // The largest R whose fit stays within E: growth from the min_points-th neighbour distance,
  // then bisection in log R.
  // With a guess (the radius of a nearby candidate): from there, growth or shrinking by
  // warm_growth, then bisection; the search from scratch below when no radius down to
  // guess/warm_growth¹² fits.
  Ball grow(std::uint32_t ci, Scratch& s, double limit = std::numeric_limits<double>::infinity(), double guess = 0) const {
    if (guess > 0 && opt.warm_growth > 1) {
      const double cap = std::min(0.5 * diagonal, limit);
      const double R = std::min(guess, cap);
      std::optional<Ball> ok = try_ball(ci, R, s);
      double lo = 0, hi = 0;
      if (ok) {
        lo = R;
        while (lo < cap) {
          const double next = std::min(cap, lo * opt.warm_growth);
          auto b = try_ball(ci, next, s);
          if (!b) { hi = next; break; }
          ok = b, lo = next;
        }
      } else {
        hi = R;
        for (int k = 0; k < 12 && !ok; ++k) {
          const double next = hi / opt.warm_growth;
          if (auto b = try_ball(ci, next, s)) ok = b, lo = next;
          else hi = next;
        }
      }
      if (ok) {
        if (hi > 0)
          for (int k = 0; k < opt.warm_bisection_steps; ++k) {
            const double mid = std::sqrt(lo * hi);
            if (auto b = try_ball(ci, mid, s)) ok = b, lo = mid;
            else hi = mid;
          }
        return *ok;
      }
    }
    index.nearest(P[ci], opt.min_points, s.nb);
    double R = std::sqrt(s.nb.back().second) * 1.05;
    if (!(R > 0)) R = E;
    R = std::min(R, limit);
    std::optional<Ball> ok = try_ball(ci, R, s);
    if (!ok) {
      // Smaller balls (height fit, down to a handful of points), else the best fit at R.
      for (int k = 0; k < 3 && !ok; ++k) {
        R *= 0.7;
        ok = try_ball(ci, R, s);
      }
      if (!ok) {
        // Noise beyond E: the tangent plane at the centre in a ball that holds no other point, so
        // the blend at this point mixes it only with patches checked against it (bunny at 1e-4:
        // the best fit at R instead left 15 points beyond E, 2 of them with no hit at all).
        index.nearest(P[ci], 2 * opt.min_points, s.nb);
        for (const auto& [j, d2] : s.nb)
          if (d2 > 0) return Ball{ci, 0.5 * std::sqrt(d2), Quadric::plane(N[ci], 0.0), true, false, 0, 0, 1, std::nullopt};
        R /= 0.7 * 0.7 * 0.7;
        auto any = try_ball(ci, R, s, true);
        // Last resort: the tangent plane at the centre.
        Ball b = any ? *any : Ball{ci, R, Quadric::plane(N[ci], 0.0), true, false, 0, 0, 1, std::nullopt};
        b.is_bounded = false;
        return b;
      }
      return *ok;
    }
    double lo = R, hi = 0;
    const double cap = std::min(0.5 * diagonal, limit);
    while (lo < cap) {
      const double next = std::min(cap, lo * opt.radius_growth);
      auto b = try_ball(ci, next, s);
      if (!b) {
        hi = next;
        break;
      }
      ok = b;
      lo = next;
    }
    if (hi > 0)
      for (int k = 0; k < opt.bisection_steps; ++k) {
        const double mid = std::sqrt(lo * hi);
        if (auto b = try_ball(ci, mid, s)) {
          ok = b;
          lo = mid;
        } else {
          hi = mid;
        }
      }
    return *ok;
  }
  double diagonal = 0;
};

void validate(const PointCloud& cloud, const SlimFitOptions& o) {
  const std::size_t n = cloud.points.size();
  if (n < 10) throw InvalidInput(fmt::format("fit_slim: {} points; at least 10 are needed", n));
  if (cloud.has_normals() && cloud.normals.size() != n)
    throw InvalidInput(fmt::format("fit_slim: {} normals for {} points", cloud.normals.size(), n));
  for (std::size_t i = 0; i < n; ++i) {
    if (!cloud.points[i].allFinite())
      throw InvalidInput(fmt::format("fit_slim: point {} is not finite ({}, {}, {})", i, cloud.points[i].x(),
                                     cloud.points[i].y(), cloud.points[i].z()));
    if (cloud.has_normals() && !(cloud.normals[i].allFinite() && cloud.normals[i].norm() > 1e-12))
      throw InvalidInput(fmt::format("fit_slim: normal {} is zero or not finite ({}, {}, {})", i,
                                     cloud.normals[i].x(), cloud.normals[i].y(), cloud.normals[i].z()));
  }
  if (!(o.max_error > 0) || !std::isfinite(o.max_error))
    throw InvalidInput(fmt::format("fit_slim: max_error must be positive and finite, got {}", o.max_error));
  if (!(o.normal_weight > 0)) throw InvalidInput(fmt::format("fit_slim: normal_weight must be > 0, got {}", o.normal_weight));
  if (!(o.radius_growth > 1)) throw InvalidInput(fmt::format("fit_slim: radius_growth must be > 1, got {}", o.radius_growth));
  if (!(o.cover_fraction > 0 && o.cover_fraction <= 1))
    throw InvalidInput(fmt::format("fit_slim: cover_fraction must lie in (0, 1], got {}", o.cover_fraction));
  if (!(o.weight_floor >= 0)) throw InvalidInput(fmt::format("fit_slim: weight_floor must be ≥ 0, got {}", o.weight_floor));
  if (o.sharp && !(o.sharp_angle_deg > 0 && o.sharp_angle_deg < 180))
    throw InvalidInput(fmt::format("fit_slim: sharp_angle_deg must lie in (0, 180), got {}", o.sharp_angle_deg));
  if (o.min_points < 3) throw InvalidInput(fmt::format("fit_slim: min_points must be ≥ 3, got {}", o.min_points));
  if (o.max_fit_points < 10) throw InvalidInput(fmt::format("fit_slim: max_fit_points must be ≥ 10, got {}", o.max_fit_points));
  // Degenerate point sets: coincident, or all on one plane (no surface to enclose).
  Box3 box;
  for (const auto& p : cloud.points) box.extend(p);
  const double diag = box.diagonal();
  if (!(diag > 0)) throw InvalidInput(fmt::format("fit_slim: all {} points coincide", n));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : cloud.points) mean += p;
  mean /= double(n);
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& p : cloud.points) C += (p - mean) * (p - mean).transpose();
  const Eigen::Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C).eigenvectors().col(0);
  double off = 0;
  for (const auto& p : cloud.points) off = std::max(off, std::abs(axis.dot(p - mean)));
  if (off <= 1e-9 * diag)
    throw InvalidInput(fmt::format("fit_slim: the {} points are coplanar (largest distance from their plane {:.3g}, "
                                   "diagonal {:.6g}); a SLIM surface needs a 3-D point set",
                                   n, off, diag));
}

}  // namespace

SlimFitResult fit_slim(const PointCloud& cloud, const SlimFitOptions& opt) {
  const auto t_start = Clock::now();
  validate(cloud, opt);
  SlimFitResult result;
  SlimFitStats& st = result.stats;
  const auto& P = cloud.points;
  const std::size_t n = P.size();
  st.points = n;
  Box3 box;
  for (const auto& p : P) box.extend(p);
  st.diagonal = box.diagonal();
  const double E = opt.max_error_is_absolute ? opt.max_error : opt.max_error * st.diagonal;
  st.max_error_abs = E;

  // Normals: given (normalised) or estimated.
  auto t0 = Clock::now();
  std::vector<Eigen::Vector3d> N;
  if (cloud.has_normals()) {
    N.resize(n);
    for (std::size_t i = 0; i < n; ++i) N[i] = cloud.normals[i].normalized();
  } else {
    N = estimate_normals(P, {.neighbours = opt.normal_neighbours}).normals;
    st.normals_estimated = true;
    log::info("fit_slim: the cloud has no normals; estimated them (PCA over {} neighbours, MST orientation)",
              opt.normal_neighbours);
  }
  st.time_normals = seconds_since(t0);

  t0 = Clock::now();
  const PointIndex index(P);
  const Subsamples subsamples(P, 4 * opt.max_check_points, opt.seed);
  Fitter fitter{P, N, index, opt, E, opt.probe_factor * E};
  fitter.subsamples = &subsamples;
  st.subsample_levels = subsamples.levels.size();
  fitter.diagonal = st.diagonal;
  std::mt19937_64 rng(opt.seed);

  std::vector<Ball> balls;                  // evaluated candidates
  std::vector<std::vector<std::uint32_t>> covers;  // points within cover_fraction·R of each candidate
  std::vector<std::uint8_t> is_candidate(n, 0);
  std::vector<Eigen::Vector3d> pilot_centres;
  std::vector<double> pilot_R;
  std::unique_ptr<PointIndex> pilot_index;
  // Radius search warm starts: the nearest pilot candidate's radius (none while the pilots run).
  auto evaluate = [&](const std::vector<std::uint32_t>& centres, const std::vector<double>* caps) {
    const std::size_t first = balls.size();
    balls.resize(first + centres.size());
    covers.resize(first + centres.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, centres.size(), 4), [&](const tbb::blocked_range<std::size_t>& r) {
      Fitter::Scratch s;
      std::vector<Neighbour> pn;
      for (std::size_t k = r.begin(); k != r.end(); ++k) {
        double guess = 0;
        if (pilot_index) {
          pilot_index->nearest(P[centres[k]], 1, pn);
          guess = pilot_R[pn[0].first];
        }
        // Repair rounds: no larger than the cap of this centre.
        Ball b = fitter.grow(centres[k], s, caps ? (*caps)[k] : std::numeric_limits<double>::infinity(), guess);
        // A ball that never reached E covers within ½R only.
        index.radius(P[centres[k]], (b.is_bounded ? opt.cover_fraction : 0.5) * b.R, s.nb);
        auto& cov = covers[first + k];
        cov.clear();
        for (const auto& [p, d2] : s.nb)
          if (b.owns((P[p] - P[centres[k]]) / b.R, N[p])) cov.push_back(p);
        balls[first + k] = std::move(b);
      }
    });
  };

  // Initial candidates: a random fraction of the points.
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), rng);
  const std::size_t m0 =
      std::min({n, opt.max_candidates, std::max(opt.min_candidates, std::size_t(opt.candidate_fraction * double(n)))});
  std::vector<std::uint32_t> centres(order.begin(), order.begin() + m0);
  for (auto c : centres) is_candidate[c] = 1;
  if (const std::size_t pilot = opt.pilot_candidates; pilot > 0 && pilot < centres.size()) {
    std::vector<std::uint32_t> first(centres.begin(), centres.begin() + pilot), rest(centres.begin() + pilot, centres.end());
    evaluate(first, nullptr);
    for (const auto& b : balls)
      if (b.is_bounded) pilot_centres.push_back(P[b.centre]), pilot_R.push_back(b.R);
    if (!pilot_centres.empty()) pilot_index = std::make_unique<PointIndex>(std::span<const Eigen::Vector3d>(pilot_centres));
    evaluate(rest, nullptr);
  } else {
    evaluate(centres, nullptr);
  }
  st.time_candidates = seconds_since(t0);

  // Greedy covering (lazy: a candidate's gain only decreases), adding uncovered points as new
  // candidates until every point is covered.
  t0 = Clock::now();
  std::vector<std::uint8_t> covered(n, 0);
  std::vector<std::uint8_t> chosen_flag;
  std::vector<std::uint32_t> chosen;
  std::size_t uncovered = n;
  using Item = std::pair<std::size_t, std::uint32_t>;  // gain, candidate
  std::priority_queue<Item> heap;
  auto gain = [&](std::uint32_t b) {
    std::size_t g = 0;
    for (auto p : covers[b]) g += !covered[p];
    return g;
  };
  auto run_greedy = [&](std::size_t from) {
    chosen_flag.resize(balls.size(), 0);
    for (std::size_t b = from; b < balls.size(); ++b) heap.push({gain(std::uint32_t(b)), std::uint32_t(b)});
    while (uncovered > 0 && !heap.empty()) {
      auto [g, b] = heap.top();
      heap.pop();
      if (g == 0) break;
      const std::size_t now = gain(b);
      if (now < g) {
        if (now > 0) heap.push({now, b});
        continue;
      }
      chosen.push_back(b);
      chosen_flag[b] = 1;
      for (auto p : covers[b])
        if (!covered[p]) {
          covered[p] = 1;
          --uncovered;
        }
    }
  };
  auto add_uncovered_candidates = [&](std::size_t limit, const std::vector<double>* cap_of_point) {
    std::vector<std::uint32_t> fresh;
    std::vector<double> caps;
    for (auto p : order)
      if (!covered[p]) {
        fresh.push_back(p);
        if (cap_of_point) caps.push_back((*cap_of_point)[p]);
        if (fresh.size() >= limit) break;
      }
    for (auto c : fresh) is_candidate[c] = 1;
    const std::size_t from = balls.size();
    evaluate(fresh, cap_of_point ? &caps : nullptr);
    return from;
  };
  run_greedy(0);
  while (uncovered > 0) {
    const std::size_t limit = std::max<std::size_t>(64, uncovered / 16);
    run_greedy(add_uncovered_candidates(limit, nullptr));
  }

  // Drop balls whose ½R points are all covered by other chosen balls (smallest first).
  std::vector<std::uint16_t> multiplicity(n, 0);
  auto prune = [&]() {
    std::fill(multiplicity.begin(), multiplicity.end(), 0);
    for (auto b : chosen)
      for (auto p : covers[b]) multiplicity[p] = std::uint16_t(std::min<int>(multiplicity[p] + 1, 60000));
    std::sort(chosen.begin(), chosen.end(), [&](auto a, auto b) { return covers[a].size() < covers[b].size(); });
    std::vector<std::uint32_t> kept;
    for (auto b : chosen) {
      const bool redundant = std::all_of(covers[b].begin(), covers[b].end(), [&](auto p) { return multiplicity[p] >= 2; });
      if (redundant) {
        for (auto p : covers[b]) --multiplicity[p];
        chosen_flag[b] = 0;
      } else {
        kept.push_back(b);
      }
    }
    chosen.swap(kept);
  };
  st.patches_before_pruning = chosen.size();
  prune();
  st.time_cover = seconds_since(t0);

  auto build_model = [&]() {
    result.model.slims.clear();
    for (auto b : chosen) {
      SlimPatch s;
      s.centre = P[balls[b].centre];
      s.radius = balls[b].R;
      s.local = balls[b].g;
      s.clip = balls[b].clip;
      result.model.slims.push_back(std::move(s));
    }
  };
  build_model();

  // Verify against the blended surface; shrink the patches at fault and cover again.
  t0 = Clock::now();
  std::vector<double> err(n, 0.0);
  const double h = opt.probe_factor * E;
  std::vector<double> cap(n, std::numeric_limits<double>::infinity());  // radius cap per centre point
  for (int round = 0;; ++round) {
    const BlendProbe probe(result.model);
    std::vector<std::uint8_t> at_fault(result.model.slims.size(), 0);
    std::vector<std::uint32_t> failing;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<int> culprits;
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        culprits.clear();
        err[i] = probe.probe(P[i], N[i], h, E, &culprits);
        for (int c : culprits) at_fault[c] = 1;  // benign race: every writer stores 1
      }
    });
    for (std::size_t i = 0; i < n; ++i)
      if (!(err[i] <= E)) failing.push_back(std::uint32_t(i));
    st.blend_failures = failing.size();
    if (failing.empty() || round >= opt.repair_rounds) break;
    ++st.repair_rounds;
    log::debug("fit_slim: repair round {}: {} points beyond E", round + 1, failing.size());
    // Remove the culprit patches; their centres may come back no larger than 0.7 R.
    std::vector<std::uint32_t> keep;
    for (std::size_t k = 0; k < chosen.size(); ++k) {
      const auto b = chosen[k];
      if (!at_fault[k] || balls[b].R <= 0) {
        keep.push_back(b);
        continue;
      }
      chosen_flag[b] = 0;
      cap[balls[b].centre] = std::min(cap[balls[b].centre], 0.7 * balls[b].R);
    }
    chosen.swap(keep);
    std::fill(covered.begin(), covered.end(), 0);
    uncovered = n;
    for (auto b : chosen)
      for (auto p : covers[b])
        if (!covered[p]) {
          covered[p] = 1;
          --uncovered;
        }
    // Other points near failures that are centres of culprits get capped candidates first.
    std::vector<std::uint32_t> again;
    std::vector<double> caps;
    for (std::size_t i = 0; i < n; ++i)
      if (std::isfinite(cap[i]) && !covered[i]) {
        again.push_back(std::uint32_t(i));
        caps.push_back(cap[i]);
      }
    const std::size_t from = balls.size();
    evaluate(again, &caps);
    for (std::size_t b = from; b < balls.size(); ++b) cap[balls[b].centre] = std::min(cap[balls[b].centre], balls[b].R);
    // Re-covering must not regrow balls beyond their caps: candidates at capped points are
    // evaluated with the cap.
    chosen_flag.resize(balls.size(), 0);
    for (std::size_t b = 0; b < from; ++b)
      if (!chosen_flag[b] && balls[b].R > cap[balls[b].centre]) covers[b].clear();  // retire
    while (!heap.empty()) heap.pop();
    run_greedy(0);
    while (uncovered > 0) {
      const std::size_t limit = std::max<std::size_t>(64, uncovered / 16);
      run_greedy(add_uncovered_candidates(limit, &cap));
    }
    prune();
    build_model();
  }
  st.time_verify = seconds_since(t0);

  // Statistics and metadata.
  double sum_sq_blend = 0;
  std::size_t finite = 0;
  st.max_blend = 0;
  for (double e : err) {
    st.max_blend = std::max(st.max_blend, e);
    if (std::isfinite(e)) {
      sum_sq_blend += e * e;
      ++finite;
    }
  }
  st.rms_blend = finite ? std::sqrt(sum_sq_blend / double(finite)) : 0;
  double sum_sq_taubin = 0;
  std::size_t in_balls = 0;
  for (auto b : chosen) {
    st.max_taubin = std::max(st.max_taubin, balls[b].max_taubin);
    sum_sq_taubin += balls[b].sum_sq_taubin;
    in_balls += balls[b].count;
    st.height_patches += balls[b].is_height;
    st.unbounded_patches += !balls[b].is_bounded;
    st.clipped_patches += balls[b].clip.has_value();
  }
  st.rms_taubin = in_balls ? std::sqrt(sum_sq_taubin / double(in_balls)) : 0;
  st.candidates = balls.size();
  st.patches = chosen.size();
  st.time_total = seconds_since(t_start);

  auto& md = result.model.metadata;
  auto num = [](double v) { return fmt::format("{:.6g}", v); };
  md["producer"] = "quadrix fit";
  md["max_error"] = num(E / st.diagonal);
  md["max_error_abs"] = num(E);
  md["diagonal"] = num(st.diagonal);
  md["normals"] = st.normals_estimated ? "estimated" : "given";
  md["points"] = std::to_string(n);
  md["patches"] = std::to_string(st.patches);
  md["candidates"] = std::to_string(st.candidates);
  md["subsample_levels"] = std::to_string(st.subsample_levels);
  md["height_patches"] = std::to_string(st.height_patches);
  if (opt.sharp) md["clipped_patches"] = std::to_string(st.clipped_patches);
  md["measured_max_error"] = num(st.max_blend);
  md["measured_rms_error"] = num(st.rms_blend);
  md["measured_failures"] = std::to_string(st.blend_failures);
  md["taubin_max_error"] = num(st.max_taubin);
  md["taubin_rms_error"] = num(st.rms_taubin);
  md["time_normals_s"] = num(st.time_normals);
  md["time_candidates_s"] = num(st.time_candidates);
  md["time_cover_s"] = num(st.time_cover);
  md["time_verify_s"] = num(st.time_verify);
  md["time_total_s"] = num(st.time_total);
  log::info("fit_slim: {} points, {} patches ({} candidates), E = {:.3g}, blended max {:.3g} rms {:.3g}, {:.2f} s", n,
            st.patches, st.candidates, E, st.max_blend, st.rms_blend, st.time_total);
  return result;
}

}  // namespace quadrix
