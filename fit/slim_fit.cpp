#include "fit/slim_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <array>
#include <numbers>
#include <numeric>
#include <optional>
#include <span>
#include <queue>
#include <mutex>
#include <random>
#include <memory>
#include <thread>
#include <tuple>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "core/error.h"
#include "core/io/io.h"
#include "core/log.h"
#include "core/reference.h"
#include "core/slim.h"
#include "fit/data_surface.h"
#include "fit/evaluate.h"
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
  // Sharp features, open boundaries, a face's prism: the patch keeps the sheet of its centre.
  ClipPlanes clips;
  Eigen::Vector3d sheet = Eigen::Vector3d::Zero(), other = Eigen::Vector3d::Zero();  // cluster normals
  bool settled = false;      // the surface side (BallFitter::settle) was checked
  std::int64_t face = -1;    // a face patch (SlimFitOptions::face_patches): the face's plane
  int surface_lattice = 0;   // settle's surface_ok passed on a lattice this fine (lines per side)
  // A point of the ball (local u, normal n) belongs to this patch's sheet.
  bool owns(const Eigen::Vector3d& u, const Eigen::Vector3d& n) const {
    return clips.empty() || (clips.keeps(u) && n.dot(sheet) >= n.dot(other));
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

// The faces of the data's mesh, for face patches: which face each face sample lies on, and per
// face the sample at its centroid and its largest centroid–vertex distance.
struct FaceSet {
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  const PolygonMesh* mesh = nullptr;
  std::vector<std::uint32_t> face_of;   // per point: its face, or kNone (a cloud point)
  std::vector<std::uint32_t> centroid;  // per face: the point at its centroid, or kNone
  std::vector<double> reach;            // per face: largest centroid–vertex distance
  // A side wall of a face's prism: the plane through one of its edges, perpendicular to the face.
  struct Side {
    Eigen::Vector3d inward;  // unit, in the face's plane, towards the centroid
    double offset = 0;       // the edge's distance from the centroid along -inward
    double length = 0;       // the edge's length
    bool open = false;       // the edge is used by this face only (the data's boundary)
  };
  std::vector<std::vector<Side>> sides;  // per face: one per edge for a convex face of at most
                                         // ClipPlanes::kMax edges, else its longest open edge

  FaceSet(const PolygonMesh& m, std::vector<std::uint32_t> of, const std::vector<Eigen::Vector3d>& P, bool prisms)
      : mesh(&m), face_of(std::move(of)), centroid(m.face_count(), kNone), reach(m.face_count(), 0.0) {
    for (std::size_t i = 0; i < face_of.size(); ++i) {
      const auto f = face_of[i];
      if (f == kNone || centroid[f] != kNone) continue;
      centroid[f] = static_cast<std::uint32_t>(i);  // face_samples lists the centroids first
      for (const int v : m.face(f)) reach[f] = std::max(reach[f], (m.vertices[v] - P[i]).norm());
    }
    // The face's plane stops at its edges: at an open edge (used by one face) it must not run on
    // past the data's boundary, and across an inner edge it would run on into the neighbour's
    // territory, where the blend mixes it with the neighbour's plane (several E at every edge of
    // a coarse mesh fitted below its sampling).
    const EdgeUses uses(m);
    sides.resize(m.face_count());
    for (std::size_t f = 0; f < m.face_count(); ++f) {
      if (centroid[f] == kNone) continue;
      const auto vs = m.face(f);
      const Eigen::Vector3d& c = P[centroid[f]];
      std::vector<Side> all;
      bool convex = vs.size() <= static_cast<std::size_t>(ClipPlanes::kMax);
      for (std::size_t k = 0; k < vs.size(); ++k) {
        const int a = vs[k], b = vs[(k + 1) % vs.size()];
        const Eigen::Vector3d e = m.vertices[b] - m.vertices[a];
        Eigen::Vector3d in = c - m.vertices[a];
        in -= in.dot(e) / e.squaredNorm() * e;
        if (!(in.norm() > 0) || !(e.squaredNorm() > 0)) {
          convex = false;
          continue;
        }
        all.push_back({in.normalized(), in.norm(), e.norm(), uses.open(a, b)});
      }
      // Every corner on the inner side of every wall (up to rounding), or the prism would cut
      // into the face itself.
      for (const Side& sd : all)
        for (const int v : vs)
          if (sd.inward.dot(m.vertices[v] - c) < -sd.offset * (1.0 + 1e-9) - 1e-12 * reach[f]) convex = false;
      if (convex && prisms) {
        sides[f] = std::move(all);
        continue;
      }
      // Else only along its longest open edge, as far as one wall of a non-convex face may go.
      const Side* longest = nullptr;
      for (const Side& sd : all)
        if (sd.open && (!longest || sd.length > longest->length)) longest = &sd;
      if (longest) sides[f] = {*longest};
    }
  }
  double distance(std::uint32_t f, const Eigen::Vector3d& x) const {
    const auto vs = mesh->face(f);
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t k = 1; k + 1 < vs.size(); ++k)
      d = std::min(d, point_triangle_distance(x, mesh->vertices[vs[0]], mesh->vertices[vs[k]], mesh->vertices[vs[k + 1]]));
    return d;
  }
};

struct BallFitter {
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
  const DataSurface* data = nullptr;  // the points' local surface (tangent discs)
  const FaceSet* faces = nullptr;     // face patches (SlimFitOptions::face_patches)

  // The face point ci lies on (its own, for a face sample; else among the faces of its nearest
  // face samples), as a face patch: the face's plane around its centroid.
  std::optional<Ball> face_ball(std::uint32_t ci, Scratch& s) const {
    if (!faces) return std::nullopt;
    // Only below the sampling (nearest sample farther than face_patch_spacing·E): above it a
    // failed fit is a local defect, and the tangent disc below keeps it local.
    index.nearest(P[ci], 2, s.nb);
    if (s.nb.size() < 2 || !(std::sqrt(s.nb[1].second) > opt.face_patch_spacing * E)) return std::nullopt;
    std::uint32_t f = faces->face_of[ci];
    if (f == FaceSet::kNone) {
      // A point of the cloud (a vertex): the face it lies on among its nearest samples' faces.
      index.nearest(P[ci], 24, s.nb);
      double best = std::numeric_limits<double>::infinity();
      for (const auto& [j, d2] : s.nb) {
        const auto fj = faces->face_of[j];
        if (fj == FaceSet::kNone || fj == f) continue;
        if (const double d = faces->distance(fj, P[ci]); d < best) best = d, f = fj;
      }
      if (!(best <= 1e-3 * E)) return std::nullopt;
    }
    auto b = face_patch(f);
    if (!b || !((P[ci] - P[b->centre]).norm() < b->R)) return std::nullopt;  // it must cover ci
    return b;
  }

  // Face f's plane around its centroid, clipped to its prism (SlimFitOptions::face_prisms).
  std::optional<Ball> face_patch(std::uint32_t f) const {
    const std::uint32_t c = faces->centroid[f];
    // Clipped to its prism, the plane may have a larger ball than its farthest vertex: at r = 1
    // that vertex had weight 0, a pinhole where every face around it put it there (armadillo at
    // 1e-4: 20 vertices with no hit). Reach 1.1: weight ≥ 1.5e-4 at every corner.
    const double grow = opt.face_prisms ? 1.1 : 1.0;
    const double R = c == FaceSet::kNone ? 0.0 : grow * opt.face_patch_reach * faces->reach[f];
    if (c == FaceSet::kNone || !(R > 0)) return std::nullopt;
    Ball b{c, R, Quadric::plane(N[c], 0.0), true, true, 0, 0, 0, ClipPlanes{}};
    // Clipped to the face's prism: a hair outside an open edge, so the edge's vertices stay;
    // face_patch_margin·E outside an inner edge, so neighbouring faces' pieces overlap (no crack
    // where the GPU's rounding puts a ray on neither side) and stay within that of the data.
    for (const FaceSet::Side& sd : faces->sides[f]) {
      const double margin = sd.open ? 1e-3 * E : opt.face_patch_margin * E;
      b.clips.add(ClipPlane{sd.inward, (sd.offset + margin) / R});
    }
    if (!b.clips.empty()) b.sheet = N[c], b.other = -N[c];
    b.face = f;
    b.settled = true;
    return b;
  }

  // The local form of the surface side: the patch's zero set inside its ball stays within
  // local_surface_factor·E of the data (no fins, no second sheets, no extrapolation past an
  // open boundary).
  bool surface_ok(const Ball& b) const {
    return zero_set_excess(SlimPatch{P[b.centre], b.R, b.g, b.clips, std::nullopt, std::nullopt}, *data,
                           opt.local_surface_factor * E, opt.local_surface_grid, opt.local_surface_depth) == 0.0;
  }

  // A ball at (ci, R) whose points are within E and whose zero set passes surface_ok: the
  // plain fit, else its centre's sheet alone, clipped (two sheets in one ball: a thin part, a
  // gap, a crease).
  std::optional<Ball> try_both_sides(std::uint32_t ci, double R, Scratch& s) const {
    auto b = try_ball(ci, R, s);
    if (!b) return std::nullopt;
    if (surface_ok(*b)) return b;
    if (!b->clips.empty()) return std::nullopt;  // try_ball already tried the clipped sheet (--sharp)
    // Both use the check points try_ball left in s.
    if (auto c = try_boundary(*b, s); c && surface_ok(*c)) return c;
    auto c = try_sharp(ci, R, s);
    if (c && surface_ok(*c)) return c;
    return std::nullopt;
  }

