#include "fit/ball_fitter.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <span>

#include <Eigen/Eigenvalues>

#include "fit/local_fit.h"

namespace quadrix::fit_detail {
namespace {

// Weight of a point in the local least squares, r = ‖p − c‖/R: the SLIM blend weight's shape
// (DESIGN §2) plus a floor so rim points, which are checked too, still pull on the fit.
double fit_weight(double r, double floor) {
  if (r < 0.5) return std::exp(-8.0 * r * r) + floor;
  const double s = 1.0 - std::min(r, 1.0);
  return 16.0 * std::exp(-2.0) * (s * s) * (s * s) + floor;
}

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

}  // namespace

Subsamples::Subsamples(const std::vector<Eigen::Vector3d>& P, std::size_t min_points, std::uint64_t seed) {
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

FaceSet::FaceSet(const PolygonMesh& m, std::vector<std::uint32_t> of, const std::vector<Eigen::Vector3d>& P, bool prisms)
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

double FaceSet::distance(std::uint32_t f, const Eigen::Vector3d& x) const {
  const auto vs = mesh->face(f);
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k + 1 < vs.size(); ++k)
    d = std::min(d, point_triangle_distance(x, mesh->vertices[vs[0]], mesh->vertices[vs[k]], mesh->vertices[vs[k + 1]]));
  return d;
}

// The face point ci lies on (its own, for a face sample; else among the faces of its nearest
// face samples), as a face patch: the face's plane around its centroid.
std::optional<Ball> BallFitter::face_ball(std::uint32_t ci, Scratch& s) const {
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
std::optional<Ball> BallFitter::face_patch(std::uint32_t f) const {
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
  const auto& sides = faces->sides[f];
  std::vector<double> m;
  for (const FaceSet::Side& sd : sides) m.push_back(sd.open ? 1e-3 * E : opt.face_patch_margin * E);
  // A triangle's whole prism (sides in edge order, consecutive ones meeting at a corner v): the
  // cross-section's corner p beyond v has a·(p − v) = −m_a and b·(p − v) = −m_b for the two
  // walls' inward normals a, b, so |p − v| = m / sin(θ/2) for a corner angle θ and equal
  // margins: far past a sharp corner (happy_buddha_10k at 1e-3: face patches on needle
  // triangles reached 8E past them, and the fit ended with 11 surface samples beyond 2E). At a
  // corner beyond local_surface_factor·E the two margins shrink until p is that close, down to a
  // floor of a fifth of the margin; a needle still beyond then gets a fourth plane across its
  // bisector (a fourth plane is four more columns for every patch of the file, so only there).
  // The cross-section then lies within local_surface_factor·E of the triangle.
  const bool triangle = sides.size() == 3 && faces->mesh->face(f).size() == 3;
  // Where two lines meet that lie ma and mb outside v along unit normals a and b (a·(q − v) = −ma,
  // b·(q − v) = −mb): |q − v|, infinite for parallel lines.
  const auto meet = [](const Eigen::Vector3d& a, double ma, const Eigen::Vector3d& b, double mb) {
    const double k = a.dot(b), det = 1.0 - k * k;
    if (!(det > 1e-12)) return std::numeric_limits<double>::infinity();
    const double x = (-ma + k * mb) / det, y = (-mb + k * ma) / det;
    return std::sqrt(std::max(0.0, x * x + y * y + 2.0 * x * y * k));
  };
  const auto corner = [&](std::size_t i) { return meet(sides[i].inward, m[i], sides[(i + 1) % 3].inward, m[(i + 1) % 3]); };
  // Past a corner, the plane runs at most local_surface_factor·E from the data, as any patch's
  // zero set may (surface_ok).
  const double most = opt.local_surface_factor * E;
  const double least = 0.2 * opt.face_patch_margin * E;  // a margin's floor: still an overlap
  std::optional<ClipPlane> cut;  // the fourth plane, across the sharpest corner
  if (triangle) {
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t i = 0; i < 3; ++i)
        if (const double p = corner(i); p > most && std::isfinite(p)) {
          m[i] = std::max(least, m[i] * most / p);
          m[(i + 1) % 3] = std::max(least, m[(i + 1) % 3] * most / p);
        }
    std::size_t tip = 3;  // the corner cut (none: 3)
    double tip_reach = 0;
    std::size_t worst = 0;
    for (std::size_t i = 1; i < 3; ++i)
      if (corner(i) > corner(worst)) worst = i;
    const FaceSet::Side &sa = sides[worst], &sb = sides[(worst + 1) % 3];
    const Eigen::Vector3d bis = sa.inward + sb.inward;
    // A needle the floor keeps beyond: the fourth plane, where the two shrunk walls are
    // 2·least apart.
    if (const double p = corner(worst); p > most * (1 + 1e-9) && std::isfinite(p) && bis.norm() > 1e-9) {
      const Eigen::Vector3d n = bis.normalized();
      const int v = faces->mesh->face(f)[(worst + 1) % 3];
      const Eigen::Vector3d vl = (faces->mesh->vertices[v] - P[c]) / R;
      const double at = most - 2.0 * least;
      cut = ClipPlane{n, -n.dot(vl) + at / R};
      tip = worst;
    }
    // A sliver with a second corner the floor keeps beyond (two sharp corners; the fourth plane
    // cuts one): that corner's two walls go down to a hair outside their edges, as at an open
    // edge (happy_buddha_10k at 1e-4: such face patches ran 1.5–3.2E from the data, were
    // dropped by the repair and made again, round after round, until the fit ended outside its
    // bound).
    for (std::size_t i = 0; i < 3; ++i)
      if (const double p = corner(i); i != tip && p > most * (1 + 1e-9) && std::isfinite(p)) {
        m[i] = std::max(1e-3 * E, m[i] * most / p);
        m[(i + 1) % 3] = std::max(1e-3 * E, m[(i + 1) % 3] * most / p);
      }
    if (cut) {
      // Where the cut meets the two walls.
      const Eigen::Vector3d n = cut->n;
      const double at = most - 2.0 * least;
      for (const double q : {meet(sa.inward, m[worst], n, at), meet(sb.inward, m[(worst + 1) % 3], n, at)})
        if (std::isfinite(q)) tip_reach = std::max(tip_reach, q);
    }
    double reach = tip_reach;
    for (std::size_t i = 0; i < 3; ++i)
      if (i != tip) reach = std::max(reach, corner(i));
    b.on_data = reach <= opt.local_surface_factor * E;
  }
  for (std::size_t i = 0; i < sides.size(); ++i) b.clips.add(ClipPlane{sides[i].inward, (sides[i].offset + m[i]) / R});
  if (cut) b.clips.add(*cut);
  if (!b.clips.empty()) b.sheet = N[c], b.other = -N[c];
  b.face = f;
  b.settled = true;
  return b;
}

// The local form of the surface side: the patch's zero set inside its ball stays within
// local_surface_factor·E of the data (no fins, no second sheets, no extrapolation past an
// open boundary).
std::pair<int, int> BallFitter::surface_lattice(double R) const {
  if (verify_lattice) {
    const int grid = std::clamp(static_cast<int>(std::ceil(2.0 * R / (opt.verify_spacing * E))), opt.verify_surface_grid,
                                opt.verify_max_grid);
    if (grid > opt.local_surface_grid << opt.local_surface_depth) return {grid, 1};
  }
  return {opt.local_surface_grid, opt.local_surface_depth};
}

bool BallFitter::surface_ok(const Ball& b) const {
  const auto [grid, depth] = surface_lattice(b.R);
  return zero_set_excess(SlimPatch{P[b.centre], b.R, b.g, b.clips, std::nullopt, std::nullopt}, *data,
                         opt.local_surface_factor * E, grid, depth) == 0.0;
}

// A ball at (ci, R) whose points are within E and whose zero set passes surface_ok: the
// plain fit, else its centre's sheet alone, clipped (two sheets in one ball: a thin part, a
// gap, a crease).
std::optional<Ball> BallFitter::try_both_sides(std::uint32_t ci, double R, Scratch& s) const {
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
// boundary points in the ball (DataSurface::boundary_near) when they bend measurably (a
// curved boundary: a straight cut across the sheet would leave slivers past it), else across
// the sheet, facing the boundary points' inward tangent or the points' tangential centroid.
// Points beside a sharp crease count as such boundary points here (DataSurface::boundary_near's
// crease_sides), though their discs reach the crease: the patch of the face stops there, and
// another patch or the crease's clipped ones cover the rest.
std::optional<Ball> BallFitter::try_boundary(const Ball& b, const Scratch& s) const {
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
  data->boundary_near(c0, b.R, edge, /*crease_sides=*/true);
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
Ball BallFitter::settle(Ball b, Scratch& s) const {
  b.settled = true;
  if (b.face >= 0 || !b.is_bounded) return b;
  // Passed surface_ok: its zero set was checked on a lattice of at least this many lines per
  // side (finer where a sample could not vouch for its cell).
  const auto passed = [&](Ball c) {
    c.settled = true;
    const auto [grid, depth] = surface_lattice(c.R);
    c.surface_lattice = depth == 1 && grid > opt.local_surface_grid << opt.local_surface_depth ? grid : opt.local_surface_grid << opt.local_surface_depth;
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
std::size_t BallFitter::ball_points(const Eigen::Vector3d& c, double R, Scratch& s) const {
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
std::optional<Ball> BallFitter::try_ball(std::uint32_t ci, double R, Scratch& s, bool accept_any) const {
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
  if ((opt.sharp || (sharp_at && (*sharp_at)[ci])) && !accept_any)
    if (auto b = try_sharp(ci, R, s, !opt.sharp)) return b;
  if (best && !best->is_bounded && !accept_any) return std::nullopt;
  return best;
}

// The centre's sheet only, clipped by the plane where the two sheets' tangent planes are
// equally far (dA(u) = dB(u): it separates the sheets at convex and concave creases alike).
// Uses the check subset s.u, s.n that try_ball left behind.
std::optional<Ball> BallFitter::try_sharp(std::uint32_t ci, double R, Scratch& s, bool planar) const {
  const double sharp_cos = std::cos(opt.sharp_angle_deg * std::numbers::pi / 180.0);
  const auto split = split_normals(s.n, N[ci], sharp_cos, opt.min_points / 2);
  if (!split) return std::nullopt;
  const auto& [na, nb0] = *split;
  // A corner of three faces: the other cluster splits in two again (a box's corner gave the
  // centre's sheet one plane between it and the other two faces' mean, and no ball near the
  // corner fitted, so the smallest balls left holes there that the fit's checks did not see:
  // 4.2e-4 of the true box's pixels at 1e-3, 49 of 77 hole pixels within 15E of a corner). Each
  // other sheet then gets its own plane.
  Eigen::Vector3d nb = nb0, nc = Eigen::Vector3d::Zero();
  {
    std::vector<Eigen::Vector3d> rest;
    for (const auto& x : s.n)
      if (x.dot(na) < x.dot(nb0)) rest.push_back(x);
    if (const auto again = split_normals(rest, nb0, sharp_cos, opt.min_points / 2)) nb = again->first, nc = again->second;
  }
  // Which sheet a normal belongs to: 0 (the centre's), 1 or 2.
  const auto sheet_of = [&](const Eigen::Vector3d& x) {
    const double a = x.dot(na), b = x.dot(nb), c = nc.isZero() ? -2.0 : x.dot(nc);
    return a >= b && a >= c ? 0 : b >= c ? 1 : 2;
  };
  std::array<Eigen::Vector3d, 3> centroid{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::array<std::size_t, 3> members{};
  for (std::size_t j = 0; j < s.u.size(); ++j) {
    const int k = sheet_of(s.n[j]);
    centroid[std::size_t(k)] += s.u[j], ++members[std::size_t(k)];
  }
  // A split whose one half holds none of the ball's points: the other cluster whole again.
  if (members[1] == 0 || members[2] == 0) {
    centroid[1] += centroid[2], members[1] += members[2];
    centroid[2].setZero(), members[2] = 0;
    nb = nb0, nc.setZero();
  }
  if (members[0] == 0 || members[1] == 0) return std::nullopt;
  for (std::size_t k = 0; k < 3; ++k)
    if (members[k] > 0) centroid[k] /= double(members[k]);
  const Eigen::Vector3d& pa = centroid[0];
  // (Beside a curved face, a plane through its points' centroid along their mean normal stands
  // off it, and so does the cut: fandisk sampled without normals drew 2× the pixels beyond 2E.)
  // Up to 2 % of each sheet's points (at least one) may lie farther than E off its plane (rounded
  // normals beside an edge that put a point in the other sheet: with none allowed, a 30° wedge's
  // balls failed and fitted 2.5× the patches, 3-5× the holes).
  constexpr double kPlanarStrays = 0.02;
  if (planar) {
    const std::array<Eigen::Vector3d, 3> normal{na, nb, nc};
    std::array<std::size_t, 3> off{};
    for (std::size_t j = 0; j < s.u.size(); ++j) {
      const auto k = std::size_t(sheet_of(s.n[j]));
      off[k] += std::abs(normal[k].dot(s.u[j] - centroid[k])) > E / R;
    }
    for (std::size_t k = 0; k < 3; ++k)
      if (double(off[k]) > std::max(1.0, kPlanarStrays * double(members[k]))) return std::nullopt;
  }
  // The plane keeps dA(u) ≥ dB(u) (signed distances to the two tangent planes): sheet A's side
  // at a convex crease, where the surface is max(dA, dB) = 0. At a concave one (sheet B's points
  // above A's plane) the surface is min(dA, dB) = 0 and A's side is dA ≤ dB: the plane turned.
  // (Unturned, a valley's centre was never its own patch's: a V-groove of 20,000 points at 1e-3
  // fitted 132 patches with --sharp as without, where the same ridge drops from 141 to 75.)
  const auto between = [&](const Eigen::Vector3d& nx, const Eigen::Vector3d& px) {
    ClipPlane clip;
    clip.n = na - nx;
    clip.d = -(na.dot(pa) - nx.dot(px));
    if (na.dot(px - pa) > 0) clip.n = -clip.n, clip.d = -clip.d;
    const double len = clip.n.norm();
    clip.n /= len, clip.d /= len;
    return clip;
  };
  ClipPlanes clips = ClipPlanes::of(between(nb, centroid[1]));
  if (!nc.isZero()) clips.add(between(nc, centroid[2]));
  Ball probe_ball;
  probe_ball.clips = clips, probe_ball.sheet = na, probe_ball.other = nb, probe_ball.other2 = nc;
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
    Ball b{ci, R, *g, is_height, true, e.max_taubin * R, e.sum_sq_taubin * R * R, u.size(), clips, na, nb};
    b.other2 = nc;
    return b;
  }
  return std::nullopt;
}

// The largest R whose fit stays within E: growth from the min_points-th neighbour distance,
// then bisection in log R.
// With a guess (the radius of a nearby candidate): from there, growth or shrinking by
// warm_growth, then bisection; the search from scratch below when no radius down to
// guess/warm_growth¹² fits.
Ball BallFitter::grow(std::uint32_t ci, Scratch& s, double limit, double guess) const {
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
      // Points within E/1000 count as the centre itself (happy_buddha_10k: a vertex one ulp
      // from another made a ball of radius 8.7e-19, which float32 cannot place, so the model fell
      // back to the double encoding).
      index.nearest(P[ci], 2 * opt.min_points, s.nb);
      for (const auto& [j, d2] : s.nb)
        if (d2 > 1e-6 * E * E) return Ball{ci, std::min(0.5 * std::sqrt(d2), limit), Quadric::plane(N[ci], 0.0), true, false, 0, 0, 1, ClipPlanes{}};
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

}  // namespace quadrix::fit_detail