  // An open boundary inside the ball: the patch is clipped by a plane just beyond the outermost
  // point, instead of extrapolating to the ball's rim. The plane is the one of the data's
  // boundary points in the ball (DataSurface::boundary_inward) when they bend measurably (a
  // curved boundary: a straight cut across the sheet would leave slivers past it), else across
  // the sheet, facing the boundary points' inward tangent or the points' tangential centroid.
  std::optional<Ball> try_boundary(const Ball& b, const Scratch& s) const {
    if (s.u.size() < 3) return std::nullopt;
    const Eigen::Vector3d& c0 = P[b.centre];
    Eigen::Vector3d nbar = Eigen::Vector3d::Zero(), centroid = Eigen::Vector3d::Zero();
    for (std::size_t j = 0; j < s.u.size(); ++j) nbar += s.n[j], centroid += s.u[j];
    if (!(nbar.norm() > 0)) return std::nullopt;
    nbar.normalize();
    centroid /= double(s.u.size());
    Eigen::Vector3d m = centroid - nbar.dot(centroid) * nbar;
    // The data's boundary in the ball, in local coordinates.
    thread_local std::vector<DataSurface::BoundarySample> edge;
    data->boundary_near(c0, b.R, edge);
    Eigen::Vector3d inward = Eigen::Vector3d::Zero(), mean = Eigen::Vector3d::Zero();
    for (const auto& e : edge) inward += e.inward, mean += (e.point - c0) / b.R;
    const double count = double(edge.size());
    if (edge.size() >= 6 && inward.norm() > 0.5 * count) {
      inward.normalize();
      mean /= count;
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      for (const auto& e : edge) {
        const Eigen::Vector3d v = (e.point - c0) / b.R - mean;
        C += v * v.transpose();
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C / count);
      const Eigen::Vector3d line = es.eigenvectors().col(2);
      const double bend = std::sqrt(std::max(0.0, es.eigenvalues()[1]));
      Eigen::Vector3d across = es.eigenvectors().col(0);
      if (across.dot(inward) < 0) across = -across;
      // The arc's own plane when its bow is well above the error (and the plane leans into the
      // data), else the plane through the boundary line across the sheet.
      if (bend > E / b.R && across.dot(inward) > 0.3) m = across;
      else m = inward - inward.dot(line) * line;
    } else if (m.norm() < opt.boundary_offset) {
      return std::nullopt;
    }
    if (!(m.norm() > 0)) return std::nullopt;
    m.normalize();
    double lo = std::numeric_limits<double>::infinity();
    for (const auto& [id, d2] : s.nb) lo = std::min(lo, m.dot((P[id] - c0) / b.R));
    Ball c = b;
    c.clips = ClipPlanes::of(ClipPlane{m, -(lo - 0.5 * E / b.R)});
    if (!c.clips.keeps(Eigen::Vector3d::Zero())) return std::nullopt;  // must own its centre
    return c;
  }

  // A ball from grow, shrunk (×shrink_step) until its zero set passes surface_ok too; when
  // nothing does, the smallest ball within E on the points side (verification reports the rest).
  Ball settle(Ball b, Scratch& s) const {
    b.settled = true;
    if (b.face >= 0 || !b.is_bounded) return b;
    // Passed surface_ok: its zero set was checked on a lattice of at least this many lines per
    // side (finer where a sample could not vouch for its cell).
    const auto passed = [&](Ball c) {
      c.settled = true;
      c.surface_lattice = opt.local_surface_grid << opt.local_surface_depth;
      return c;
    };
    if (surface_ok(b)) return passed(b);
    const std::uint32_t ci = b.centre;
    if (auto c = try_both_sides(ci, b.R, s)) return passed(*c);
    double R = b.R;
    for (int k = 0; k < opt.shrink_steps; ++k) {
      R *= opt.shrink_step;
      if (auto c = try_both_sides(ci, R, s)) return passed(*c);
      if (auto c = try_ball(ci, R, s)) b = *c, b.settled = true;
    }
    return b;
  }

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
      best = Ball{ci, R, *g, is_height, err <= bound, e.max_taubin * R, e.sum_sq_taubin * R * R, in_ball, ClipPlanes{}};
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
    probe_ball.clips = ClipPlanes::of(clip), probe_ball.sheet = na, probe_ball.other = nb;
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
      Ball b{ci, R, *g, is_height, true, e.max_taubin * R, e.sum_sq_taubin * R * R, u.size(), ClipPlanes::of(clip), na, nb};
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
      if (!ok)
        if (auto f = face_ball(ci, s)) return *f;
      if (!ok) {
        // Noise beyond E: the tangent plane at the centre in a ball that holds no other point, so
        // the blend at this point mixes it only with patches checked against it (bunny at 1e-4:
        // the best fit at R instead left 15 points beyond E, 2 of them with no hit at all).
        // No larger than the repair's cap (limit): else a disc that failed the surface side came
        // back the same size every round (a sheet's open corner, beside face-hole points).
        index.nearest(P[ci], 2 * opt.min_points, s.nb);
        for (const auto& [j, d2] : s.nb)
          if (d2 > 0) return Ball{ci, std::min(0.5 * std::sqrt(d2), limit), Quadric::plane(N[ci], 0.0), true, false, 0, 0, 1, ClipPlanes{}};
        R /= 0.7 * 0.7 * 0.7;
        auto any = try_ball(ci, R, s, true);
        // Last resort: the tangent plane at the centre.
        Ball b = any ? *any : Ball{ci, R, Quadric::plane(N[ci], 0.0), true, false, 0, 0, 1, ClipPlanes{}};
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


// The fit as named steps (PMP's decimation shape): candidates, covering, pruning, then rounds of
// verification on both sides of the contract and repair of the patches at fault.
class SlimFitter {
public:
  SlimFitter(const PointCloud& cloud, const SlimFitOptions& options, const PolygonMesh* surface)
      : cloud_(cloud), opt_(options), P_(cloud.points), surface_(surface) {}
  // Owning its points (a mesh's vertices and face samples), the fitter may add points where the
  // faces between them are left uncovered (SlimFitOptions::cover_face_holes).
  SlimFitter(PointCloud&& cloud, const SlimFitOptions& options, const PolygonMesh* surface, std::vector<std::uint32_t> face_of)
      : owned_(std::move(cloud)), cloud_(owned_), opt_(options), P_(owned_.points), surface_(surface),
        face_of_(std::move(face_of)), can_add_points_(true) {}

  SlimFitResult run() {
    const auto t_start = Clock::now();
    validate(cloud_, opt_);
    setup();
    auto t0 = Clock::now();
    initial_candidates();
    st_.time_candidates = seconds_since(t0);
    t0 = Clock::now();
    cover(nullptr);
    st_.patches_before_pruning = chosen_.size();
    prune();
    st_.time_cover = seconds_since(t0);
    build_model();
    t0 = Clock::now();
    verify_and_repair();
    st_.time_verify = seconds_since(t0);
    st_.time_total = seconds_since(t_start);
    finish();
    return std::move(result_);
  }

private:
  void setup() {
    const std::size_t n = P_.size();
    st_.points = n;
    Box3 box;
    for (const auto& p : P_) box.extend(p);
    st_.diagonal = box.diagonal();
    E_ = opt_.max_error_is_absolute ? opt_.max_error : opt_.max_error * st_.diagonal;
    st_.max_error_abs = E_;
    const auto t0 = Clock::now();
    if (cloud_.has_normals()) {
      N_.resize(n);
      for (std::size_t i = 0; i < n; ++i) N_[i] = cloud_.normals[i].normalized();
    } else {
      N_ = estimate_normals(P_, {.neighbours = opt_.normal_neighbours}).normals;
      st_.normals_estimated = true;
      log::info("fit_slim: the cloud has no normals; estimated them (PCA over {} neighbours, MST orientation)",
                opt_.normal_neighbours);
    }
    st_.time_normals = seconds_since(t0);
    // The point indices and the data's surface are independent: built side by side.
    auto t1 = Clock::now();
    tbb::parallel_invoke(
        [&] {
          index_ = std::make_unique<PointIndex>(P_);
          subsamples_ = std::make_unique<Subsamples>(P_, 4 * opt_.max_check_points, opt_.seed);
        },
        [&] {
          data_ = std::make_shared<DataSurface>(surface_ ? DataSurface::from_mesh(*surface_) : DataSurface::from_points(P_, N_));
        });
    log::debug("fit_slim: point indices and the data's surface ({}) in {:.2f} s", surface_ ? "mesh" : "tangent discs",
               seconds_since(t1));
    t1 = Clock::now();
    probe_height_ = probe_heights(P_, N_, opt_.probe_factor * E_, surface_ ? data_.get() : nullptr);
    log::debug("fit_slim: probe heights in {:.2f} s", seconds_since(t1));
    if (surface_ && opt_.face_patches && face_of_.size() == n)
      faces_ = std::make_unique<FaceSet>(*surface_, std::move(face_of_), P_, opt_.face_prisms);
    if (faces_)
      for (std::size_t k = 0; k < faces_->mesh->face_count(); ++k)
        if (faces_->centroid[k] != FaceSet::kNone) face_triangles_ += faces_->mesh->face(k).size() - 2;
    make_fitter();
    st_.subsample_levels = subsamples_->levels.size();
    order_.resize(n);
    std::iota(order_.begin(), order_.end(), 0u);
    std::mt19937_64 rng(opt_.seed);
    std::shuffle(order_.begin(), order_.end(), rng);
    covered_.assign(n, 0);
    uncovered_ = n;
    cap_.assign(n, std::numeric_limits<double>::infinity());
  }

  void make_fitter() {
    fitter_ = std::make_unique<BallFitter>(BallFitter{P_, N_, *index_, opt_, E_, opt_.probe_factor * E_});
    fitter_->subsamples = subsamples_.get();
    fitter_->data = data_.get();
    fitter_->faces = faces_.get();
    fitter_->diagonal = st_.diagonal;
  }

  struct Changed;  // below: the balls a repair changed

  // The chosen balls that may hold a point of the triangle abc, nearest centres first.
  void balls_near_triangle(const PointIndex& index, double max_radius, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c, std::vector<Neighbour>& nb, std::vector<std::uint32_t>& near) const {
    const auto& slims = result_.model.slims;
    const Eigen::Vector3d mid = (a + b + c) / 3.0;
    const double spread = std::max({(a - mid).norm(), (b - mid).norm(), (c - mid).norm()});
    index.radius(mid, max_radius + spread, nb);
    std::sort(nb.begin(), nb.end(), [](const Neighbour& x, const Neighbour& y) { return x.second < y.second; });
    near.clear();
    for (const auto& [i, d2] : nb)
      if (std::sqrt(d2) < slims[i].radius + spread) near.push_back(std::uint32_t(i));
  }

  // The triangle pqs split at its edges' midpoints: visit(corner piece ×3, middle piece).
  template <class Visit>
  static void split_in_four(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& s, Visit&& visit) {
    const Eigen::Vector3d pq = 0.5 * (p + q), qs = 0.5 * (q + s), sp = 0.5 * (s + p);
    visit(p, pq, sp);
    visit(pq, q, qs);
    visit(sp, qs, s);
    visit(pq, qs, sp);
  }

  // Spots of the data's faces outside every chosen ball: holes of the drawn surface between
  // points that are all covered. A fan triangle some one ball holds whole (its three corners:
  // balls are convex) is covered; else it is split in four, down to face_hole_depth levels, and
  // a smallest piece contributes its first corner or centroid that no ball holds.
  // index: the round's index of the patches' centres; changed: the balls that left or joined
  // the model since the last check (none: the first), so a face covered then and far from all
  // of them is covered still.
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> face_holes(const PointIndex& index, const Changed* changed) {
    const auto& slims = result_.model.slims;
    if (!faces_ || slims.empty()) return {};
    double max_radius = 0;
    for (const auto& s : slims) max_radius = std::max(max_radius, s.radius);
    const PolygonMesh& m = *faces_->mesh;
    // A ray along the face's normal meets such a zero set within this of the face (twice the
    // surface bound: the points of a noisy face may lie beyond the bound from a patch within E of
    // its vertices; a face patch across a crease lies hundreds of E away).
    const double band = 2.0 * opt_.surface_factor * E_;
    if (!changed) face_covered_.assign(m.face_count(), 0);
    tbb::enumerable_thread_specific<std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>> found;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.face_count(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
      auto& out = found.local();
      std::vector<Neighbour> nb;
      std::vector<std::uint32_t> near;
      for (std::size_t f = r.begin(); f != r.end(); ++f) {
        if (faces_->centroid[f] == FaceSet::kNone) continue;  // a sliver: no surface of its own
        const auto vs = m.face(f);
        if (face_covered_[f] && changed) {
          const Eigen::Vector3d& o = P_[faces_->centroid[f]];
          if (!changed->near_ball(o, faces_->reach[f], nb)) continue;
        }
        const std::size_t spots_before = out.size();
        for (std::size_t k = 1; k + 1 < vs.size(); ++k) {
          const Eigen::Vector3d &a = m.vertices[vs[0]], &b = m.vertices[vs[k]], &c = m.vertices[vs[k + 1]];
          balls_near_triangle(index, max_radius, a, b, c, nb, near);
          // Inside the ball and its clip planes, its zero set passing within `band`:
          // a boundary plane that stops a sheet short of a crease leaves the strip beyond it
          // uncovered although the ball reaches across, and the prism of a face patch across
          // the crease holds the strip but its plane is elsewhere. (Ball and planes are convex,
          // and so is the band about a plane, so a piece whose corners one such patch holds is
          // held whole, up to a quadric's bending over the piece.)
          const auto holds = [&](std::uint32_t i, const Eigen::Vector3d& x) {
            const SlimPatch& sp = slims[i];
            if (!((x - sp.centre).squaredNorm() < sp.radius * sp.radius)) return false;
            const Eigen::Vector3d u = (x - sp.centre) / sp.radius;
            if (!sp.clips.keeps(u)) return false;
            const double g = sp.local.eval(u), gn = sp.local.gradient(u).norm();
            return std::abs(g) * sp.radius <= band * gn;
          };
          const auto any_holds = [&](const Eigen::Vector3d& x) {
            return std::any_of(near.begin(), near.end(), [&](std::uint32_t i) { return holds(i, x); });
          };
          const auto check = [&](const auto& self, const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                                 const Eigen::Vector3d& s, int depth) -> void {
            for (const std::uint32_t i : near)
              if (holds(i, p) && holds(i, q) && holds(i, s)) return;
            if (depth == opt_.face_hole_depth) {
              for (const Eigen::Vector3d& x : {Eigen::Vector3d((p + q + s) / 3.0), p, q, s})
                if (!any_holds(x)) {
                  out.push_back({std::uint32_t(f), x});
                  return;
                }
              return;
            }
            split_in_four(p, q, s, [&](const auto&... piece) { self(self, piece..., depth + 1); });
          };
          check(check, a, b, c, 0);
        }
        face_covered_[f] = out.size() == spots_before;
      }
    });
    std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> all;
    for (auto& v : found) all.insert(all.end(), v.begin(), v.end());
    // The same spot from two pieces (a shared corner) once.
    std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) {
      return std::tie(x.first, x.second.x(), x.second.y(), x.second.z()) < std::tie(y.first, y.second.x(), y.second.y(), y.second.z());
    });
    all.erase(std::unique(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.first == y.first && x.second == y.second; }),
              all.end());
    return all;
  }

  bool face_prisms() const { return faces_ && opt_.face_patches && opt_.face_prisms; }

  // Holes a view sees although the balls cover the face: a ray through a face's spot from a
  // direction within view_hole_angle_deg of its normal that meets no patch near the face (a patch
  // leaning against the face at a grazing view, a hit just outside its ball's rim or clip
  // planes). The lattice check above is view-independent and cannot see these (buddha at 1e-2:
  // hole pixels inside balls whose zero sets pass 0.002–0.15E from the data). Each fan triangle's
  // centroid is seen along its normal and along two cones of view_hole_rays directions about it,
  // from L before it (L the surface band at the widest angle) on (seen_through). Faces covered at the last check and far from every changed ball are
  // skipped; faces that hold a face patch already are not checked (their prism holds the spot).
  // Whether the view along d sees the data at x (the first data hit from L before it is x, from
  // its front, and the data covers the view's neighbourhood: rays surface_factor·E to each side
  // meet it from the front too, so x is not on the data's silhouette), but the model shows nothing
  // anywhere on that ray: a hole as bench fit counts them (fit/surface_error.h).
  bool seen_through(const ReferenceScene& scene, const TraceOptions& trace, const Eigen::Vector3d& x, const Eigen::Vector3d& d,
                    double L) const {
    const Eigen::Vector3d o = x - L * d;
    bool front = false;
    const auto t = data_->intersect(Ray{o, d}, 0.0, &front);
    if (!t || !front || std::abs(*t - L) > 1e-3 * E_) return false;
    const Eigen::Vector3d u = d.unitOrthogonal(), v = d.cross(u);
    const double r = opt_.surface_factor * E_;
    static const std::array<Eigen::Vector2d, 6> kAround = [] {
      std::array<Eigen::Vector2d, 6> a;
      for (int k = 0; k < 6; ++k) a[k] = {std::cos(std::numbers::pi * k / 3.0), std::sin(std::numbers::pi * k / 3.0)};
      return a;
    }();
    for (const Eigen::Vector2d& a : kAround)
      if (!data_->intersect(Ray{o + r * (a[0] * u + a[1] * v), d}, 0.0, &front) || !front) return false;
    // Last, as the dearest: the whole ray through the blend.
    return !scene.trace(Ray{o, d}, 0.0, kInf, trace);
  }

  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> view_holes(const ReferenceScene& scene, const PointIndex& index,
                                                                    const Changed* changed) {
    const auto& slims = result_.model.slims;
    if (!faces_ || slims.empty() || opt_.view_hole_rays <= 0) return {};
    double max_radius = 0;
    for (const auto& s : slims) max_radius = std::max(max_radius, s.radius);
    const PolygonMesh& m = *faces_->mesh;
    const double widest = std::clamp(opt_.view_hole_angle_deg, 0.0, 85.0) * std::numbers::pi / 180.0;
    const double L = 2.0 * opt_.surface_factor * E_ / std::cos(widest);
    // meets_every_view: normals within `lean` of the face's (views then meet them at most 85° off).
    const double lean = std::max(0.0, 85.0 * std::numbers::pi / 180.0 - widest);
    if (!changed) view_clear_.assign(m.face_count(), 0);
    view_clear_.resize(m.face_count(), 0);
    face_patched_.resize(m.face_count(), 0);
    TraceOptions trace;
    trace.slim = blend();
    // The view directions in the face's frame (n, t1, t2): j = 0 the normal; then `rays` at half
    // the widest angle, `rays` at it, the outer cone turned by half a step.
    const int rays = opt_.view_hole_rays;
    std::vector<Eigen::Vector3d> cone;
    for (int j = 0; j <= 2 * rays; ++j) {
      const int ring = j == 0 ? 0 : (j - 1) / rays + 1;
      const double theta = widest * ring / 2.0;
      const double phi = 2.0 * std::numbers::pi * ((j - 1) % rays + (ring == 2 ? 0.5 : 0.0)) / rays;
      cone.emplace_back(std::cos(theta), std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi));
    }
    tbb::enumerable_thread_specific<std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>> found;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.face_count(), 128), [&](const tbb::blocked_range<std::size_t>& r) {
      auto& out = found.local();
      std::vector<Neighbour> nb;
      std::vector<std::uint32_t> near;
      for (std::size_t f = r.begin(); f != r.end(); ++f) {
        if (faces_->centroid[f] == FaceSet::kNone || !face_covered_[f] || face_patched_[f]) continue;
        const Eigen::Vector3d& o = P_[faces_->centroid[f]];
        if (view_clear_[f] && changed && !changed->near_ball(o, faces_->reach[f] + 2.0 * opt_.surface_factor * E_, nb)) continue;
        const auto vs = m.face(f);
        bool clear = true;
        for (std::size_t k = 1; k + 1 < vs.size() && clear; ++k) {
          const Eigen::Vector3d &a = m.vertices[vs[0]], &b = m.vertices[vs[k]], &c = m.vertices[vs[k + 1]];
          Eigen::Vector3d n = (b - a).cross(c - a);
          if (!(n.norm() > 0)) continue;
          n.normalize();
          if (n.dot(N_[faces_->centroid[f]]) < 0) n = -n;
          const Eigen::Vector3d t1 = (b - a).normalized(), t2 = n.cross(t1);
          // The balls that hold the triangle's spots: one of their patches hit on the ray makes
          // the blend hit it (each patch's own first hit, as the blend's first pass takes it), so
          // only a ray none of them meets is traced through the scene.
          balls_near_triangle(index, max_radius, a, b, c, nb, near);
          // A patch that meets every view of x without tracing: x well inside its ball and
          // planes, its zero set δ from x (to first order) and its normal within
          // 85° − view_hole_angle_deg of the face's, so every ray up to that angle meets it
          // front-facing within s = δ / cos 85° of x; twice that room is asked inside the ball and
          // the planes (the zero set's bending over s).
          const double steepest = std::cos(widest + lean);  // least |cos| of a view against such a normal
          const auto meets_every_view = [&](std::uint32_t i, const Eigen::Vector3d& x) {
            const SlimPatch& sp = slims[i];
            const Eigen::Vector3d u = (x - sp.centre) / sp.radius;
            const double r = u.norm();
            if (!(r < 1.0)) return false;
            const Eigen::Vector3d g = sp.local.gradient(u);
            const double gn = g.norm();
            if (!(gn > 0) || g.dot(n) < std::cos(lean) * gn) return false;
            const double room = 2.0 * std::abs(sp.local.eval(u)) / (gn * steepest) + 1e-3;
            if (1.0 - r <= room) return false;
            for (const ClipPlane& c : sp.clips)
              if (!(c.n.dot(u) + c.d > room * c.n.norm())) return false;
            return true;
          };
          const auto local_hit = [&](const Ray& ray) {
            Hit h;
            for (const std::uint32_t i : near)
              if (intersect_slim_patch(slims[i], ray, 0.0, 2.0 * L, h) && (h.point - slims[i].centre).norm() < slims[i].radius) return true;
            return false;
          };
          const auto sees_through = [&](const Eigen::Vector3d& x) {
            for (const Eigen::Vector3d& c : cone) {
              const Eigen::Vector3d d = -(c[0] * n + c[1] * t1 + c[2] * t2).normalized();
              if (!local_hit(Ray{x - L * d, d}) && seen_through(scene, trace, x, d, L)) return true;
            }
            return false;
          };
          // A piece one patch meets from every view at its three corners is clear (ball, planes
          // and the room they leave are convex); else it is split in four, down to
          // view_hole_depth levels, and a smallest piece's centroid is seen along the rays.
          const auto check = [&](const auto& self, const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& s,
                                 int depth) -> void {
            if (!clear) return;
            if (lean > 0)
              for (const std::uint32_t i : near)
                if (meets_every_view(i, p) && meets_every_view(i, q) && meets_every_view(i, s)) return;
            if (depth >= opt_.view_hole_depth) {
              const Eigen::Vector3d x = (p + q + s) / 3.0;
              if (lean > 0 && std::any_of(near.begin(), near.end(), [&](std::uint32_t i) { return meets_every_view(i, x); })) return;
              if (sees_through(x)) {
                out.push_back({std::uint32_t(f), x});
                clear = false;
              }
              return;
            }
            split_in_four(p, q, s, [&](const auto&... piece) { self(self, piece..., depth + 1); });
          };
          check(check, a, b, c, 0);
        }
        view_clear_[f] = clear;
      }
    });
    std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> all;
    for (auto& v : found) all.insert(all.end(), v.begin(), v.end());
    std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    return all;
  }


  // A face patch (BallFitter::face_patch) for each face that holds a spot, kept through pruning.
  std::size_t add_face_patches(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots) {
    const std::size_t first = balls_.size();
    for (std::size_t k = 0; k < spots.size(); ++k) {
      if (k > 0 && spots[k].first == spots[k - 1].first) continue;  // sorted by face
      if (auto b = fitter_->face_patch(spots[k].first)) {
        balls_.push_back(std::move(*b));
        face_patched_.resize(faces_->mesh->face_count(), 0);
        face_patched_[spots[k].first] = 1;
      }
    }
    covers_.resize(balls_.size());
    chosen_flag_.resize(balls_.size(), 0);
    pinned_.resize(balls_.size(), 0);
    // Not verified yet: the next round traces them whole.
    patch_excess_.resize(balls_.size(), -1.0);
    patch_errors_.resize(balls_.size());
    patch_reach_.resize(balls_.size(), kInf);
    std::vector<Neighbour> nb;
    for (std::size_t b = first; b < balls_.size(); ++b) {
      cover_of(b, nb);
      pinned_[b] = 1;
      take(std::uint32_t(b));
    }
    return balls_.size() - first;
  }

  // A regular ball (radius search, surface side) at the centroid of each face that holds a spot
  // (the centroid is one of the points), largest first, kept through pruning. A face whose
  // centroid lies within half the radius of a ball taken here needs none of its own; a face whose
  // ball comes out smaller than view_ball_min_reach × the face (or as a face patch, or unbounded)
  // joins `small` for a face patch instead. Returns the number of balls taken.
  std::size_t add_view_balls(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots,
                             std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& small) {
    std::vector<std::uint32_t> centres, face;
    std::vector<double> caps;
    for (std::size_t k = 0; k < spots.size(); ++k) {
      if (k > 0 && spots[k].first == spots[k - 1].first) continue;
      const auto c = faces_->centroid[spots[k].first];
      centres.push_back(c);
      face.push_back(spots[k].first);
      caps.push_back(cap_[c]);
    }
    const std::size_t first = balls_.size();
    evaluate(centres, &caps);
    std::vector<std::uint32_t> fresh(balls_.size() - first);
    std::iota(fresh.begin(), fresh.end(), std::uint32_t(first));
    settle(fresh);
    chosen_flag_.resize(balls_.size(), 0);
    pinned_.resize(balls_.size(), 0);
    patch_excess_.resize(balls_.size(), -1.0);
    patch_errors_.resize(balls_.size());
    patch_reach_.resize(balls_.size(), kInf);
    std::sort(fresh.begin(), fresh.end(), [&](auto a, auto b) { return balls_[a].R > balls_[b].R; });
    std::vector<std::uint32_t> taken;
    for (const auto b : fresh) {
      const Eigen::Vector3d& c = P_[balls_[b].centre];
      const std::uint32_t f = face[b - first];
      if (balls_[b].face >= 0 || !balls_[b].is_bounded || balls_[b].R < opt_.view_ball_min_reach * faces_->reach[f]) {
        small.push_back({f, c});
        continue;
      }
      if (std::any_of(taken.begin(), taken.end(), [&](auto t) { return (P_[balls_[t].centre] - c).norm() < 0.5 * balls_[t].R; }))
        continue;
      cap_[balls_[b].centre] = std::min(cap_[balls_[b].centre], balls_[b].R);
      pinned_[b] = 1;
      take(b);
      taken.push_back(b);
    }
    return taken.size();
  }

  // The spots join the points, uncovered, on their faces with their faces' normals.
  void add_points(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots) {
    const std::size_t n0 = P_.size();
    for (const auto& [f, x] : spots) {
      owned_.points.push_back(x);
      N_.push_back(N_[faces_->centroid[f]]);
      faces_->face_of.push_back(f);
    }
    const std::size_t n1 = P_.size();
    const std::vector<double> h = probe_heights(std::span<const Eigen::Vector3d>(P_).subspan(n0),
                                                std::span<const Eigen::Vector3d>(N_).subspan(n0), opt_.probe_factor * E_, data_.get());
    probe_height_.insert(probe_height_.end(), h.begin(), h.end());
    covered_.resize(n1, 0);
    cap_.resize(n1, kInf);
    point_error_.resize(n1, kInf);
    point_reach_.resize(n1, kInf);
    other_direction_.resize(n1, 0);
    for (std::size_t i = n0; i < n1; ++i) order_.push_back(std::uint32_t(i));
    index_ = std::make_unique<PointIndex>(P_);
    make_fitter();
    st_.hole_points += n1 - n0;
  }

  // Fits a ball around each centre (TBB-parallel) and records the points it covers. Radius
  // search warm-starts from the nearest pilot candidate; caps bound the radius (repair).
  void evaluate(const std::vector<std::uint32_t>& centres, const std::vector<double>* caps) {
    const std::size_t first = balls_.size();
    balls_.resize(first + centres.size());
    covers_.resize(first + centres.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, centres.size(), 4), [&](const tbb::blocked_range<std::size_t>& r) {
      BallFitter::Scratch s;
      std::vector<Neighbour> pn;
      for (std::size_t k = r.begin(); k != r.end(); ++k) {
        double guess = 0;
        if (pilot_index_) {
          pilot_index_->nearest(P_[centres[k]], 1, pn);
          guess = pilot_R_[pn[0].first];
        }
        Ball b = fitter_->grow(centres[k], s, caps ? (*caps)[k] : std::numeric_limits<double>::infinity(), guess);
        if (!opt_.lazy_surface_check) b = fitter_->settle(std::move(b), s);
        balls_[first + k] = std::move(b);
        cover_of(first + k, s.nb);
      }
    });
  }

  // The points candidate b covers: those within cover_fraction·R of its centre (½R for a ball
  // that never reached E) on its sheet.
  void cover_of(std::size_t b, std::vector<Neighbour>& nb) {
    const Ball& ball = balls_[b];
    const Eigen::Vector3d& c = P_[ball.centre];
    if (ball.face >= 0) {  // a face patch covers the points on its face
      index_->radius(c, ball.R, nb);
      auto& cov = covers_[b];
      cov.clear();
      for (const auto& [p, d2] : nb)
        if (faces_->distance(std::uint32_t(ball.face), P_[p]) <= 1e-3 * E_) cov.push_back(p);
      balls_[b].count = nb.size();
      return;
    }
    index_->radius(c, (ball.is_bounded ? opt_.cover_fraction : 0.5) * ball.R, nb);
    auto& cov = covers_[b];
    cov.clear();
    for (const auto& [p, d2] : nb)
      if (ball.owns((P_[p] - c) / ball.R, N_[p])) cov.push_back(p);
  }

  // The surface side of candidates (BallFitter::settle), in parallel; their covers follow.
  void settle(const std::vector<std::uint32_t>& ids) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ids.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
      BallFitter::Scratch s;
      for (std::size_t k = r.begin(); k != r.end(); ++k) {
        const std::uint32_t b = ids[k];
        if (balls_[b].settled) continue;
        balls_[b] = fitter_->settle(std::move(balls_[b]), s);
        cover_of(b, s.nb);
      }
    });
  }

  // A random fraction of the points; the first pilot_candidates search their radius from scratch.
  void initial_candidates() {
    const std::size_t n = P_.size();
    const std::size_t m0 = std::min(
        {n, opt_.max_candidates, std::max(opt_.min_candidates, std::size_t(opt_.candidate_fraction * double(n)))});
    std::vector<std::uint32_t> centres(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(m0));
    if (const std::size_t pilot = opt_.pilot_candidates; pilot > 0 && pilot < centres.size()) {
      std::vector<std::uint32_t> first(centres.begin(), centres.begin() + static_cast<std::ptrdiff_t>(pilot)),
          rest(centres.begin() + static_cast<std::ptrdiff_t>(pilot), centres.end());
      evaluate(first, nullptr);
      for (const auto& b : balls_)
        if (b.is_bounded) pilot_centres_.push_back(P_[b.centre]), pilot_R_.push_back(b.R);
      if (!pilot_centres_.empty())
        pilot_index_ = std::make_unique<PointIndex>(std::span<const Eigen::Vector3d>(pilot_centres_));
      // As many candidates as the pilots say the covering needs (about n / their mean cover,
      // balls overlapping about twice), times candidates_per_patch for the greedy to choose from.
      double covered = 0;
      for (std::size_t k = 0; k < pilot; ++k) covered += double(covers_[k].size());
      const double mean_cover = std::max(1.0, covered / double(pilot));
      const auto wanted = std::size_t(opt_.candidates_per_patch * 2.0 * double(n) / mean_cover);
      const std::size_t keep = std::clamp(wanted, std::min(opt_.min_candidates, rest.size()), rest.size());
      rest.resize(keep - std::min(keep, pilot));
      evaluate(rest, nullptr);
    } else {
      evaluate(centres, nullptr);
    }
  }

  std::size_t gain(std::uint32_t b) const {
    std::size_t g = 0;
    for (auto p : covers_[b]) g += !covered_[p];
    return g;
  }

  void take(std::uint32_t b) {
    chosen_.push_back(b);
    chosen_flag_[b] = 1;
    for (auto p : covers_[b])
      if (!covered_[p]) covered_[p] = 1, --uncovered_;
  }

  // Greedy covering over candidates [from, end) (lazy: a candidate's gain only decreases).
  // A candidate's surface side is checked when it reaches the top of the heap (lazy_surface_check),
  // together with the next unchecked ones in gain order so the checks run in parallel; settling
  // may shrink it, and it goes back into the heap with its new gain.
  void run_greedy(std::size_t from) {
    chosen_flag_.resize(balls_.size(), 0);
    for (std::size_t b = from; b < balls_.size(); ++b) heap_.push({gain(std::uint32_t(b)), std::uint32_t(b)});
    const std::size_t batch_size = std::max<std::size_t>(4, 4 * std::thread::hardware_concurrency());
    std::vector<std::uint32_t> batch;
    std::vector<std::pair<std::size_t, std::uint32_t>> aside;
    while (uncovered_ > 0 && !heap_.empty()) {
      auto [g, b] = heap_.top();
      heap_.pop();
      if (g == 0) break;
      const std::size_t now = gain(b);
      if (now < g) {
        if (now > 0) heap_.push({now, b});
        continue;
      }
      if (balls_[b].settled) {
        take(b);
        continue;
      }
      batch.assign(1, b);
      aside.clear();
      for (std::size_t looked = 0; batch.size() < batch_size && looked < 4 * batch_size && !heap_.empty(); ++looked) {
        const auto next = heap_.top();
        heap_.pop();
        // Only candidates whose gain is current join the batch (a stale one would rank lower).
        if (const std::size_t gn = gain(next.second); gn < next.first) {
          if (gn > 0) aside.push_back({gn, next.second});
        } else if (balls_[next.second].settled) {
          aside.push_back(next);
        } else {
          batch.push_back(next.second);
        }
      }
      settle(batch);
      for (const auto& a : aside) heap_.push(a);
      for (const auto c : batch)
        if (const std::size_t gc = gain(c); gc > 0) heap_.push({gc, c});
    }
  }

  // Greedy covering, adding uncovered points as new candidates until every point is covered.
  void cover(const std::vector<double>* cap_of_point) {
    run_greedy(0);
    while (uncovered_ > 0) {
      const std::size_t limit = std::max<std::size_t>(64, uncovered_ / 16);
      std::vector<std::uint32_t> fresh;
      std::vector<double> caps;
      for (auto p : order_)
        if (!covered_[p]) {
          fresh.push_back(p);
          if (cap_of_point) caps.push_back((*cap_of_point)[p]);
          if (fresh.size() >= limit) break;
        }
      const std::size_t from = balls_.size();
      evaluate(fresh, cap_of_point ? &caps : nullptr);
      run_greedy(from);
    }
  }

  // Drops balls whose covered points are all covered by other chosen balls (smallest first).
  void prune() {
    std::vector<std::uint16_t> multiplicity(P_.size(), 0);
    for (auto b : chosen_)
      for (auto p : covers_[b]) multiplicity[p] = std::uint16_t(std::min<int>(multiplicity[p] + 1, 60000));
    std::sort(chosen_.begin(), chosen_.end(), [&](auto a, auto b) { return covers_[a].size() < covers_[b].size(); });
    std::vector<std::uint32_t> kept;
    for (auto b : chosen_) {
      const bool redundant = !(b < pinned_.size() && pinned_[b]) &&
                             std::all_of(covers_[b].begin(), covers_[b].end(), [&](auto p) { return multiplicity[p] >= 2; });
      if (redundant) {
        for (auto p : covers_[b]) --multiplicity[p];
        chosen_flag_[b] = 0;
      } else {
        kept.push_back(b);
      }
    }
    chosen_.swap(kept);
  }

  void build_model() {
    auto& slims = result_.model.slims;
    slims.clear();
    for (auto b : chosen_) slims.push_back(SlimPatch{P_[balls_[b].centre], balls_[b].R, balls_[b].g, balls_[b].clips, std::nullopt, std::nullopt});
    result_.model.metadata["slim_offset"] = fmt::format("{:.6g}", opt_.blend_offset);
    if (const SlimBlendOptions b = blend(); std::isfinite(b.max_push))
      result_.model.metadata["slim_max_push"] = fmt::format("{:.9g}", b.max_push);
    else
      result_.model.metadata.erase("slim_max_push");
  }

  // The blend the bound is certified for (written with the model, build_model).
  SlimBlendOptions blend() const {
    SlimBlendOptions b;
    b.offset = opt_.blend_offset;
    if (opt_.blend_max_push > 0) b.max_push = opt_.blend_max_push * E_;
    return b;
  }

  // Points side: every point's probe against the blended surface (core/reference.h).
  // Culprits: patches whose own hit in the blend is farther than E, or whose ball holds a
  // point the blend misses.
  std::size_t verify_points(const ReferenceScene& scene, const PointIndex& centres, const std::vector<std::uint8_t>& stale,
                            std::vector<std::uint8_t>& at_fault) {
    const std::size_t n = P_.size();
    point_error_.resize(n, kInf);
    point_reach_.resize(n, kInf);
    other_direction_.resize(n, 0);
    const auto& slims = result_.model.slims;
    double max_radius = 0;
    for (const auto& s : slims) max_radius = std::max(max_radius, s.radius);
    TraceOptions trace;
    trace.slim = blend();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<SlimSample> blended;
      std::vector<Neighbour> near;
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        if (!stale[i]) continue;
        const double h = probe_height_[i];
        bool other = false;
        const PointProbe probe = measure_point(scene, trace, *index_, N_, P_[i], N_[i], h, E_, &blended, &other);
        // Measured along its neighbourhood's normal: traced again in every round (staleness
        // follows the first ray only).
        other_direction_[i] = other;
        point_error_[i] = probe.error;
        point_reach_[i] = probe.reach;
        if (!std::isfinite(probe.error)) {
          centres.radius(P_[i], max_radius, near);
          for (const auto& [k, d2] : near)
            if (d2 <= slims[k].radius * slims[k].radius) at_fault[k] = 1;  // benign race: all store 1
          continue;
        }
        if (probe.error > E_)
          for (const auto& s : blended)
            if (std::abs(s.hit.t - h) > E_) at_fault[static_cast<std::size_t>(s.index)] = 1;
      }
    });
    std::size_t failing = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (!(point_error_[i] <= E_) && ++failing <= 8)
        log::debug("fit_slim: point {} at ({:.6g}, {:.6g}, {:.6g}) normal ({:.3f}, {:.3f}, {:.3f}): {:.3g} E from the surface",
                   i, P_[i].x(), P_[i].y(), P_[i].z(), N_[i].x(), N_[i].y(), N_[i].z(), point_error_[i] / E_);
    return failing;
  }

  // The chosen patches' surface-sample distances, all in one list (the figures' source).
  void collect_surface_errors() {
    surface_error_.clear();
    for (const auto b : chosen_) surface_error_.insert(surface_error_.end(), patch_errors_[b].begin(), patch_errors_[b].end());
  }

  // Surface side: samples of every patch's zero set, each seen along its normal through the
  // blend; the blended point must lie within surface_factor·E of the data. Culprits: the
  // blended patches whose own hit is farther than local_surface_factor·E (all of them when none is).
  std::size_t verify_surface(const ReferenceScene& scene, const std::vector<std::uint8_t>& stale,
                             std::vector<std::uint8_t>& at_fault) {
    debug_shown_ = 0;
    const auto& slims = result_.model.slims;
    const double bound = opt_.surface_factor * E_, local = opt_.local_surface_factor * E_;
    const double h = opt_.surface_probe_factor * E_;
    TraceOptions trace;
    trace.slim = blend();
    shrink_.assign(slims.size(), opt_.shrink_step);
    patch_excess_.resize(balls_.size(), -1.0);
    patch_errors_.resize(balls_.size());
    patch_reach_.resize(balls_.size(), kInf);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slims.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<SlimSurfaceSample> zero, rim;
      std::vector<SlimSample> blended;
      for (std::size_t k = r.begin(); k != r.end(); ++k) {
        if (!stale[k]) continue;
        auto& errors = patch_errors_[chosen_[k]];
        double& reach = patch_reach_[chosen_[k]];
        errors.clear();
        reach = 0;
        // The patch alone on a lattice fine in world units (≈ verify_spacing·E), so slivers
        // past a curved boundary are found on large balls too; a patch found d > bound away
        // shrinks by √(bound/d) (a sliver's sagitta goes with R²).
        const int grid = std::clamp(static_cast<int>(std::ceil(2.0 * slims[k].radius / (opt_.verify_spacing * E_))),
                                    opt_.verify_surface_grid, opt_.verify_max_grid);
        // A patch's own zero set does not change between rounds: checked once per candidate ball.
        double& excess = patch_excess_[chosen_[k]];
        // Skipped when settle's check already passed on a lattice at least as fine (same bound).
        if (excess < 0)
          excess = grid <= balls_[chosen_[k]].surface_lattice ? 0.0 : zero_set_excess(slims[k], *data_, local, grid, 1);
        if (const double d = excess; d > 0) {
          at_fault[k] = 1;
          errors.push_back(d);
          reach = kInf;
          shrink_[k] = std::clamp(std::sqrt(local / d), 0.3, opt_.shrink_step);
          continue;
        }
        zero.clear();
        sample_slim_patch(slims[k], opt_.verify_surface_grid, zero);
        // The rim every E/2: its points off the data are seen through the blend too (elsewhere
        // other patches hide it, or the lattice samples above vouch for the blend).
        rim.clear();
        sample_slim_rim(slims[k], 0.5 * E_, rim);
        for (const auto& z : rim)
          if (!(data_->distance(z.point, bound, bound) <= bound)) zero.push_back(z);
        for (const auto& z : zero) {
          const auto hit = scene.trace(Ray{z.point + h * z.normal, -z.normal}, 0.0, kInf, trace, &blended);
          if (!hit) continue;
          reach = std::max(reach, blend_reach(blended, trace.slim));
          double d = data_->distance(hit->point, bound);
          if (!(d <= bound)) d = data_->distance(hit->point);
          errors.push_back(d);
          if (d <= bound) continue;
          reach = kInf;
          if (log::level() <= log::Level::debug) {
            const std::lock_guard lock(debug_mutex_);
            if (++debug_shown_ <= 8) {
              std::string who;
              for (const auto& sb : blended) {
                const Ball& bb = balls_[chosen_[static_cast<std::size_t>(sb.index)]];
                who += fmt::format(" [{}{} R {:.3g}E w {:.2g} t-h {:.3g}E data {:.3g}E]", sb.index, bb.face >= 0 ? " face" : "",
                                   sb.radius / E_, sb.weight, (sb.hit.t - h) / E_, data_->distance(sb.hit.point) / E_);
              }
              log::debug("fit_slim: surface sample of patch {}{} (R {:.3g}E) at ({:.6g}, {:.6g}, {:.6g}): blend {:.3g}E from the data;{}", k,
                         balls_[chosen_[k]].face >= 0 ? " (face)" : "", slims[k].radius / E_, z.point.x(), z.point.y(), z.point.z(), d / E_, who);
            }
          }
          bool blamed = false;
          for (const auto& s : blended)
            if (data_->distance(s.hit.point, local) > local) at_fault[static_cast<std::size_t>(s.index)] = 1, blamed = true;
          if (!blamed)
            for (const auto& s : blended) at_fault[static_cast<std::size_t>(s.index)] = 1;
        }
      }
    });
    collect_surface_errors();
    std::size_t failing = 0;
    for (const double e : surface_error_) failing += e > bound;
    return failing;
  }

  // What a repair changed: the balls that left the model and those that joined it. Only the
  // probes whose blend looked inside one of them need tracing again.
  struct Changed {
    std::vector<Eigen::Vector3d> centres;
    std::vector<double> radii;
    double max_radius = 0;
    std::unique_ptr<PointIndex> index;

    // Whether any changed ball meets the segment o + t·d, t ∈ [0, length] (d unit).
    // Whether any changed ball meets the ball (c, r).
    bool near_ball(const Eigen::Vector3d& c, double r, std::vector<Neighbour>& near) const {
      if (centres.empty()) return false;
      index->radius(c, r + max_radius, near);
      for (const auto& [k, d2] : near)
        if (d2 <= (r + radii[k]) * (r + radii[k])) return true;
      return false;
    }

    bool meets(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double length, std::vector<Neighbour>& near) const {
      if (centres.empty()) return false;
      if (!std::isfinite(length)) return true;
      index->radius(o + 0.5 * length * d, 0.5 * length + max_radius, near);
      for (const auto& [c, d2] : near) {
        const Eigen::Vector3d v = centres[c] - o;
        const double t = std::clamp(v.dot(d), 0.0, length);
        if ((v - t * d).squaredNorm() <= radii[c] * radii[c] * (1.0 + 1e-9)) return true;
      }
      return false;
    }
  };

  Changed changed_since(const std::vector<std::uint32_t>& before) const {
    std::vector<std::uint8_t> was(balls_.size(), 0), is(balls_.size(), 0);
    for (const auto b : before) was[b] = 1;
    for (const auto b : chosen_) is[b] = 1;
    Changed c;
    for (std::size_t b = 0; b < balls_.size(); ++b)
      if (was[b] != is[b]) {
        c.centres.push_back(P_[balls_[b].centre]);
        c.radii.push_back(balls_[b].R);
        c.max_radius = std::max(c.max_radius, balls_[b].R);
      }
    c.index = std::make_unique<PointIndex>(std::span<const Eigen::Vector3d>(c.centres));
    return c;
  }

  // A verified model: its balls and what verification measured on it.
  struct Verified {
    std::vector<std::uint32_t> chosen;
    std::vector<double> point_error;
    std::vector<std::vector<double>> patch_errors;  // per chosen ball
    std::size_t blend_failures = 0, surface_failures = 0, face_holes = 0, view_holes = 0;
    int round = -1;  // -1: none
    double score = 0;  // failures() of that model
  };

  // How far the verified model is from its contract: the share of points beyond E, plus the share
  // of surface samples beyond the surface bound, plus the share of the data's area outside every
  // ball (face_holes: at most one spot per smallest piece of a fan triangle). No count alone: a
  // fit below its data's noise trades a few points just past E for many fewer surface samples
  // far off, or fewer holes for more of both.
  double failures() const {
    double f = double(st_.blend_failures) / double(std::max<std::size_t>(1, P_.size())) +
               double(st_.surface_failures) / double(std::max<std::size_t>(1, surface_error_.size()));
    if (faces_ && st_.face_holes > 0)
      f += double(st_.face_holes) / (double(std::max<std::size_t>(1, face_triangles_)) * double(1u << (2 * opt_.face_hole_depth)));
    // A fan triangle seen through from some view: counted as the whole triangle.
    if (faces_ && st_.view_holes > 0) f += double(st_.view_holes) / double(std::max<std::size_t>(1, face_triangles_));
    return f;
  }

  Verified snapshot(int round, double score) const {
    Verified v{chosen_, point_error_, {}, st_.blend_failures, st_.surface_failures, st_.face_holes, st_.view_holes, round, score};
    v.patch_errors.reserve(chosen_.size());
    for (const auto b : chosen_) v.patch_errors.push_back(patch_errors_[b]);
    return v;
  }

  void restore(Verified&& v) {
    for (const auto b : chosen_) chosen_flag_[b] = 0;
    chosen_ = std::move(v.chosen);
    for (std::size_t k = 0; k < chosen_.size(); ++k) {
      chosen_flag_[chosen_[k]] = 1;
      patch_errors_[chosen_[k]] = std::move(v.patch_errors[k]);
    }
    point_error_ = std::move(v.point_error);
    collect_surface_errors();
    st_.blend_failures = v.blend_failures;
    st_.surface_failures = v.surface_failures;
    st_.face_holes = v.face_holes;
    st_.view_holes = v.view_holes;
    build_model();
  }

  // Rounds of verification (both sides); the patches at fault are removed, their centres come
  // back no larger than shrink_step·R, and the points they covered are covered again.
  void verify_and_repair() {
    std::vector<std::uint32_t> before;  // the chosen balls of the last verified model
    int fill_rounds = 0;  // rounds that added points on face holes
    // The best model verified since the points last changed. A repair can make things worse where
    // E is far below the data's sampling (armadillo at 1e-4: 26 points beyond E after the first
    // round, 3,550 after six more, each changing most balls); the fit then returns the best one,
    // and stops after three rounds that did not improve on it.
    Verified best;
    for (int round = 0;; ++round) {
      // Rounds that add points do not count against repair_rounds (up to face_hole_rounds of them).
      const int budget = opt_.repair_rounds + std::min(fill_rounds, std::max(0, opt_.face_hole_rounds));
      const ReferenceScene scene(result_.model);
      const auto& slims = result_.model.slims;
      std::vector<Eigen::Vector3d> centres;
      for (const auto& s : slims) centres.push_back(s.centre);
      const PointIndex centre_index{std::span<const Eigen::Vector3d>(centres)};
      std::vector<std::uint8_t> at_fault(slims.size(), 0);
      // Which probes to trace: all in the first round; afterwards those that failed, and those
      // whose blend may have changed (their ray meets a ball that left or joined the model).
      std::vector<std::uint8_t> stale_points(P_.size(), 1), stale_patches(slims.size(), 1);
      std::optional<Changed> changed_balls;
      if (round > 0) {
        changed_balls = changed_since(before);
        const Changed& changed = *changed_balls;
        const double bound = opt_.surface_factor * E_, h = opt_.surface_probe_factor * E_;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P_.size(), 1024), [&](const auto& r) {
          std::vector<Neighbour> near;
          for (std::size_t i = r.begin(); i != r.end(); ++i)
            stale_points[i] = !(point_error_[i] <= E_) || other_direction_[i] ||
                              changed.meets(P_[i] + probe_height_[i] * N_[i], -N_[i], point_reach_[i], near);
        });
        std::vector<std::uint8_t> was(balls_.size(), 0);
        for (const auto b : before) was[b] = 1;
        std::vector<Neighbour> near;
        for (std::size_t k = 0; k < slims.size(); ++k) {
          const auto b = chosen_[k];
          if (!was[b] || !std::isfinite(patch_reach_[b])) continue;
          bool failed = false;
          for (const double e : patch_errors_[b]) failed |= e > bound;
          if (failed) continue;
          // Every probe of this patch starts within R + h of its centre and looks patch_reach along.
          stale_patches[k] = changed.near_ball(slims[k].centre, slims[k].radius + h + patch_reach_[b], near);
        }
        std::size_t np = 0, nk = 0;
        for (const auto v : stale_points) np += v;
        for (const auto v : stale_patches) nk += v;
        log::debug("fit_slim: round {}: {} balls changed; tracing {} of {} point probes, {} of {} patches", round + 1,
                   changed.centres.size(), np, P_.size(), nk, slims.size());
      }
      st_.blend_failures = verify_points(scene, centre_index, stale_points, at_fault);
      shrink_.clear();
      st_.surface_failures = opt_.check_surface ? verify_surface(scene, stale_patches, at_fault) : 0;
      std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> holes;
      if (can_add_points_ && opt_.cover_face_holes) holes = face_holes(centre_index, changed_balls ? &*changed_balls : nullptr);
      st_.face_holes = holes.size();
      std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> seen;
      if (can_add_points_ && opt_.cover_face_holes && face_prisms()) {
        const auto t0 = Clock::now();
        seen = view_holes(scene, centre_index, changed_balls ? &*changed_balls : nullptr);
        log::debug("fit_slim: round {}: {} fan triangles seen through from some view ({:.2f} s)", round + 1, seen.size(), seconds_since(t0));
      }
      st_.view_holes = seen.size();
      const bool view_fill = !seen.empty() && round + 2 < budget;
      // More than one spot per 8 faces: the balls are smaller than the faces nearly everywhere
      // (E far below the data's sampling: bunny at 1e-4 had 88,211 for 69,451 faces). Points
      // there more than doubled the fit's work (51 s instead of 29 s) and left 2,881 points beyond
      // E; such faces get face patches instead (add_face_patches, with face_prisms), else the
      // spots are counted (face_holes) and left.
      const bool few = holes.size() <= std::max<std::size_t>(64, faces_ ? faces_->mesh->face_count() / 8 : 0);
      // Not in the last two rounds: the balls that cover new points need verifying and repairing too.
      const bool fill = !holes.empty() && few && round + 2 < budget;
      // Too many: the faces with spots get face patches of their own (below). So do the faces
      // with spots in the last round that may still change the model (too late for points: the
      // balls that would cover them would go unverified), as face patches are the data itself.
      const bool late = round + 2 >= budget && round + 1 < budget;
      const bool face_fill = !holes.empty() && face_prisms() && ((!few && round + 2 < budget) || late);
      const std::size_t failing =
          st_.blend_failures + st_.surface_failures + (fill || face_fill ? holes.size() : 0) + (view_fill ? seen.size() : 0);
      const double score = failures();
      st_.round_failures.push_back(score);
      st_.kept_round = round;
      const bool improved = best.round < 0 || score < best.score;
      const bool stalled = !improved && round - best.round >= 3;
      if (failing == 0 || round >= budget || stalled) {
        if (!improved) {
          log::info("fit_slim: the repairs after verification round {} made the fit worse ({} points beyond E and {} surface "
                    "samples beyond {}E in round {}, against {} and {}); the model of round {} is kept",
                    best.round + 1, st_.blend_failures, st_.surface_failures, opt_.surface_factor, round + 1,
                    best.blend_failures, best.surface_failures, best.round + 1);
          st_.kept_round = best.round;
          restore(std::move(best));
        }
        break;
      }
      if (improved) best = snapshot(round, score);
      // The model just verified: what changes from here on (face patches below, the repair) is
      // traced again next round.
      before = chosen_;
      if (fill) {
        ++fill_rounds;
        log::debug("fit_slim: round {}: {} spots of the data's faces outside every ball join the points", round + 1, holes.size());
        // One spot per face (the first; spots come sorted by face): the ball that covers it
        // mostly covers the face's others too, which the next round finds if not. Every spot at
        // once cost the bunny 260 points and 220 patches at 1e-3; one per face 74 and 35.
        // A face that still holds a spot after a point was added on it (the balls that cover
        // the points there come out smaller than the face: E below the sampling in this region)
        // gets a face patch instead of another point (bunny at 1e-4: 568 spots were left after
        // the fill rounds, each round's repair opening new ones).
        std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> one, again;
        hole_tried_.resize(faces_->mesh->face_count(), 0);
        for (std::size_t k = 0; k < holes.size(); ++k)
          if (k == 0 || holes[k].first != holes[k - 1].first)
            (hole_tried_[holes[k].first] && face_prisms() ? again : one).push_back(holes[k]);
        for (const auto& h : one) hole_tried_[h.first] = 1;
        add_points(one);
        if (!again.empty()) {
          const std::size_t added = add_face_patches(again);
          log::debug("fit_slim: round {}: {} faces with spots left after a point joined them get patches of their own", round + 1, added);
          st_.hole_face_patches += added;
        }
        best = Verified{};  // other points: not comparable
      } else if (face_fill) {
        // Too many to join the points: each face with a spot gets its own face patch instead, its
        // plane clipped to its prism — the data itself, covering the whole face.
        const std::size_t added = add_face_patches(holes);
        if (few)
          log::debug("fit_slim: round {}: {} spots of the data's faces outside every ball; too late for points, {} faces get "
                     "patches of their own", round + 1, holes.size(), added);
        else
          log::info("fit_slim: round {}: {} spots of the data's faces lie outside every ball (balls smaller than the faces: "
                    "E below the data's sampling); {} faces get patches of their own", round + 1, holes.size(), added);
        st_.hole_face_patches += added;
      } else if (!few && round == 0) {
        log::info("fit_slim: {} spots of the data's faces lie outside every ball (balls smaller than the faces: E below "
                  "the data's sampling); left as they are", holes.size());
      }
      if (view_fill) {
        // Faces inside the balls that a view still sees through: their own face patches (the
        // data there), as for the many spots above; with view_balls, a face seen through for the
        // first time gets a regular ball at its centroid instead, unless that ball would not
        // reach across the face.
        if (opt_.view_balls) {
          view_tried_.resize(faces_->mesh->face_count(), 0);
          std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> fresh, again;
          for (const auto& s : seen) (view_tried_[s.first] ? again : fresh).push_back(s);
          for (const auto& s : fresh) view_tried_[s.first] = 1;
          const std::size_t balls = add_view_balls(fresh, again);
          log::debug("fit_slim: round {}: {} faces seen through for the first time get {} balls at their centroids", round + 1,
                     fresh.size(), balls);
          st_.view_balls += balls;
          std::sort(again.begin(), again.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
          seen.swap(again);
        }
        const std::size_t added = add_face_patches(seen);
        log::debug("fit_slim: round {}: {} faces seen through from some view get patches of their own", round + 1, added);
        st_.view_face_patches += added;
      }
      ++st_.repair_rounds;
      log::debug("fit_slim: repair round {}: {} points beyond E, {} surface samples beyond {}E, {} face spots outside every "
                 "ball (failures {:.3g})", round + 1, st_.blend_failures, st_.surface_failures, opt_.surface_factor, st_.face_holes, score);
      // The late round's face patches are verified on the model as it is: a repair there opens
      // new spots that no later round may fill (bunny at 1e-4: 219 → 946).
      if (!(late && face_fill)) repair(at_fault);
      prune();
      build_model();
    }
  }

  void repair(const std::vector<std::uint8_t>& at_fault) {
    std::vector<std::uint32_t> keep;
    for (std::size_t k = 0; k < chosen_.size(); ++k) {
      const auto b = chosen_[k];
      if (k >= at_fault.size() || !at_fault[k] || balls_[b].R <= 0) {  // new since verified (add_face_patches)
        keep.push_back(b);
        continue;
      }
      chosen_flag_[b] = 0;
      const double f = k < shrink_.size() ? shrink_[k] : opt_.shrink_step;
      cap_[balls_[b].centre] = std::min(cap_[balls_[b].centre], f * balls_[b].R);
    }
    chosen_.swap(keep);
    std::fill(covered_.begin(), covered_.end(), 0);
    uncovered_ = P_.size();
    for (auto b : chosen_)
      for (auto p : covers_[b])
        if (!covered_[p]) covered_[p] = 1, --uncovered_;
    // Centres of culprits whose points are now uncovered come back first, capped.
    std::vector<std::uint32_t> again;
    std::vector<double> caps;
    for (std::size_t i = 0; i < P_.size(); ++i)
      if (std::isfinite(cap_[i]) && !covered_[i]) again.push_back(std::uint32_t(i)), caps.push_back(cap_[i]);
    const std::size_t from = balls_.size();
    evaluate(again, &caps);
    for (std::size_t b = from; b < balls_.size(); ++b) cap_[balls_[b].centre] = std::min(cap_[balls_[b].centre], balls_[b].R);
    // Candidates larger than their centre's cap retire, so re-covering cannot regrow them.
    chosen_flag_.resize(balls_.size(), 0);
    for (std::size_t b = 0; b < from; ++b)
      if (!chosen_flag_[b] && balls_[b].R > cap_[balls_[b].centre]) covers_[b].clear();
    while (!heap_.empty()) heap_.pop();
    cover(&cap_);
    // A point still beyond E although covered (a tip, a spike: it sits near the rims of the balls
    // that cover it, where their weights vanish and farther patches dominate the blend) gets a
    // ball of its own, centred on it and kept through pruning.
    std::vector<std::uint32_t> stubborn;
    std::vector<double> stubborn_caps;
    for (std::size_t i = 0; i < P_.size(); ++i)
      if (!(point_error_[i] <= E_) && covered_[i]) stubborn.push_back(std::uint32_t(i)), stubborn_caps.push_back(cap_[i]);
    if (stubborn.empty() || stubborn.size() > P_.size() / 100) return;
    const std::size_t first = balls_.size();
    // Centred on the point itself: a face patch would centre on its face's centroid instead.
    const FaceSet* faces = std::exchange(fitter_->faces, nullptr);
    evaluate(stubborn, &stubborn_caps);
    fitter_->faces = faces;
    std::vector<std::uint32_t> fresh(balls_.size() - first);
    std::iota(fresh.begin(), fresh.end(), std::uint32_t(first));
    settle(fresh);
    chosen_flag_.resize(balls_.size(), 0);
    pinned_.resize(balls_.size(), 0);
    for (std::size_t b = first; b < balls_.size(); ++b) {
      cap_[balls_[b].centre] = std::min(cap_[balls_[b].centre], balls_[b].R);
      pinned_[b] = 1;
      take(std::uint32_t(b));
    }
  }

  void finish() {
    double sum_sq = 0;
    std::size_t finite = 0;
    st_.max_blend = 0;
    for (const double e : point_error_) {
      st_.max_blend = std::max(st_.max_blend, e);
      if (std::isfinite(e)) sum_sq += e * e, ++finite;
    }
    st_.rms_blend = finite ? std::sqrt(sum_sq / double(finite)) : 0;
    st_.surface_samples = surface_error_.size();
    if (!surface_error_.empty()) {
      std::vector<double> e = surface_error_;
      const std::size_t k = std::min(e.size() - 1, static_cast<std::size_t>(0.999 * double(e.size() - 1)));
      std::nth_element(e.begin(), e.begin() + static_cast<std::ptrdiff_t>(k), e.end());
      st_.surface_p999 = e[k];
      st_.surface_max = *std::max_element(e.begin(), e.end());
    }
    double sum_sq_taubin = 0;
    std::size_t in_balls = 0;
    for (auto b : chosen_) {
      st_.max_taubin = std::max(st_.max_taubin, balls_[b].max_taubin);
      sum_sq_taubin += balls_[b].sum_sq_taubin;
      in_balls += balls_[b].count;
      st_.height_patches += balls_[b].is_height;
      st_.unbounded_patches += !balls_[b].is_bounded;
      st_.clipped_patches += !balls_[b].clips.empty();
    }
    st_.rms_taubin = in_balls ? std::sqrt(sum_sq_taubin / double(in_balls)) : 0;
    st_.candidates = balls_.size();
    result_.data = data_;
    result_.surface_error_per_patch.assign(chosen_.size(), 0.0);
    for (std::size_t k = 0; k < chosen_.size() && chosen_[k] < patch_errors_.size(); ++k)
      for (const double e : patch_errors_[chosen_[k]]) result_.surface_error_per_patch[k] = std::max(result_.surface_error_per_patch[k], e);
    st_.settled_candidates = std::size_t(std::count_if(balls_.begin(), balls_.end(), [](const Ball& b) { return b.settled; }));
    st_.patches = chosen_.size();

    auto& md = result_.model.metadata;
    auto num = [](double v) { return fmt::format("{:.6g}", v); };
    md["producer"] = "quadrix fit";
    md["max_error"] = num(E_ / st_.diagonal);
    md["max_error_abs"] = num(E_);
    md["surface_bound_abs"] = num(opt_.surface_factor * E_);
    md["surface_reference"] = surface_ ? "mesh" : "points";
    md["diagonal"] = num(st_.diagonal);
    md["normals"] = st_.normals_estimated ? "estimated" : "given";
    md["points"] = std::to_string(st_.points);
    if (st_.hole_points > 0) md["hole_points"] = std::to_string(st_.hole_points);
    if (st_.hole_face_patches > 0) md["hole_face_patches"] = std::to_string(st_.hole_face_patches);
    if (st_.view_face_patches > 0) md["view_face_patches"] = std::to_string(st_.view_face_patches);
    if (st_.view_balls > 0) md["view_balls"] = std::to_string(st_.view_balls);
    if (can_add_points_ && opt_.cover_face_holes && face_prisms()) md["view_holes"] = std::to_string(st_.view_holes);
    if (can_add_points_ && opt_.cover_face_holes) md["face_holes"] = std::to_string(st_.face_holes);
    md["patches"] = std::to_string(st_.patches);
    md["candidates"] = std::to_string(st_.candidates);
    md["subsample_levels"] = std::to_string(st_.subsample_levels);
    md["height_patches"] = std::to_string(st_.height_patches);
    if (opt_.sharp) md["clipped_patches"] = std::to_string(st_.clipped_patches);
    md["measured_max_error"] = num(st_.max_blend);
    md["measured_rms_error"] = num(st_.rms_blend);
    md["measured_failures"] = std::to_string(st_.blend_failures);
    md["measured_surface_max"] = num(st_.surface_max);
    md["measured_surface_p999"] = num(st_.surface_p999);
    md["measured_surface_failures"] = std::to_string(st_.surface_failures);
    md["taubin_max_error"] = num(st_.max_taubin);
    md["taubin_rms_error"] = num(st_.rms_taubin);
    md["time_normals_s"] = num(st_.time_normals);
    md["time_candidates_s"] = num(st_.time_candidates);
    md["time_cover_s"] = num(st_.time_cover);
    md["time_verify_s"] = num(st_.time_verify);
    md["time_total_s"] = num(st_.time_total);
    log::info("fit_slim: {} points, {} patches ({} candidates, {} checked on the surface side), E = {:.3g}: points max {:.3g} ({} beyond E), "
              "surface max {:.3g} p99.9 {:.3g} ({} samples beyond {}E), {:.2f} s",
              st_.points, st_.patches, st_.candidates, st_.settled_candidates, E_, st_.max_blend, st_.blend_failures, st_.surface_max,
              st_.surface_p999, st_.surface_failures, opt_.surface_factor, st_.time_total);
    if (st_.face_holes > 0)
      log::info("fit_slim: {} spots of the data's faces outside every ball (holes between covered points; {} points "
                "were added on such spots)", st_.face_holes, st_.hole_points);
  }

  static constexpr double kInf = std::numeric_limits<double>::infinity();
  PointCloud owned_;  // the points, when the fitter owns them (may grow: add_points)
  const PointCloud& cloud_;
  const SlimFitOptions& opt_;
  const std::vector<Eigen::Vector3d>& P_;
  const PolygonMesh* surface_;
  std::vector<Eigen::Vector3d> N_;
  double E_ = 0;
  SlimFitResult result_;
  SlimFitStats& st_ = result_.stats;
  std::unique_ptr<PointIndex> index_;
  std::unique_ptr<Subsamples> subsamples_;
  std::shared_ptr<DataSurface> data_;
  std::unique_ptr<BallFitter> fitter_;
  std::vector<std::uint32_t> order_;                 // the points in random order
  std::mutex debug_mutex_;                           // -vv: the first failing surface samples
  std::size_t debug_shown_ = 0;
  std::vector<Ball> balls_;                          // evaluated candidates
  std::vector<std::vector<std::uint32_t>> covers_;   // points each candidate covers
  std::vector<Eigen::Vector3d> pilot_centres_;
  std::vector<double> pilot_R_;
  std::unique_ptr<PointIndex> pilot_index_;
  std::vector<std::uint8_t> covered_, chosen_flag_;
  std::vector<std::uint8_t> pinned_;                 // per candidate: kept through pruning (repair)
  std::size_t uncovered_ = 0;
  std::vector<std::uint32_t> chosen_;
  std::priority_queue<std::pair<std::size_t, std::uint32_t>> heap_;  // gain, candidate
  std::vector<double> cap_;                           // radius cap per centre point (repair)
  std::vector<double> point_error_, surface_error_;
  std::vector<double> shrink_;                        // per chosen patch: radius factor on repair
  std::vector<double> patch_excess_;                 // per candidate: zero_set_excess, −1 unknown
  std::vector<std::vector<double>> patch_errors_;    // per candidate: its last surface samples' distances
  std::vector<double> patch_reach_;                  // per candidate: how far its probes' blends looked
  std::vector<double> point_reach_;                  // per point: how far its probe's blend looked
  std::vector<std::uint8_t> other_direction_;         // per point: measured along its neighbourhood's normal
  std::vector<double> probe_height_;                  // per point (fit/evaluate.h probe_heights)
  std::vector<std::uint32_t> face_of_;                // per point: its face (face samples), until setup
  std::unique_ptr<FaceSet> faces_;                    // face patches
  bool can_add_points_ = false;                       // owned_ holds the points
  std::size_t face_triangles_ = 0;                    // fan triangles of the faces with a surface (face_holes' pieces / 4^depth)
  std::vector<std::uint8_t> face_covered_;            // per face: inside the union of the balls at the last check
  std::vector<std::uint8_t> view_clear_;              // per face: every view ray met a patch at the last check
  std::vector<std::uint8_t> hole_tried_;              // per face: a spot on it joined the points (add_points)
  std::vector<std::uint8_t> view_tried_;              // per face: seen through before (view_balls)
  std::vector<std::uint8_t> face_patched_;            // per face: holds a face patch of add_face_patches
};

}  // namespace

SlimFitResult fit_slim(const PointCloud& cloud, const SlimFitOptions& options) {
  return SlimFitter(cloud, options, nullptr).run();
}

SlimFitResult fit_slim(const PointCloud& cloud, const PolygonMesh& surface, const SlimFitOptions& options) {
  if (!options.cover_faces || !cloud.has_normals()) return SlimFitter(cloud, options, &surface).run();
  // Each face's centroid (and a lattice on faces much larger than their neighbours, core/io/io.h
  // face_samples) joins the points with the face's normal, so coverage and the points side hold
  // between the vertices too.
  PointCloud all = cloud;
  std::vector<std::uint32_t> face_of(cloud.points.size(), FaceSet::kNone);
  // The lattice on large faces only when E is finer than the mesh's spacing: coarser balls span
  // many faces, held by their vertices and centroids (bunny at 1e-2, where E is 1.7 median
  // edges: a lattice point on a filled scan hole stayed 14E off through every repair round).
  Box3 box;
  for (const auto& p : cloud.points) box.extend(p);
  const double E = options.max_error_is_absolute ? options.max_error : options.max_error * box.diagonal();
  const PointCloud faces = face_samples(surface, 2.0, &face_of, E);
  all.points.insert(all.points.end(), faces.points.begin(), faces.points.end());
  all.normals.insert(all.normals.end(), faces.normals.begin(), faces.normals.end());
  const std::size_t added = all.points.size() - cloud.points.size();
  SlimFitResult r = SlimFitter(std::move(all), options, &surface, std::move(face_of)).run();
  r.model.metadata["face_samples"] = std::to_string(added);
  return r;
}

}  // namespace quadrix
