// SLIM fits of clouds built to break them (thin parts, boundaries, creases, uneven density, noise,
// no normals, sparse data): each asserts both sides of the contract (DESIGN §2) with measures
// independent of the fitter: every point within E of the blended surface (fit/evaluate.h), and
// the surface seen from 8 views within 2E of the true surface, without holes (fit/surface_error.h
// against a fine triangulation of the analytic surface).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <tuple>

#include "fit/data_surface.h"
#include "fit/evaluate.h"
#include "fit/normals.h"
#include "fit/slim_fit.h"
#include "fit/surface_error.h"
#include "core/camera.h"
#include "core/io/io.h"
#include "core/reference.h"
#include "core/slim.h"
#include "core/log.h"
#include <map>

namespace quadrix {
namespace {

using Vec = Eigen::Vector3d;
using Param = std::function<Vec(double, double)>;

// A parametric patch over [0,1]²: its triangulation (the truth) and area-uniform samples with
// normals (by rejection on the area element), normals flipped by `sign`.
struct Sheet {
  Param f;
  double sign = 1;
  int grid = 200;
};

Vec normal_of(const Param& f, double u, double v) {
  const double h = 1e-6;
  const Vec du = (f(std::min(u + h, 1.0), v) - f(std::max(u - h, 0.0), v));
  const Vec dv = (f(u, std::min(v + h, 1.0)) - f(u, std::max(v - h, 0.0)));
  return du.cross(dv).normalized();
}

struct Shape {
  PolygonMesh mesh;
  PointCloud cloud;
  Box3 box;
};

Shape make(const std::vector<Sheet>& sheets, std::size_t n, std::uint64_t seed,
           const std::function<double(const Vec&)>& density = nullptr) {
  Shape s;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<double> areas;
  for (const auto& sh : sheets) {
    const int g = sh.grid;
    const int base = static_cast<int>(s.mesh.vertices.size());
    for (int j = 0; j <= g; ++j)
      for (int i = 0; i <= g; ++i) s.mesh.vertices.push_back(sh.f(double(i) / g, double(j) / g));
    double area = 0;
    for (int j = 0; j < g; ++j)
      for (int i = 0; i < g; ++i) {
        const int a = base + j * (g + 1) + i, b = a + 1, c = a + g + 1, d = c + 1;
        // Winding so the triangle normal follows sign·(∂u × ∂v).
        if (sh.sign > 0) s.mesh.add_face(std::vector<int>{a, b, d}), s.mesh.add_face(std::vector<int>{a, d, c});
        else s.mesh.add_face(std::vector<int>{a, d, b}), s.mesh.add_face(std::vector<int>{a, c, d});
        const Vec &pa = s.mesh.vertices[a], &pb = s.mesh.vertices[b], &pc = s.mesh.vertices[c], &pd = s.mesh.vertices[d];
        area += 0.5 * ((pb - pa).cross(pd - pa).norm() + (pd - pa).cross(pc - pa).norm());
      }
    areas.push_back(area);
  }
  for (const auto& v : s.mesh.vertices) s.box.extend(v);
  std::discrete_distribution<std::size_t> pick(areas.begin(), areas.end());
  while (s.cloud.points.size() < n) {
    const auto& sh = sheets[pick(rng)];
    const double u = U(rng), v = U(rng);
    const double h = 1e-5;
    const Vec du = sh.f(std::min(u + h, 1.0), v) - sh.f(std::max(u - h, 0.0), v);
    const Vec dv = sh.f(u, std::min(v + h, 1.0)) - sh.f(u, std::max(v - h, 0.0));
    const double jac = du.cross(dv).norm() / (4 * h * h);
    (void)jac;  // the parametrisations below are near-uniform; density() skews on purpose
    const Vec p = sh.f(u, v);
    if (density && U(rng) > density(p)) continue;
    s.cloud.points.push_back(p);
    s.cloud.normals.push_back(sh.sign * normal_of(sh.f, u, v));
  }
  return s;
}

Sheet quad(const Vec& o, const Vec& a, const Vec& b, double sign = 1, int grid = 60) {
  return {[=](double u, double v) { return Vec(o + u * a + v * b); }, sign, grid};
}

// The six faces of an axis-aligned box, outward.
std::vector<Sheet> box(const Vec& lo, const Vec& hi) {
  const Vec d = hi - lo;
  const Vec x(d.x(), 0, 0), y(0, d.y(), 0), z(0, 0, d.z());
  return {quad(lo, y, x), quad(lo + z, x, y), quad(lo, x, z), quad(lo + y, z, x), quad(lo, z, y), quad(lo + x, y, z)};
}

struct Outcome {
  SlimFitResult fit;
  SlimError points;
  SurfaceError surface;
  double E = 0;
};

// With faces (the default) the fit is bounded against the mesh and measured against it; points
// only: bounded and measured against the points' local surface (their tangent discs).
Outcome fit_and_measure(const Shape& s, double rel, const SlimFitOptions& extra = {}, bool drop_normals = false,
                        bool with_faces = true) {
  Outcome o;
  SlimFitOptions opt = extra;
  opt.max_error = rel;
  PointCloud input = s.cloud;
  if (drop_normals) input.normals.clear();
  o.fit = with_faces ? fit_slim(input, s.mesh, opt) : fit_slim(input, opt);
  o.E = o.fit.stats.max_error_abs;
  // Points measured along the normals the fit used (estimated the same way when dropped), from
  // the same probe heights (with faces: at most halfway to the next sheet, as in the fitter).
  const DataSurface truth = with_faces ? DataSurface::from_mesh(s.mesh) : DataSurface::from_points(s.cloud.points, s.cloud.normals);
  // With faces the fitter bounds the face centroids too (fit_slim's cover_faces), and a point's
  // neighbourhood (measure_point) includes them: measure the same set.
  PointCloud measured = input;
  if (with_faces && input.has_normals()) {
    const PointCloud faces = face_samples(s.mesh.fanned());  // the fitter's faces: triangles
    measured.points.insert(measured.points.end(), faces.points.begin(), faces.points.end());
    measured.normals.insert(measured.normals.end(), faces.normals.begin(), faces.normals.end());
  }
  o.points = evaluate_slim(o.fit.model, measured, {.keep_per_point = true, .surface = with_faces ? &truth : nullptr});
  o.surface = measure_surface_error(o.fit.model, truth, s.box, {.views = 8, .resolution = 160, .bound = 2 * o.E});
  std::cerr << "  patches " << o.fit.stats.patches << ", points max/E " << o.points.max / o.E << " (" << o.points.misses
            << " misses), surface p99.9/E " << o.surface.p999 / o.E << " max/E " << o.surface.max / o.E << " beyond 2E "
            << o.surface.share_beyond << ", holes " << o.surface.holes << "/" << o.surface.data_pixels << ", "
            << o.fit.stats.time_total << " s, " << o.fit.stats.hole_points << " hole points, " << o.fit.stats.hole_face_patches << " hole face patches, " << o.fit.stats.face_holes << " face holes left, " << o.fit.stats.repair_rounds << " repair rounds; fitter: points max/E " << o.fit.stats.max_blend / o.E << " (" << o.fit.stats.blend_failures << " beyond), surface max/E " << o.fit.stats.surface_max / o.E << " (" << o.fit.stats.surface_failures << " beyond 2E)\n";
  if (!o.points.per_point.empty() && !measured.points.empty()) {
    const auto w = o.points.worst;
    std::cerr << "  worst point " << w << " at " << measured.points[w].transpose() << " normal "
              << (measured.has_normals() ? Vec(measured.normals[w]) : Vec::Zero()).transpose() << "\n";
  }
  return o;
}

void expect_two_sided(const Outcome& o, double points_factor = 1.0) {
  EXPECT_EQ(o.points.misses, 0u);
  EXPECT_LE(o.points.max, points_factor * o.E * (1 + 1e-9)) << o.points.count_above(o.E) << " points beyond E";
  EXPECT_GT(o.surface.pixels, 1000u);
  EXPECT_LE(o.fit.stats.surface_max, 2 * o.E);
  EXPECT_LE(o.surface.p999, 2 * o.E) << "surface p99.9 / E = " << o.surface.p999 / o.E;
  EXPECT_LE(o.surface.share_beyond, 1e-3) << o.surface.beyond << " of " << o.surface.pixels << " pixels beyond 2E";
  EXPECT_LE(o.surface.hole_share, 1e-3) << o.surface.holes << " holes in " << o.surface.data_pixels << " pixels";
  EXPECT_EQ(o.fit.stats.blend_failures, 0u);
  EXPECT_EQ(o.fit.stats.surface_failures, 0u);
}

constexpr double kE = 1e-3;  // relative to the diagonal

TEST(FitSlimHard, TwoParallelSheetsAFewEApart) {
  // An open gap between two sheets facing each other, 5E apart.
  const double gap = 5 * kE * std::sqrt(3.0);
  const Shape s = make({quad({0, 0, 0}, {1, 0, 0}, {0, 1, 0}), quad({0, 0, gap}, {1, 0, 0}, {0, 1, 0}, -1)}, 20000, 1);
  expect_two_sided(fit_and_measure(s, kE));
}

TEST(FitSlimHard, ThinPlate) {
  // 12E thick, sampled finer than its thickness.
  const Shape s = make(box({0, 0, 0}, {0.3, 0.3, 0.005}), 30000, 2);
  expect_two_sided(fit_and_measure(s, kE));
}

TEST(FitSlimHard, ThinCylinderFinger) {
  // A finger of radius 4E on a plate.
  const double r = 0.006, L = 0.5;
  std::vector<Sheet> sheets = box({-0.3, -0.3, -0.05}, {0.3, 0.3, 0.0});
  sheets.push_back({[=](double u, double v) {
                      const double a = 2 * std::numbers::pi * u;
                      return Vec(r * std::cos(a), r * std::sin(a), v * L);
                    },
                    1, 200});
  sheets.push_back({[=](double u, double v) {
                      const double a = 2 * std::numbers::pi * u;
                      return Vec(v * r * std::cos(a), v * r * std::sin(a), L);
                    },
                    1, 40});
  const Shape s = make(sheets, 30000, 3);
  expect_two_sided(fit_and_measure(s, kE));
}

// A wire fitted at an E of its radius comes out as a cylinder a few hundredths of its ball
// across: every lattice line of the lone-patch check passed between its sides, so a tube
// running 2 units (100 bounds) past the wire's ends was never seen (a new user's wire of radius
// 0.01 and length 10, exit 0 with "0 surface samples"). Lines along the quadric's principal axes
// through its centre meet it: unclipped it runs past the data, clipped at the wire's ends it
// does not.
TEST(FitSlimHard, AWireThinnerThanTheLatticeIsChecked) {
  const double r = 0.01, half = 1.0, R = 3.0;
  std::vector<Eigen::Vector3d> P, N;
  for (int i = 0; i < 400; ++i)
    for (int j = 0; j < 16; ++j) {
      const double a = 2 * std::numbers::pi * (j + 0.5 * (i % 2)) / 16, z = -half + 2 * half * (i + 0.5) / 400;
      P.emplace_back(r * std::cos(a), r * std::sin(a), z);
      N.emplace_back(std::cos(a), std::sin(a), 0.0);
    }
  const DataSurface data = DataSurface::from_points(P, N);
  SlimPatch wire;
  wire.radius = R;
  wire.local.A.diagonal() = Eigen::Vector3d(1, 1, 0);
  wire.local.c = -(r / R) * (r / R);
  const double bound = 0.015;
  EXPECT_GT(zero_set_excess(wire, data, bound, 6, 2), bound) << "the tube past the wire's ends went unseen";
  SlimPatch clipped = wire;
  clipped.clips = ClipPlanes::of(ClipPlane{Eigen::Vector3d(0, 0, -1), half / R});
  clipped.clips.add(ClipPlane{Eigen::Vector3d(0, 0, 1), half / R});
  EXPECT_EQ(zero_set_excess(clipped, data, bound, 6, 2), 0.0);
  // The verification's samples (core/slim.h sample_slim_patch) meet the tube too: it had none.
  for (const SlimPatch* p : {&wire, &clipped}) {
    std::vector<SlimSurfaceSample> zero;
    sample_slim_patch(*p, 6, zero);
    EXPECT_GT(zero.size(), 100u);
    double off_axis = 0, far_end = 0;
    for (const auto& z : zero)
      off_axis = std::max(off_axis, std::abs(z.point.head<2>().norm() - r)), far_end = std::max(far_end, std::abs(z.point.z()));
    EXPECT_LT(off_axis, 1e-9);
    if (p == &clipped) EXPECT_LE(far_end, half * (1 + 1e-9));
    else EXPECT_GT(far_end, 2.0);
  }
}

// A newcomer's capsule (radius 0.05, 3 long, 10,000 points without normals) fitted at 1e-2 with
// 3 patches came out with a nub 2.9E above its end, exit 0, the check saying 0.7E: the body's
// ball, 50E across, held a prolate ellipsoid whose tip lay just past the ball's sphere. The piece
// of it left inside, the nub, met the sphere in a loop 0.7E across, which the rim sampling's
// steps along its meridians (3.3E there) stepped over. The rim is now also sought beside where
// the quadric's principal axes leave the ball (core/slim.h sample_slim_rim_at_axes), and verification
// sees it through the blend: the newcomer's cloud now draws 1.18E at most, none beyond 2E (a
// capsule sampled here with another seed showed no nub either way, so only the sampling is
// tested).
TEST(FitSlimHard, AnEllipsoidsTipJustPastItsBallIsSeen) {
  const double r = 0.05, half = 1.5;
  std::vector<Eigen::Vector3d> P, N;
  for (int i = 0; i < 300; ++i)  // the body
    for (int j = 0; j < 24; ++j) {
      const double a = 2 * std::numbers::pi * (j + 0.5 * (i % 2)) / 24, z = -half + 2 * half * (i + 0.5) / 300;
      P.emplace_back(r * std::cos(a), r * std::sin(a), z);
      N.emplace_back(std::cos(a), std::sin(a), 0.0);
    }
  for (int i = 0; i < 12; ++i)  // the two caps
    for (int j = 0; j < 24; ++j) {
      const double t = 0.5 * std::numbers::pi * (i + 0.5) / 12, a = 2 * std::numbers::pi * j / 24;
      const Eigen::Vector3d n(std::sin(t) * std::cos(a), std::sin(t) * std::sin(a), std::cos(t));
      P.push_back(Eigen::Vector3d(0, 0, half) + r * n), N.push_back(n);
      P.push_back(Eigen::Vector3d(0, 0, -half) + r * Eigen::Vector3d(n.x(), n.y(), -n.z())), N.emplace_back(n.x(), n.y(), -n.z());
    }
  const DataSurface data = DataSurface::from_points(P, N);
  // x²/r² + y²/r² + z²/c² = 1, its tip at z = c = 1.66, 0.11 past the capsule's end; the ball's
  // sphere reaches z = 1.643.
  const double c = 1.66, R = 1.551, E = 0.031;
  const Eigen::Vector3d centre(0.049, 0.0, 0.092);
  SlimPatch body;
  body.centre = centre;
  body.radius = R;
  // In the ball's units u = (x − centre)/R: (R u + centre)ᵀ D (R u + centre) − 1.
  const Eigen::Matrix3d D = Eigen::Vector3d(1 / (r * r), 1 / (r * r), 1 / (c * c)).asDiagonal();
  body.local.A = R * R * D;
  body.local.b = R * D * centre;
  body.local.c = centre.dot(D * centre) - 1.0;
  std::vector<SlimSurfaceSample> rim;
  sample_slim_rim(body, 0.5 * E, rim);  // as verification samples it
  sample_slim_rim_at_axes(body, rim);
  double top = -1, farthest = 0;
  for (const auto& z : rim)
    if (z.point.z() > half) top = std::max(top, z.point.z()), farthest = std::max(farthest, data.distance(z.point));
  std::cerr << "  rim past the capsule's end up to z = " << top << ", " << farthest / E << "E off the data\n";
  EXPECT_GT(top, 1.6) << "the nub's rim went unseen";
  EXPECT_GT(farthest, 2 * E);
}

// Both used to fail (surface p99.9 14E and 3.6E): a clip plane cut slightly askew across an open
// boundary leaves a wedge of surface past it, thinner than the verification lattice; the curve
// where the zero set meets its clip plane is now sampled densely (fit/data_surface.h
// zero_set_excess). In the roof the culprit was the open lower edge, not the crease.
TEST(FitSlimHard, OpenCapWithABoundary) {
  // A spherical cap (open, boundary circle): the surface must stop near the boundary.
  const Shape s = make({{[](double u, double v) {
                           const double th = 0.9 * u, ph = 2 * std::numbers::pi * v;
                           return Vec(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
                         },
                         -1, 120}},
                       15000, 4);
  expect_two_sided(fit_and_measure(s, kE));
}

TEST(FitSlimHard, SharpCrease) {
  // A roof: two planes at 90°, open.
  const Shape s = make({quad({0, 0, 0}, {0, 1, 0}, {0.5, 0, 0.5}), quad({0.5, 0, 0.5}, {0, 1, 0}, {0.5, 0, -0.5})}, 20000, 5);
  expect_two_sided(fit_and_measure(s, kE));
}

// The same roof with its normals up (a ridge: a convex crease) and down (seen from below, a
// valley: a concave one), points only, --sharp. try_sharp's plane kept dA ≥ dB, sheet A's side
// at a convex crease only; at a concave one the centre was never its own patch's, so the valley
// fitted as without --sharp: here 146 patches against the ridge's 66 (now 66 and 66); a V of
// 20,000 points at 1e-3 through the CLI, 132 against 75 (now 60 and 75). (SharpCrease's roof,
// above, has its normals down: a valley.)
TEST(FitSlimHard, ConcaveCreaseGetsSharpPatchesAsAConvexOneDoes) {
  const auto roof = [](double sign) {
    return make({quad({0, 0, 0}, {0, 1, 0}, {0.5, 0, 0.5}, sign), quad({0.5, 0, 0.5}, {0, 1, 0}, {0.5, 0, -0.5}, sign)}, 20000, 5);
  };
  SlimFitOptions o;
  o.sharp = true;
  const Outcome up = fit_and_measure(roof(-1), kE, o, false, false), down = fit_and_measure(roof(1), kE, o, false, false);
  expect_two_sided(up);
  expect_two_sided(down);
  const double more = double(std::max(up.fit.stats.patches, down.fit.stats.patches)),
               fewer = double(std::min(up.fit.stats.patches, down.fit.stats.patches));
  EXPECT_LE(more, 1.3 * fewer) << up.fit.stats.patches << " patches with the normals up, " << down.fit.stats.patches << " down";
}

// A sphere sampled 10× more densely on one side.
Shape uneven_sphere() {
  return make({{[](double u, double v) {
                  const double th = std::acos(1 - 2 * u), ph = 2 * std::numbers::pi * v;
                  return Vec(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
                },
                1, 150}},
              15000, 6, [](const Vec& p) { return p.x() > 0 ? 1.0 : 0.1; });
}

TEST(FitSlimHard, UnevenDensity) {
  const Shape s = uneven_sphere();
  expect_two_sided(fit_and_measure(s, kE));
}

// The same sphere as points alone: the points' local surface (their tangent discs) must have no
// hole and no boundary at the density step (DataSurface::from_points). Each sparse point nearest
// the step, taken for a boundary with a disc the dense side's size, left gaps that the fit read as
// the surface running off the data: 84 patches in 8 s (a sphere evenly sampled as sparsely as
// the sparse side needs 22, its discs sagging off the sphere).
// Holes between the sparse points: the repair round left two holes about 20E across in the sparse
// half, between points whose coverage discs were all held, and a few points' discs not held;
// below the fill band they were only counted (50 of 33,775 pixels seen through at 160², 1.5e-3).
// Now the holes a view along the points' normals sees are filled (see_point_holes): 3 pixels,
// for 37 patches instead of 24. Since fit_slim fits the points in Morton order (and sorts its
// parallel loops' spots), this draw leaves 6 pixels for 36 patches (the unfilled fit 54). Not
// all are filled: fitted through the CLI with seeds 1–6, 6, 6, 4, 3, 0 and 8 pixels stay (in
// file order, before: 4, 9, 0, 10, 9, 0), mostly a slit between two large clipped patches whose
// planes both cut away a spot on the smooth sphere, seen head-on, that no ring of spots around
// the points lands in; seed 5 fits the sphere with 4 patches and no hole.
TEST(FitSlimHard, UnevenDensityPointsOnly) {
  const Shape s = uneven_sphere();
  const Outcome o = fit_and_measure(s, kE, {}, false, false);
  expect_two_sided(o);
  EXPECT_LE(o.fit.stats.patches, 45u);
  EXPECT_EQ(o.fit.stats.seen_point_holes, 0u);
  // The holes were between points on flat tangent discs, which sag off the sphere between its
  // sparse points: with flat discs and no view check they stay.
  SlimFitOptions flat;
  flat.see_point_holes = false;
  flat.bent_discs = false;
  const Outcome unseen = fit_and_measure(s, kE, flat, false, false);
  EXPECT_GT(unseen.surface.holes, 3 * o.surface.holes + 10) << "the case no longer leaves holes between its points";
  // Bent discs (the data's surface following the sphere between the points) leave none to fill:
  // the sphere is 4 patches without the view check too, where flat discs needed 36.
  SlimFitOptions bent;
  bent.see_point_holes = false;
  const Outcome bent_unseen = fit_and_measure(s, kE, bent, false, false);
  EXPECT_LE(bent_unseen.surface.holes, o.surface.holes);
  EXPECT_LE(bent_unseen.fit.stats.patches, unseen.fit.stats.patches / 2);
}

// A wave scanned in lines 15 times farther apart than their points, with its exact normals. The
// nearest 16 points lie along one line, whose plane is anything: the given normals were judged
// "99.5 % off their neighbours' plane" and replaced, and each point's tangent disc, sized along
// its line, left the strips between the lines off the data: 1,281 patches at 1e-2 and 4,293 at
// 1e-3, where a grid of as many points needs 27 and 63.
TEST(FitSlimHard, LineScannedWaveKeepsItsNormalsAndFitsAsAGrid) {
  PointCloud c;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 600; ++j) {
      const double x = -1 + (i + 0.5) / 20.0, y = -1 + (j + 0.5) / 300.0;
      c.points.emplace_back(x, y, 0.2 * std::sin(2 * x) * std::cos(2 * y));
      c.normals.push_back(Vec(-0.4 * std::cos(2 * x) * std::cos(2 * y), 0.4 * std::sin(2 * x) * std::sin(2 * y), 1).normalized());
    }
  for (const double E : {1e-2, 1e-3}) {
    const SlimFitResult r = fit_slim(c, {.max_error = E});
    std::printf("line-scanned wave at %g: %zu patches (normals %s), %.2f s\n", E, r.stats.patches,
                r.stats.normals_estimated ? "estimated" : "given", r.stats.time_total);
    EXPECT_FALSE(r.stats.normals_estimated) << E;
    EXPECT_EQ(r.stats.blend_failures, 0u) << E;
    EXPECT_EQ(r.stats.surface_failures, 0u) << E;
    EXPECT_LE(r.stats.patches, E > 5e-3 ? 40u : 120u) << E;
  }
  // Random normals on the same lines are still judged off the plane (over the wider
  // neighbourhood) and replaced: skipping line neighbourhoods kept them, 12,876 patches.
  {
    PointCloud bad = c;
    std::mt19937_64 rng(3);
    std::normal_distribution<double> G(0.0, 1.0);
    for (auto& nrm : bad.normals) nrm = Vec(G(rng), G(rng), G(rng)).normalized();
    const SlimFitResult r = fit_slim(bad, {.max_error = 1e-2});
    std::printf("line-scanned wave with random normals at 0.01: %zu patches (normals %s)\n", r.stats.patches,
                r.stats.normals_estimated ? "estimated" : "given");
    EXPECT_TRUE(r.stats.normals_estimated);
    EXPECT_LE(r.stats.patches, 200u);
  }
  // Without normals they are estimated over wider neighbourhoods where 16 points lie on a line.
  c.normals.clear();
  const SlimFitResult r = fit_slim(c, {.max_error = 1e-3});
  std::printf("line-scanned wave at 1e-3, normals estimated: %zu patches\n", r.stats.patches);
  EXPECT_EQ(r.stats.surface_failures, 0u);
  EXPECT_LE(r.stats.patches, 300u);
}

TEST(FitSlimHard, UniformNoiseOfHalfE) {
  Shape s = make({{[](double u, double v) {
                     const double th = std::acos(1 - 2 * u), ph = 2 * std::numbers::pi * v;
                     return Vec(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
                   },
                   1, 150}},
                 15000, 7);
  std::mt19937_64 rng(77);
  const double E = kE * s.box.diagonal();
  std::uniform_real_distribution<double> noise(-0.5 * E, 0.5 * E);
  for (std::size_t i = 0; i < s.cloud.points.size(); ++i) s.cloud.points[i] += noise(rng) * s.cloud.normals[i];
  // E is relative to the noisy cloud's diagonal; the truth is the mesh of the exact sphere.
  expect_two_sided(fit_and_measure(s, kE));
}

TEST(FitSlimHard, NoNormalsEstimatedAndOriented) {
  const Shape s = make(box({0, 0, 0}, {1, 0.6, 0.3}), 20000, 8);
  const Outcome o = fit_and_measure(s, 2 * kE, {}, /*drop_normals=*/true, /*with_faces=*/false);
  EXPECT_TRUE(o.fit.stats.normals_estimated);
  expect_two_sided(o);
}

// A lens (two spherical caps meeting at a knife edge), no normals. The PCA normals of the rim's
// points lie between the caps', so the orientation propagated over the points crossed the rim and
// turned one cap inside out: at 39° it fitted with exit 0 and was seen from behind as specks
// (SLIM draws front-facing hits), because every check placed its views on the side the normals
// gave. Ray parity (fit/normals.cpp orient_by_parity) turns that cap back.
Shape lens(double dihedral_deg, std::size_t n, std::uint64_t seed) {
  const double alpha = dihedral_deg / 2 * std::numbers::pi / 180, rho = 1 / std::sin(alpha);
  const auto cap = [=](double z_sign) {
    return [=](double u, double v) {
      const double th = alpha * u, ph = 2 * std::numbers::pi * v;
      return Vec(rho * std::sin(th) * std::cos(ph), rho * std::sin(th) * std::sin(ph), z_sign * rho * (std::cos(th) - std::cos(alpha)));
    };
  };
  return make({{cap(1), 1, 120}, {cap(-1), -1, 120}}, n, seed);
}

TEST(FitSlimHard, AKnifeEdgeLensWithoutNormalsHasBothCapsOutward) {
  const Shape s = lens(39, 12000, 14);
  for (std::size_t i = 0; i < s.cloud.points.size(); ++i)  // the truth's normals face away from the lens's middle
    ASSERT_GT(s.cloud.normals[i].z() * s.cloud.points[i].z(), 0) << i;
  const Outcome o = fit_and_measure(s, 2 * kE, {}, /*drop_normals=*/true, /*with_faces=*/false);
  EXPECT_TRUE(o.fit.stats.normals_estimated);
  expect_two_sided(o);
}

TEST(FitSlimHard, SparseCloudBelowItsSpacing) {
  // 2,000 points on a torus-like bump surface, fitted at 1e-4: E is far below the spacing.
  const Shape s = make({{[](double u, double v) {
                           const double a = 2 * std::numbers::pi * u, b = 2 * std::numbers::pi * v;
                           return Vec((1 + 0.4 * std::cos(b)) * std::cos(a), (1 + 0.4 * std::cos(b)) * std::sin(a),
                                      0.4 * std::sin(b));
                         },
                         -1, 200}},
                       2000, 9);
  expect_two_sided(fit_and_measure(s, 1e-4, {}, false, /*with_faces=*/false));
}


// A cloud on an exact sphere fitted far below what its tangent discs resolve: the repairs shrink
// the patches until gaps open between the points, though every point's coverage disc is held.
// The fit said nothing of them (800 points without normals at 1e-6: 0 holes, 81 % of bench fit's
// pixels open); the holes it leaves are now counted on the model returned, and the measure agrees
// there are. With the exact normals given, the rounds' own check saw none (38 coverage discs
// not held, 0 holes seen, 99.9 % of the pixels open, exit 0): the ring spots one spacing out lie
// 60E below the neighbours' bent discs, so the view began 2E above those, inside the sphere, and
// the coverage discs' corners were judged on flat discs that sag 1,000E there. Either way the
// holes now put the fit outside its bound (hole_share, exit 7).
TEST(FitSlimHard, HolesLeftBetweenThePointsAreCounted) {
  PointCloud cloud;
  const int n = 800;
  for (int i = 0; i < n; ++i) {  // a Fibonacci sphere, exact to double
    const double z = 1.0 - (2.0 * i + 1.0) / n, r = std::sqrt(1.0 - z * z), phi = i * 2.399963229728653;
    cloud.points.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  SlimFitOptions opt;
  opt.max_error = 1e-6;
  const SlimFitResult fit = fit_slim(cloud, opt);  // normals estimated
  const DataSurface discs = DataSurface::from_points(cloud.points, cloud.points);  // the sphere's own normals
  Box3 box;
  for (const auto& p : cloud.points) box.extend(p);
  const SurfaceError e = measure_surface_error(fit.model, discs, box, {.views = 8, .resolution = 96, .bound = 2 * fit.stats.max_error_abs});
  ASSERT_TRUE(e.has_holes_measure);
  std::cerr << "  holes " << e.hole_share << ", counted " << fit.stats.point_holes << " + " << fit.stats.seen_point_holes << "\n";
  ASSERT_GT(e.hole_share, 0.05);  // the case this test is for
  EXPECT_GT(fit.stats.point_holes + fit.stats.seen_point_holes, std::size_t(n / 10));
  EXPECT_TRUE(fit.stats.holes_exceeded) << "hole share " << fit.stats.hole_share;
  PointCloud exact = cloud;
  exact.normals = cloud.points;
  const SlimFitResult given = fit_slim(exact, opt);
  const SurfaceError g = measure_surface_error(given.model, discs, box, {.views = 8, .resolution = 96, .bound = 2 * given.stats.max_error_abs});
  std::cerr << "  exact normals: holes " << g.hole_share << ", counted " << given.stats.point_holes << " + "
            << given.stats.seen_point_holes << ", hole share " << given.stats.hole_share << "\n";
  ASSERT_GT(g.hole_share, 0.05);
  EXPECT_GT(given.stats.seen_point_holes, std::size_t(n / 10));
  EXPECT_GT(given.stats.hole_share, 0.1);
  EXPECT_TRUE(given.stats.holes_exceeded);
}

// A smooth sheet (z = 0.08 sin 3u cos 2v over the unit square, grid² quads) whose mesh vertices
// move by uniform noise of ±amplitude·E in z (E = rel × its diagonal) where `where` holds; the
// cloud is the noisy mesh's vertices with their area-weighted normals, as a scan's would be.
Shape noisy_sheet(int grid, double rel, double amplitude, std::uint64_t noise_seed, std::uint64_t seed,
                  const std::function<bool(const Vec&)>& where) {
  Shape s = make({{[](double u, double v) { return Vec(u, v, 0.08 * std::sin(3 * u) * std::cos(2 * v)); }, 1, grid}}, 10, seed);
  const double E = rel * s.box.diagonal();
  std::mt19937_64 rng(noise_seed);
  std::uniform_real_distribution<double> noise(-amplitude * E, amplitude * E);
  for (auto& v : s.mesh.vertices)
    if (where(v)) v.z() += noise(rng);
  s.cloud = points_from_mesh(s.mesh);
  s.box = Box3{};
  for (const auto& v : s.mesh.vertices) s.box.extend(v);
  return s;
}

// A scan whose vertices jitter by ±3E about a smooth sheet, its spacing about 50E, fitted at E
// with its faces: no quadric through more than a few vertices stays within E (the bunny at 1e-4
// is like this). Without face patches (SlimFitOptions::face_patches) the fit fell apart into
// tangent discs: holes 5.2 % of the data's pixels, surface p99.9 5.5E. With them: 0.27 %, 2.4E.
// The two-sided bound itself is out of reach here: blended planes of faces that meet at up to
// ~7° leave a few E between them, and a vertex mixed with a neighbouring quadric lands up to
// 1.3E off (see the session note), so the test bounds what the face patches buy.
TEST(FitSlimHard, NoisyMeshBelowItsNoise) {
  const double rel = 2e-4;
  const Shape s = noisy_sheet(70, rel, 3.0, 99, 10, [](const Vec&) { return true; });
  const Outcome o = fit_and_measure(s, rel);
  EXPECT_EQ(o.points.misses, 0u);
  EXPECT_LE(o.points.max, 2 * o.E);
  EXPECT_GT(o.surface.pixels, 1000u);
  EXPECT_LE(o.surface.hole_share, 5e-3) << o.surface.holes << " holes in " << o.surface.data_pixels << " pixels";
  EXPECT_LE(o.surface.p999, 3 * o.E) << "surface p99.9 / E = " << o.surface.p999 / o.E;
  EXPECT_LE(o.surface.share_beyond, 3e-3);
}

// Spots of the mesh's triangles (a barycentric lattice of 4 per edge) outside every SLIM ball:
// holes of the drawn surface between points that are all covered. Independent of the fitter's
// own check (fit_slim's face_holes), which splits triangles instead.
std::size_t spots_outside_every_ball(const Model& model, const PolygonMesh& mesh) {
  std::size_t outside = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    const Vec &a = mesh.vertices[vs[0]], &b = mesh.vertices[vs[1]], &c = mesh.vertices[vs[2]];
    for (int i = 0; i <= 4; ++i)
      for (int j = 0; i + j <= 4; ++j) {
        const Vec x = a + (i / 4.0) * (b - a) + (j / 4.0) * (c - a);
        outside += std::none_of(model.slims.begin(), model.slims.end(),
                                [&](const SlimPatch& p) { return (x - p.centre).norm() < p.radius; });
      }
  }
  return outside;
}

// A smooth sheet whose mesh is noisy (±2E) in one corner: the balls there stay smaller than the
// faces, so they cover every vertex and face sample but not the faces between them (the bunny's
// base at 1e-3 had 37 such triangles). The fitter finds such spots and covers them.
TEST(FitSlimHard, NoFaceLeftBetweenCoveredPointsOnANoisyCorner) {
  const double rel = 1e-3;
  const Shape s = noisy_sheet(60, rel, 2.0, 7, 11, [](const Vec& v) { return v.x() < 0.3 && v.y() < 0.3; });
  const Outcome off = fit_and_measure(s, rel, {.cover_face_holes = false});
  const Outcome on = fit_and_measure(s, rel);
  const std::size_t before = spots_outside_every_ball(off.fit.model, s.mesh);
  const std::size_t after = spots_outside_every_ball(on.fit.model, s.mesh);
  std::cerr << "  spots outside every ball: " << before << " without, " << after << " with (" << on.fit.stats.hole_points
            << " points added); holes " << off.surface.holes << " → " << on.surface.holes << "\n";
  EXPECT_GT(before, 0u) << "the case no longer makes holes between covered points";
  EXPECT_EQ(after, 0u);
  EXPECT_EQ(on.fit.stats.face_holes, 0u);
  EXPECT_GT(on.fit.stats.hole_points, 0u);
  EXPECT_LE(on.surface.holes, off.surface.holes);
  EXPECT_EQ(on.points.misses, 0u);
  EXPECT_EQ(on.fit.stats.blend_failures, 0u);
}

// The coarse polyhedral sphere below, and a box of 3 × 3 quads a face, fitted at 1e-4: every face
// far larger than E, so no quadric through a point's neighbours stays within E and the faces are
// covered by their own planes (face patches). Each face patch is clipped to its face's prism;
// without the prisms a face's plane ran on across its edges into the neighbours' territory and
// the blend mixed the planes there (sphere: surface p99.9 134E).
Shape coarse_sphere() {
  return make({{[](double u, double v) {
                  const double th = 0.05 + 3.0 * u, ph = 2 * std::numbers::pi * v;
                  return Vec(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
                },
                1, 16}},
              10, 5);
}

// The data as the mesh has it: its vertices as the points (coarse_sphere's few points lie on the
// round sphere, up to 14E off its faces, where no surface can be within E of both).
Shape vertices_only(Shape s) {
  s.cloud.points = s.mesh.vertices;
  s.cloud.normals.clear();
  for (const Vec& v : s.mesh.vertices) s.cloud.normals.push_back(v.normalized());
  return s;
}

TEST(FitSlimHard, CoarsePolyhedronBelowItsSampling) {
  const Shape sphere = vertices_only(coarse_sphere());
  const Outcome with = fit_and_measure(sphere, 1e-4);
  expect_two_sided(with);
  std::vector<Sheet> faces = box(Vec(-1, -0.5, -0.7), Vec(1, 0.5, 0.7));
  for (auto& f : faces) f.grid = 3;
  const Shape cs = make(faces, 10, 3);
  const Outcome cube = fit_and_measure(cs, 1e-4);
  expect_two_sided(cube);
  // The case still needs the prisms.
  const Outcome without = fit_and_measure(sphere, 1e-4, {.face_prisms = false});
  EXPECT_GT(without.surface.p999, 2 * without.E) << "the case no longer needs the face prisms";
}

// A coarse polyhedral sphere (16 × 16 quads) fitted at 1e-4: every face far larger than E, bent
// 11° against its neighbours, the regime where a repair can leave the fit worse than it found it
// (the armadillo at 1e-4: 26 points beyond E after the first verification, 3,550 after six
// repairs). The fit keeps the verified model with the fewest failures, its figures with it.
TEST(FitSlimHard, KeepsTheBestVerifiedModelWhenRepairsMakeItWorse) {
  // Its few points lie on the round sphere, up to 14E off the faces (no model can be within E
  // of both), and without the face prisms the faces' planes blend across the edges: a repair
  // can only trade one failure for another there.
  const Shape s = coarse_sphere();
  const SlimFitResult r = fit_slim(s.cloud, s.mesh, {.max_error = 1e-4, .face_prisms = false, .cover_face_holes = false});
  const auto& st = r.stats;
  ASSERT_EQ(st.hole_points, 0u);  // the same points in every round: their failures compare
  ASSERT_GE(st.round_failures.size(), 3u);
  ASSERT_EQ(st.round_breaches.size(), st.round_failures.size());
  std::cerr << "  kept round " << st.kept_round << " of " << st.round_failures.size() << ":";
  for (std::size_t i = 0; i < st.round_failures.size(); ++i)
    std::cerr << " " << st.round_failures[i] << " (" << st.round_breaches[i] << ")";
  std::cerr << "\n";
  // The fewest breaches of the bound (points beyond E, surface samples beyond 2E), then the
  // least share of failures.
  std::size_t best = 0;
  for (std::size_t i = 1; i < st.round_failures.size(); ++i)
    if (std::pair(st.round_breaches[i], st.round_failures[i]) < std::pair(st.round_breaches[best], st.round_failures[best]))
      best = i;
  EXPECT_EQ(st.kept_round, int(best));
  const auto least = st.round_failures.begin() + std::ptrdiff_t(best);
  EXPECT_TRUE(std::pair(*(st.round_breaches.begin() + std::ptrdiff_t(best)), *least) <
              std::pair(st.round_breaches.back(), st.round_failures.back()))
      << "the case no longer has a repair that makes the fit worse";
  // The figures reported are the kept model's: its failures add up to that round's.
  const double triangles = double(s.mesh.face_count()), pieces = 64.0;  // face_hole_depth 3
  const double again = double(st.blend_failures) / double(st.points) +
                       double(st.surface_failures) / double(st.surface_samples) + double(st.face_holes) / (triangles * pieces);
  EXPECT_NEAR(again, *least, 1e-9 * (1 + *least));
  EXPECT_EQ(r.model.slims.size(), st.patches);
}

// Folded faces, as decimated meshes have them (dragon_10k and happy_buddha_10k in ../shared: a
// triangle stood up across its neighbours, its normal along the surface): here fans of six tiny
// triangles standing on a sphere, their normals tangent to it and cancelling, among sparse
// samples. Their face samples lie 0.1E above the sphere, but along their own normal, tangent to
// a surface that curves away, no surface is met, and their neighbourhood disagrees (no
// neighbourhood_normal). dragon_10k at 1e-2 had 7 such points "10E away", repaired in vain for
// 10 rounds; the distance along any line through the point bounds it (nearest_along_lines), and
// the fit keeps its bound.
TEST(FitSlimHard, FoldedFacesStandingOnTheSurface) {
  const double rel = 1e-2;  // the cloud's spacing below E: no face patches, which would hold a fold's own plane
  const std::array<Vec, 3> fans{Vec(0.6, 0.0, 0.8), Vec(0.0, -0.6, 0.8), Vec(-0.48, 0.6, -0.64)};
  const double E = rel * 2.0 * std::sqrt(3.0);  // the unit sphere's box diagonal
  const auto sphere = [](double u, double v) {
    const double th = 0.05 + 3.04 * u, ph = 2 * std::numbers::pi * v;
    return Vec(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
  };
  // No cloud points within 4E of a fan: the folds' nearest samples are each other and the
  // sphere's face samples.
  Shape s = make({{sphere, 1, 60}}, 20000, 17, [&](const Vec& p) {
    return std::all_of(fans.begin(), fans.end(), [&](const Vec& q) { return (p - q).norm() > 4 * E; }) ? 1.0 : 0.0;
  });
  std::vector<std::pair<Vec, Vec>> folds;  // centroid, normal
  for (const Vec& q : fans) {
    const Vec e1 = q.unitOrthogonal(), e2 = q.cross(e1);
    for (int k = 0; k < 6; ++k) {
      const double a = k * std::numbers::pi / 3;
      const Vec u = std::cos(a) * e1 + std::sin(a) * e2;
      const int base = static_cast<int>(s.mesh.vertices.size());
      s.mesh.vertices.push_back(q + 0.5 * E * u);
      s.mesh.vertices.push_back(q + 3.0 * E * u);
      s.mesh.vertices.push_back(q + 1.75 * E * u + 0.3 * E * q);
      s.mesh.add_face(std::vector<int>{base, base + 1, base + 2});
      const Vec* v = &s.mesh.vertices[base];
      folds.push_back({(v[0] + v[1] + v[2]) / 3.0, (v[1] - v[0]).cross(v[2] - v[0]).normalized()});
    }
  }
  const Outcome o = fit_and_measure(s, rel);
  expect_two_sided(o);
  // The case needs more than the point's own normal and its neighbourhood's.
  const ReferenceScene scene(o.fit.model);
  TraceOptions trace;
  trace.slim.offset = slim_offset_of(o.fit.model);
  PointCloud all = s.cloud;  // the points the fit measures: the cloud and the face samples
  const PointCloud faces = face_samples(s.mesh);
  all.points.insert(all.points.end(), faces.points.begin(), faces.points.end());
  all.normals.insert(all.normals.end(), faces.normals.begin(), faces.normals.end());
  const PointIndex index{std::span<const Vec>(all.points)};
  std::vector<Neighbour> scratch;
  std::size_t beyond_along_normal = 0, no_neighbourhood = 0;
  for (const auto& [c, n] : folds) {
    beyond_along_normal += !(probe_point(scene, trace, c, n, 4 * E, E).error <= E);
    no_neighbourhood += !neighbourhood_normal(index, all.normals, c, n, scratch).has_value();
  }
  EXPECT_GT(beyond_along_normal, 0u) << "the folds no longer hide the surface from their normals";
  EXPECT_GT(no_neighbourhood, 0u) << "every fold's neighbourhood agrees: the case no longer needs the lines";
}

// A V-groove of two coarse walls (3 × 3 quads each) fitted far below its sampling: every point
// lies on its face's plane, so points and surface pass in the first round, while most of the
// faces lie outside every ball. Those faces get face patches of their own before the fit ends
// (it used to stop on the passing sides: 5.8 % of the data's pixels left empty).
TEST(FitSlimHard, CoarseGrooveGetsItsFacePatchesBeforeTheFitEnds) {
  const double th = 50.0 * std::numbers::pi / 180.0;  // each wall 50° above the groove's floor line
  const Vec x(2, 0, 0), a(0, std::cos(th), std::sin(th)), b(0, -std::cos(th), std::sin(th));
  const Shape s = make({quad(Vec(0, 0, 0), x, a, 1, 3), quad(Vec(0, 0, 0), b, x, 1, 3)}, 10, 21);
  const Outcome o = fit_and_measure(s, 1e-4);
  expect_two_sided(o);
  EXPECT_GT(o.fit.stats.hole_face_patches, 0u);
  EXPECT_EQ(o.fit.stats.face_holes, 0u);
}

// A coarse sheet with a flap folded under it 6E below, facing the same way (a decimated mesh's
// fold, as in dragon_10k), fitted far below its sampling: the face patches are the faces' planes
// in balls as large as the faces. A ray through the sheet meets the flap 6E on, front-facing; a
// blend that pushes the first hit back by half such a ball mixes the two sheets (dragon_10k at
// 1e-4: hits 6-10E apart blended 2-4E off both). The push is bounded by blend_max_push·E.
TEST(FitSlimHard, FlapUnderASheetIsNotBlendedIn) {
  const double rel = 1e-4, E = rel * std::sqrt(8.0);  // the sheet's diagonal
  const Shape s = make({quad(Vec(-1, -1, 0), Vec(2, 0, 0), Vec(0, 2, 0), 1, 3),
                        quad(Vec(-0.5, -0.5, -6 * E), Vec(1, 0, 0), Vec(0, 1, 0), 1, 2)},
                       10, 21);
  const Outcome bounded = fit_and_measure(s, rel);
  expect_two_sided(bounded);
  EXPECT_TRUE(bounded.fit.model.metadata.contains("slim_max_push"));
  const Outcome unbounded = fit_and_measure(s, rel, {.blend_max_push = 0});
  EXPECT_FALSE(unbounded.fit.model.metadata.contains("slim_max_push"));
  EXPECT_GT(unbounded.surface.p999, 2 * unbounded.E) << "the case no longer blends the flap into the sheet";
}

// A bumpy sheet given as a coarse triangle mesh (12 × 12 quads) and fitted at 1e-2: the balls
// cover every face (the lattice check passes), yet seen at an angle some rays meet no patch: a
// patch leaning against its face ends at its ball's rim before the ray reaches it (dragon_10k at
// 1e-2: 116 hole pixels over 8 views at 1024²; the same after the lattice check). The view check
// traces rays through the faces' spots at up to 75° and gives the faces seen through patches of
// their own. Measured finer than the other tests (8 views at 512²), since the holes are slits.
// (Seed 7: with try_sharp's plane turned at concave creases, seed 5's sheet left only 6 hole
// pixels without the view check, 3 with it; seed 7 leaves 88 and 2.)
TEST(FitSlimHard, GrazingViewsSeeNoHolesBetweenCoveringBalls) {
  const Shape s = make({{[](double u, double v) {
                           return Vec(u, v, 0.08 * std::sin(6 * u) * std::cos(5 * v) + 0.05 * std::sin(17 * u * v));
                         },
                         1, 12}},
                       4000, 7);
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  const auto holes = [&](const Outcome& o) {
    return measure_surface_error(o.fit.model, truth, s.box, {.views = 8, .resolution = 512, .bound = 2 * o.E});
  };
  const Outcome with = fit_and_measure(s, 1e-2);
  expect_two_sided(with);
  EXPECT_GT(with.fit.stats.view_balls + with.fit.stats.view_face_patches, 0u);
  EXPECT_EQ(with.fit.stats.view_holes, 0u);
  const SurfaceError fine = holes(with);
  const Outcome without = fit_and_measure(s, 1e-2, {.view_hole_rays = 0});
  const SurfaceError before = holes(without);
  // Face patches alone (one per face seen through) mend the same slits with more patches.
  const Outcome patches_only = fit_and_measure(s, 1e-2, {.view_balls = false});
  expect_two_sided(patches_only);
  const SurfaceError by_patches = holes(patches_only);
  std::cerr << "  holes at 512²: " << fine.holes << " of " << fine.data_pixels << " pixels (" << with.fit.model.slims.size()
            << " patches, " << with.fit.stats.view_balls << " view balls, " << with.fit.stats.view_face_patches
            << " view face patches); face patches only " << by_patches.holes << " (" << patches_only.fit.model.slims.size()
            << " patches); without the view check " << before.holes << " (" << without.fit.model.slims.size() << ")\n";
  EXPECT_LE(fine.hole_share, 5e-5) << fine.holes << " of " << fine.data_pixels;
  EXPECT_LE(by_patches.hole_share, 5e-5) << by_patches.holes << " of " << by_patches.data_pixels;
  EXPECT_GT(before.holes, 3 * fine.holes) << "the case no longer leaves holes the lattice check misses";
}

// A fine bumpy sheet beside a coarse one (12 × 12 quads, its points on its faces), fitted at
// 1e-4, far below the coarse sheet's sampling and at the fine one's: most of the coarse faces get
// face patches, the rest are covered by balls that come out smaller than the faces. Both sides
// hold and the fit ends with no face outside every ball (bunny at 1e-4 used to end with 568 such
// spots: test_fit_scans.cpp).
TEST(FitSlimHard, MixedSamplingEndsWithNoFaceOutsideEveryBall) {
  const auto f = [](double ox, double u, double v) {
    return Vec(ox + u, v, 0.06 * std::sin(5 * u) * std::cos(4 * v) + 0.03 * std::sin(11 * u * v));
  };
  // The coarse sheet is its own triangulation (the points lie on its faces, as a mesh's samples
  // do): f interpolated linearly on the triangles (a, b, d), (a, d, c) that make() builds.
  const int g = 12;
  const Sheet coarse{[=](double u, double v) {
                       const int i = std::min(int(u * g), g - 1), j = std::min(int(v * g), g - 1);
                       const double x = u * g - i, y = v * g - j;
                       const Vec a = f(1.2, double(i) / g, double(j) / g), b = f(1.2, double(i + 1) / g, double(j) / g),
                                 c = f(1.2, double(i) / g, double(j + 1) / g), d = f(1.2, double(i + 1) / g, double(j + 1) / g);
                       return Vec(x >= y ? a + (x - y) * (b - a) + y * (d - a) : a + (y - x) * (c - a) + x * (d - a));
                     },
                     1, g};
  const Shape s = make({Sheet{[=](double u, double v) { return f(0, u, v); }, 1, 60}, coarse}, 6000, 9);
  const Outcome o = fit_and_measure(s, 1e-4);
  expect_two_sided(o);
  EXPECT_EQ(o.fit.stats.face_holes, 0u);
}

// A quad mesh whose quads are not planar (the saddle z = 0.4xy on an 8 × 8 grid: each quad's
// corners 6e-3 off a plane, 2E at 1e-3), fitted where its faces are larger than the balls, so
// the fit falls back to face patches. It takes the quads as their fans of triangles, as the data
// side measures them: a face patch is a plane, and a twisted quad's centroid lies off it
// (spot_quadrangulated in ../shared looped in the covering at 1e-3 until memory ran out; at 1e-4
// 540 points stayed beyond E).
TEST(FitSlimHard, TwistedQuadsBelowTheirSampling) {
  Shape s;
  const int g = 8;
  for (int j = 0; j <= g; ++j)
    for (int i = 0; i <= g; ++i) {
      const double x = -1.0 + 2.0 * i / g, y = -1.0 + 2.0 * j / g;
      s.mesh.vertices.emplace_back(x, y, 0.4 * x * y);
      s.cloud.points.emplace_back(x, y, 0.4 * x * y);
      s.cloud.normals.push_back(Vec(-0.4 * y, -0.4 * x, 1.0).normalized());
    }
  for (int j = 0; j < g; ++j)
    for (int i = 0; i < g; ++i) {
      const int a = j * (g + 1) + i;
      s.mesh.add_face(std::vector<int>{a, a + 1, a + g + 2, a + g + 1});
    }
  for (const Vec& v : s.mesh.vertices) s.box.extend(v);
  ASSERT_FALSE(s.mesh.is_triangles());
  for (const double rel : {1e-3, 1e-4}) {
    const Outcome o = fit_and_measure(s, rel);
    expect_two_sided(o);
    // At 1e-3 the repairs' balls, checked on verification's lattice before they join, may
    // cover it without them.
    if (rel < 1e-3) EXPECT_GT(o.fit.stats.hole_face_patches, 0u) << "the case no longer needs face patches";
  }
}

// Slivers with two sharp corners (about 2°, 2° and 176°: a vertex inserted just off a coarse
// triangle's edge, as decimated scans have them), fitted far below their sampling, where faces
// get face patches. Each patch's prism walls stand a margin outside its edges, and two walls
// meet far past a sharp corner: the fourth clip plane cuts one corner, and the other corner's
// walls now stand a hair outside their edges instead (happy_buddha_10k at 1e-4: such patches ran
// 1.5–3.2E from the data, were dropped and made again round after round, and the fit ended with
// samples beyond 2E).
TEST(FitSlimHard, SliversWithTwoSharpCornersBelowTheirSampling) {
  Shape s = vertices_only(coarse_sphere());
  PolygonMesh m;
  m.vertices = s.mesh.vertices;
  const double t = std::tan(2.0 * std::numbers::pi / 180.0);
  std::size_t slivers = 0;
  for (std::size_t f = 0; f < s.mesh.face_count(); ++f) {
    const auto vs = s.mesh.face(f);
    // make() builds each quad as (a, b, d), (a, d, c): every fifth quad's second triangle gets a
    // vertex M just off its diagonal a–d, towards c.
    if (f % 2 == 1 && (f / 2) % 5 == 0) {
      const int a = vs[0], d = vs[1], c = vs[2];
      const Vec mid = 0.5 * (m.vertices[a] + m.vertices[d]);
      const Vec towards = (m.vertices[c] - mid).normalized();
      const int M = static_cast<int>(m.vertices.size());
      m.vertices.push_back(mid + t * 0.5 * (m.vertices[d] - m.vertices[a]).norm() * towards);
      m.add_face(std::vector<int>{a, M, c});
      m.add_face(std::vector<int>{M, d, c});
      m.add_face(std::vector<int>{a, d, M});
      ++slivers;
    } else {
      m.add_face(std::vector<int>(vs.begin(), vs.end()));
    }
  }
  ASSERT_GT(slivers, 10u);
  s.mesh = std::move(m);
  s = vertices_only(std::move(s));
  const Outcome o = fit_and_measure(s, 1e-4);
  expect_two_sided(o);
  EXPECT_GT(o.fit.stats.hole_face_patches, 0u) << "the case no longer needs face patches";
}

// A box whose faces are 12 x 12 quads, fitted from its mesh at 1e-3 (the way `quadrix fit` reads
// an OFF: vertices with their faces' normals): along each 90-degree edge the balls of one face
// stop short of it, and the strip left is within the band of the other face's sheet, whose ball
// and prism hold it. A ray that meets the face there passes beside that sheet: a line of holes
// along every edge (the turbine of CGAL's data at 1e-3: 9.8e-4 of its pixels). This box: 236 of
// 696,944 pixels at 512^2 (600 patches) before view_holes asked about such spots, 1 after (651).
TEST(FitSlimHard, NoSlitsAlongTheEdgesOfABox) {
  constexpr int n = 12;
  Shape s;
  const auto corner = [](int x, int y, int z) { return Vec(x, 0.6 * y, 0.25 * z); };
  std::map<std::tuple<long, long, long>, int> ids;  // shared vertices along the edges
  const auto vertex = [&](const Vec& p) {
    const auto key = std::make_tuple(std::lround(p.x() * 1e9), std::lround(p.y() * 1e9), std::lround(p.z() * 1e9));
    const auto [it, fresh] = ids.emplace(key, int(s.mesh.vertices.size()));
    if (fresh) s.mesh.vertices.push_back(p);
    return it->second;
  };
  // Each face an n x n grid of quads, split along the diagonal from the lower corner, outward.
  const auto face = [&](const Vec& a, const Vec& b, const Vec& c, const Vec& d) {
    const auto at = [&](int i, int j) {
      const double u = double(i) / n, v = double(j) / n;
      return vertex((1 - u) * (1 - v) * a + u * (1 - v) * b + u * v * c + (1 - u) * v * d);
    };
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        s.mesh.add_face(std::vector<int>{at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        s.mesh.add_face(std::vector<int>{at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
  };
  face(corner(0, 0, 0), corner(0, 1, 0), corner(1, 1, 0), corner(1, 0, 0));
  face(corner(0, 0, 1), corner(1, 0, 1), corner(1, 1, 1), corner(0, 1, 1));
  face(corner(0, 0, 0), corner(1, 0, 0), corner(1, 0, 1), corner(0, 0, 1));
  face(corner(0, 1, 0), corner(0, 1, 1), corner(1, 1, 1), corner(1, 1, 0));
  face(corner(0, 0, 0), corner(0, 0, 1), corner(0, 1, 1), corner(0, 1, 0));
  face(corner(1, 0, 0), corner(1, 1, 0), corner(1, 1, 1), corner(1, 0, 1));
  for (const auto& v : s.mesh.vertices) s.box.extend(v);
  s.cloud = points_from_mesh(s.mesh);
  const Outcome o = fit_and_measure(s, kE);
  expect_two_sided(o);
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  const SurfaceError fine = measure_surface_error(o.fit.model, truth, s.box, {.views = 8, .resolution = 512, .bound = 2 * o.E});
  std::cerr << "  holes at 512^2: " << fine.holes << " of " << fine.data_pixels << " pixels, " << o.fit.model.slims.size()
            << " patches\n";
  EXPECT_GT(fine.data_pixels, 100000u);
  EXPECT_LE(fine.hole_share, 2e-5) << fine.holes << " of " << fine.data_pixels;
}

// A closed plate with normals, points only, at 3e-3: its faces' tangent discs reach a disc
// radius past the plate's edges, so the data's surface itself has fins there, and so has the fit
// (a new user's plate 0.04 thick: fins 6.9E past its edges, within 1.6E of the discs, exit 0).
// With the discs cut at the creases (SlimFitOptions::crease_cuts, the default) the fit stays
// within 2E of the true box, with no more holes, and keeps its hole promise (the slit check at
// creases counted 36 slits past the plate's edges, a hole share of 1.8e-3, until it asked for the
// data there too). Measured against the true box, as a user sees it.
TEST(FitSlimHard, PointsOnlyPlateHasNoFinsPastItsEdgesWithCreaseCuts) {
  const Shape s = make(box({0, 0, 0}, {1, 1, 0.04}), 20000, 21);
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  for (const bool cuts : {true, false}) {
    SlimFitOptions opt;
    opt.max_error = 3e-3;
    opt.crease_cuts = cuts;
    const SlimFitResult fit = fit_slim(s.cloud, opt);
    const double E = fit.stats.max_error_abs;
    const SurfaceError e = measure_surface_error(fit.model, truth, s.box, {.views = 8, .resolution = 256, .bound = 2 * E});
    std::cerr << "  crease cuts " << cuts << ": patches " << fit.stats.patches << ", surface p99.9/E " << e.p999 / E
              << " max/E " << e.max / E << " beyond 2E " << e.share_beyond << ", holes " << e.holes << "/" << e.data_pixels
              << ", fit's hole share " << fit.stats.hole_share << " (seen " << fit.stats.seen_point_holes << ", crease gaps " << fit.stats.crease_gaps << ")\n";
    if (!cuts) {  // the fins the cuts remove (measured: 5.7E, 0.11 % of the pixels beyond 2E)
      EXPECT_GT(e.max, 4 * E);
      continue;
    }
    EXPECT_LE(e.share_beyond, 1e-4) << e.beyond << " of " << e.pixels;
    EXPECT_LE(e.max, 2 * E);
    EXPECT_LE(e.hole_share, 1e-4);
    EXPECT_LE(fit.stats.hole_share, opt.max_hole_share);
    EXPECT_EQ(fit.stats.blend_failures, 0u);
    EXPECT_EQ(fit.stats.surface_failures, 0u);
  }
}

// A cloud's data surface (its discs) as a viewer would see it, measured against the truth.
SurfaceError discs_against(const DataSurface& discs, const DataSurface& truth, const Box3& box, double bound) {
  const TraceFn trace = [&](const Ray& r) -> std::optional<double> {
    if (const auto h = discs.first_hit(r)) return h->t;
    return std::nullopt;
  };
  return measure_surface_error(trace, truth, box, {.views = 8, .resolution = 128, .bound = bound, .holes = false});
}

// Crease points (DataSurfaceOptions::crease_points). A box's points without normals get PCA
// normals rounded over its edges, and a mesh's vertex normals average the faces' there: those
// discs, tilted, stood off both faces. Each such point takes its face's plane, an edge's vertex
// gives both faces a disc, and exact normals are left alone.
TEST(DataSurface, CreasePointsTakeTheirFacesPlanes) {
  const Shape s = make(box({0, 0, 0}, {1, 0.6, 0.3}), 20000, 21);
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  const double E = 1e-3 * s.box.diagonal();
  const auto on_a_face = [](const Vec& n) { return n.cwiseAbs().maxCoeff() >= std::cos(std::numbers::pi / 180.0); };
  {
    const DataSurface exact = DataSurface::from_points(s.cloud.points, s.cloud.normals, {.crease_points = true});
    EXPECT_EQ(exact.crease_points(), 0u);
    EXPECT_EQ(exact.crease_copies(), 0u);
  }
  const std::vector<Vec> pca = estimate_normals(s.cloud.points, {}).normals;
  const DataSurface with = DataSurface::from_points(s.cloud.points, pca, {.crease_points = true});
  const DataSurface without = DataSurface::from_points(s.cloud.points, pca);
  std::size_t rounded = 0, turned = 0, onto_face = 0;
  for (std::size_t i = 0; i < pca.size(); ++i) {
    rounded += !on_a_face(pca[i]);
    if (with.normal(i) == pca[i]) continue;
    ++turned;
    onto_face += on_a_face(with.normal(i));
  }
  const SurfaceError a = discs_against(with, truth, s.box, 2 * E), b = discs_against(without, truth, s.box, 2 * E);
  std::cerr << "  PCA normals more than 1° off every face: " << rounded << "; turned " << turned << ", " << onto_face
            << " onto a face's; discs beyond 2E of the box " << a.share_beyond << " (without " << b.share_beyond
            << "), p99/E " << a.p99 / E << " (" << b.p99 / E << ")\n";
  EXPECT_EQ(with.crease_points(), turned);
  EXPECT_GE(double(turned), 0.6 * double(rounded));
  EXPECT_GE(double(onto_face), 0.99 * double(turned));
  EXPECT_LE(a.share_beyond, 0.3 * b.share_beyond);
  EXPECT_LT(a.p99, 0.7 * b.p99);

  // A tessellated box's vertices with the faces' normals averaged at its edges and corners.
  std::map<std::tuple<long, long, long>, std::size_t> at;
  PointCloud v;
  for (std::size_t f = 0; f < s.mesh.face_count(); ++f) {
    const auto c = s.mesh.face(f);
    const Vec n = (s.mesh.vertices[c[1]] - s.mesh.vertices[c[0]]).cross(s.mesh.vertices[c[2]] - s.mesh.vertices[c[0]]).normalized();
    for (const int k : c) {
      const Vec& p = s.mesh.vertices[k];
      const auto [it, fresh] = at.try_emplace({std::lround(p.x() * 1e6), std::lround(p.y() * 1e6), std::lround(p.z() * 1e6)}, v.points.size());
      if (fresh) v.points.push_back(p), v.normals.push_back(Vec::Zero());
      // once per face: the faces of one sheet agree, so a sum over sheets averages the faces'
      if (v.normals[it->second].dot(n) < 0.5 || v.normals[it->second].squaredNorm() == 0) v.normals[it->second] += n;
    }
  }
  std::size_t edges = 0;
  for (auto& n : v.normals) edges += !on_a_face(n.normalized()), n.normalize();
  const DataSurface averaged = DataSurface::from_points(v.points, v.normals, {.crease_points = true});
  std::size_t faced = 0;
  for (std::size_t i = 0; i < v.points.size(); ++i) faced += !on_a_face(v.normals[i]) && on_a_face(averaged.normal(i));
  std::cerr << "  vertices " << v.points.size() << ", on edges and corners " << edges << "; taken onto a face " << faced
            << ", second discs " << averaged.crease_copies() << "\n";
  EXPECT_GE(double(faced), 0.55 * double(edges));
  EXPECT_GE(double(averaged.crease_copies()), 0.55 * double(edges));
}

// The same box's points without normals, fitted at 1e-3: its crease points' discs bring the fit's
// surface onto the true box past its edges, with fewer patches.
// A box 1 × 0.6 × 0.3 of 20,000 points without normals.
Shape box_without_normals() {
  Shape s = make(box({0, 0, 0}, {1, 0.6, 0.3}), 20000, 52);
  s.cloud.normals.clear();
  return s;
}

TEST(FitSlimHard, BoxWithoutNormalsFitsNearItsEdgesWithCreasePoints) {
  const Shape s = box_without_normals();
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  const PointCloud& cloud = s.cloud;
  std::array<SurfaceError, 2> e;
  std::array<std::size_t, 2> patches{};
  double E = 0;
  for (const bool cp : {true, false}) {
    SlimFitOptions opt;
    opt.max_error = 1e-3;
    opt.crease_points = cp;
    const SlimFitResult fit = fit_slim(cloud, opt);
    E = fit.stats.max_error_abs;
    e[cp] = measure_surface_error(fit.model, truth, s.box, {.views = 8, .resolution = 256, .bound = 2 * E});
    patches[cp] = fit.stats.patches;
    std::cerr << "  crease points " << cp << " (" << fit.stats.crease_points << "): patches " << fit.stats.patches
              << ", surface p99.9/E " << e[cp].p999 / E << " max/E " << e[cp].max / E << " beyond 2E "
              << e[cp].share_beyond << ", holes " << e[cp].hole_share << "\n";
  }
  EXPECT_LE(e[1].share_beyond, 0.5 * e[0].share_beyond);
  EXPECT_LE(e[1].p999, 2 * E);
  EXPECT_GT(e[0].p999, 3 * E) << "the case no longer needs crease points";
  EXPECT_LT(double(patches[1]), 0.85 * double(patches[0]));
  EXPECT_LE(e[1].hole_share, std::max(1e-4, 1.25 * e[0].hole_share));  // no more holes
}

// The same box's corners: balls that hold three faces fitted no quadric, and the clipped sheet
// (try_sharp) was tried only with --sharp, so the balls near a corner shrank until they held one
// or two faces, and between the smallest the true box showed holes the fit's checks did not see
// (674 patches, 2.9e-4 of its pixels; in another sampling 49 of 77 hole pixels lay within 15E of
// a corner). Beside faces found at creases a failing ball now tries its centre's sheet, and at a
// corner that sheet is clipped at both other faces' planes: 107 patches, 1.2e-4. (Without it the
// holes beside the corners now fill the band: 1,156 patches, 2.0e-4.)
TEST(FitSlimHard, BoxWithoutNormalsClipsItsCornerPatchesAtTwoFaces) {
  const Shape s = box_without_normals();
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  std::array<SurfaceError, 2> e;
  std::array<std::size_t, 2> patches{}, two_clips{};
  double E = 0;
  for (const bool sharp : {true, false}) {
    const SlimFitResult fit = fit_slim(s.cloud, {.max_error = 1e-3, .sharp_at_creases = sharp});
    E = fit.stats.max_error_abs;
    e[sharp] = measure_surface_error(fit.model, truth, s.box, {.views = 8, .resolution = 256, .bound = 2 * E});
    patches[sharp] = fit.stats.patches;
    for (const auto& p : fit.model.slims) two_clips[sharp] += p.clips.size() == 2;
    std::cerr << "  sharp at creases " << sharp << ": " << fit.stats.patches << " patches, " << fit.stats.clipped_patches
              << " clipped, " << two_clips[sharp] << " at two faces; p99.9/E " << e[sharp].p999 / E << " max/E "
              << e[sharp].max / E << " beyond 2E " << e[sharp].share_beyond << ", holes " << e[sharp].hole_share << "\n";
    if (sharp) {
      EXPECT_EQ(fit.stats.blend_failures, 0u);
      EXPECT_EQ(fit.stats.surface_failures, 0u);
    }
  }
  EXPECT_GT(two_clips[1], 0u);
  EXPECT_LT(double(patches[1]), 0.3 * double(patches[0]));
  EXPECT_LT(e[1].hole_share, e[0].hole_share);
  EXPECT_LE(e[1].p999, 2 * E);
  EXPECT_LE(e[1].share_beyond, std::max(1e-4, e[0].share_beyond));
}

// A box sampled with its faces' own normals (as a CAD model gives them) has no crease points
// (they take estimated normals' faces), so its balls beside the edges never tried the sheet
// clipped at the other face (sharp_at_creases) and shrank until they held one face (another
// sampling: 647 patches and 5.3e-4 of the true box's pixels open at 1e-3, against 96 and 3.3e-5
// without the normals). The points on a face are the planar ones there: this sampling fits 151
// patches instead of 622, beyond 2E 5.4e-6 instead of 3.5e-4, true holes 0 instead of 1.1e-5.
TEST(FitSlimHard, BoxWithItsNormalsClipsItsPatchesAtTheEdges) {
  const Shape s = make(box({0, 0, 0}, {1, 0.6, 0.3}), 20000, 53);
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  std::array<std::size_t, 2> patches{};
  std::array<SurfaceError, 2> e;
  for (const bool sharp : {false, true}) {
    const SlimFitResult fit = fit_slim(s.cloud, {.max_error = 1e-3, .sharp_at_creases = sharp});
    const double E = fit.stats.max_error_abs;
    patches[sharp] = fit.stats.patches;
    e[sharp] = measure_surface_error(fit.model, truth, s.box, {.views = 8, .resolution = 256, .bound = 2 * E});
    std::cerr << "  sharp_at_creases " << sharp << ": " << patches[sharp] << " patches, " << fit.stats.clipped_patches
              << " clipped; true holes " << e[sharp].hole_share << ", beyond 2E " << e[sharp].share_beyond << ", p99.9 "
              << e[sharp].p999 / E << "E, fit's hole share " << fit.stats.hole_share << "\n";
    if (sharp) {
      EXPECT_FALSE(fit.stats.holes_exceeded);
    }
  }
  EXPECT_LT(double(patches[1]), 0.4 * double(patches[0]));
  EXPECT_LE(e[1].hole_share, 1e-4);
  EXPECT_LT(e[1].hole_share, 0.5 * e[0].hole_share);
  EXPECT_LE(e[1].share_beyond, std::max(1e-4, e[0].share_beyond));
}

// A sparse box (2,000 points without normals, a spacing of about 25E at 1e-3): its faces' planes
// spread from the crease points to nearly every point, and when any point beside a faced one
// counted as beside a crease, none of its holes decided the fill band: the fit counted no hole
// and exited 0 with 2.1 % of the true box's pixels open (review). Only the holes beside an edge
// or corner (two faces' points among the nearest) are set aside now; the others are counted.
// (Since the discs beside a crease stopped being taken for an open boundary's, fewer are open:
// 0.19 %, still above the promise, and counted.)
TEST(FitSlimHard, ASparseBoxWithoutNormalsCountsItsHoles) {
  Shape s = make(box({0, 0, 0}, {1, 0.6, 0.3}), 2000, 52);
  s.cloud.normals.clear();
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  const SlimFitResult fit = fit_slim(s.cloud, {.max_error = 1e-3});
  const double E = fit.stats.max_error_abs;
  const SurfaceError e = measure_surface_error(fit.model, truth, s.box, {.views = 8, .resolution = 256, .bound = 2 * E});
  std::cerr << "  " << fit.stats.patches << " patches, " << fit.stats.point_holes << " points with a hole, the fit's hole share "
            << fit.stats.hole_share << "; true holes " << e.hole_share << "\n";
  ASSERT_GT(e.hole_share, 1e-4);  // the case: E far below the sampling, holes above the promise
  EXPECT_TRUE(fit.stats.holes_exceeded);
  EXPECT_GT(fit.stats.point_holes, 0u);
}

// A point beside a crease has no neighbour of its own face past it, like a point on an open
// boundary, whose disc stops a quarter of its radius past it: beside a box's corners no disc
// reached the tip, and the fit, true to its discs, left it open (a 20,000-point box without
// normals at 1e-3: 3.7e-4 of the true box's pixels open in front of the discs, 5.4e-4 in front
// of the fit). Where the crease cuts close every side without neighbours it is no boundary; the
// rim of an open box (no top) stays one, its corners too.
TEST(DataSurface, DiscsBesideACreaseReachItsCornersAndAnOpenRimStaysOpen) {
  const Shape s = make(box({0, 0, 0}, {1, 0.6, 0.3}), 20000, 53);
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  const double E = 1e-3 * s.box.diagonal();
  const std::vector<Vec> pca = estimate_normals(s.cloud.points, {}).normals;
  const DataSurface discs = DataSurface::from_points(s.cloud.points, pca, {.crease_points = true});
  const TraceFn front = [&](const Ray& r) -> std::optional<double> {  // as the fit's views see the discs
    double t0 = 0;
    for (int k = 0; k < 64; ++k) {
      const auto h = discs.first_hit(r, t0);
      if (!h) return std::nullopt;
      if (h->front) return h->t;
      t0 = h->t * (1 + 1e-12) + 1e-12;
    }
    return std::nullopt;
  };
  const SurfaceError e = measure_surface_error(front, truth, s.box, {.views = 8, .resolution = 256, .bound = 2 * E});
  // Boundary samples within 0.03 (about two spacings) of the corners.
  std::vector<DataSurface::BoundarySample> near;
  const auto at_corners = [&](const DataSurface& d, int corners, bool crease_sides = false) {
    std::size_t count = 0;
    for (int c = 0; c < 8; ++c)
      if (corners >> c & 1) {
        d.boundary_near(Vec(c & 1 ? 1 : 0, c & 2 ? 0.6 : 0, c & 4 ? 0.3 : 0), 0.03, near, crease_sides);
        count += near.size();
      }
    return count;
  };
  const std::size_t closed = at_corners(discs, 0xff);
  // (Where a patch may stop as at a boundary, the points beside the creases are still asked.)
  EXPECT_GE(at_corners(discs, 0xff, true), 100u);  // 127
  std::cerr << "  the true box's pixels open in front of the discs: " << e.hole_share << "; boundary samples beside its corners: "
            << closed << "\n";
  EXPECT_LE(e.hole_share, 1e-5);  // 0; 4.5e-5 with the points beside the creases taken for a boundary's
  EXPECT_LE(closed, 45u);         // 33; 127

  // An open box: its discs reach no higher past the rim beside its vertical edges than along the
  // rest of the rim, with or without normals. (Where a sector reaching up past the rim was closed
  // by the wall's cut, a rim point beside the edge lost its boundary and its disc ran up along the
  // edge: 0.0355 there against 0.0295 elsewhere in this sampling, 0.012 before; 3.2 spacings
  // against 2.45 in a reviewer's. A sector is closed only by cuts within 60° of each of its rays.)
  std::vector<Sheet> sheets = box({0, 0, 0}, {1, 0.6, 0.3});
  sheets.erase(sheets.begin() + 3);  // the top (y = 0.6)
  const Shape open = make(sheets, 20000, 2);
  for (const bool given : {true, false}) {
    const DataSurface rim = given ? DataSurface::from_points(open.cloud.points, open.cloud.normals)
                                  : DataSurface::from_points(open.cloud.points, estimate_normals(open.cloud.points, {}).normals,
                                                             {.crease_points = true});
    // How high above the rim the discs reach, on the walls' planes, within 0.03 of a vertical
    // edge and elsewhere (steps of 5e-4, about a twentieth of the spacing).
    double at_edges = 0, elsewhere = 0;
    for (int wall = 0; wall < 4; ++wall)
      for (int k = 0; k <= 200; ++k) {
        const double t = k / 200.0, length = wall < 2 ? 1.0 : 0.3;
        const Vec base = wall == 0 ? Vec(t, 0.6, 0) : wall == 1 ? Vec(t, 0.6, 0.3) : wall == 2 ? Vec(0, 0.6, 0.3 * t) : Vec(1, 0.6, 0.3 * t);
        double reach = 0;
        for (int step = 1; step <= 80 && rim.distance(base + Vec(0, step * 5e-4, 0)) < 1e-9; ++step) reach = step * 5e-4;
        double& kept = length * std::min(t, 1 - t) < 0.03 ? at_edges : elsewhere;
        kept = std::max(kept, reach);
      }
    const std::size_t bottom = at_corners(rim, 0b00110011);  // y = 0: closed corners
    std::cerr << "  open box, " << (given ? "given" : "estimated") << " normals: the discs reach " << at_edges
              << " above the rim beside its vertical edges, " << elsewhere
              << " elsewhere; boundary samples beside its closed corners: " << bottom << "\n";
    EXPECT_LE(at_edges, elsewhere);
    EXPECT_LE(elsewhere, 0.016);  // 0.01 (0.76 spacings); 0.0295 without the rim cuts
    EXPECT_LE(bottom, 30u);       // 18; 83
  }
}

// Rim cuts (DataSurface::cut_at_rims): a point just inside an open rim is no boundary point (its
// neighbours surround it), and its whole disc reached past the rim: a flat disc of radius 0.45
// sampled by 5,000 points had its data reach 1.83 spacings past the rim, which a fit within 2E
// of its data may follow. Now the lines where the boundary points' discs end cut it: 0.77. The
// lines must not open the sheet: a square with a round hole, a slot and a five-armed star (concave
// rims, where a line through one boundary point crosses the data beside it) stay covered inside.
// Concave rims (DataSurfaceOptions::hole_rims): a hole's rim points, whose neighbours wrap around
// the hole, were no boundary points, points across the hole or a bay passed for a density step's,
// and discs widened 3/4 of the way to the nearest point across: the data reached 2.9 spacings into
// the hole and 3.4 into the star's bays; now 1.8 and 2.1. The slot, under three spacings wide,
// is still bridged whole (its half-width reads 1.30 spacings before and 1.40 now, as the median
// spacing changes): only its opening inside is checked.
TEST(DataSurface, DiscsStopAtAnOpenRimNotPastIt) {
  // The farthest reach past the rim of the two samplings (given and estimated normals).
  const auto check = [](const char* name, const std::function<double(double, double)>& inside, double max_reach,
                        bool hole_rims = true) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    std::vector<Vec> points, normals;
    while (points.size() < 5000) {
      const double x = u(rng), y = u(rng);
      if (inside(x, y) >= 0) points.emplace_back(x, y, 0), normals.emplace_back(0, 0, 1);
    }
    double farthest = 0;
    for (const bool given : {true, false}) {
      const DataSurface d = given ? DataSurface::from_points(points, normals, {.hole_rims = hole_rims})
                                  : DataSurface::from_points(points, estimate_normals(points, {}).normals,
                                                             {.crease_points = true, .hole_rims = hole_rims});
      std::vector<double> spacing;
      for (std::size_t i = 0; i < points.size(); ++i) spacing.push_back(d.spacing(i));
      std::nth_element(spacing.begin(), spacing.begin() + std::ptrdiff_t(spacing.size() / 2), spacing.end());
      const double sp = spacing[spacing.size() / 2];
      // On a 600² grid over the plane: the farthest covered point outside, and the uncovered
      // points more than half a spacing inside.
      double reach = 0;
      std::size_t deep = 0, open = 0;
      for (int a = 0; a < 600; ++a)
        for (int b = 0; b < 600; ++b) {
          const double x = -0.5 + (a + 0.5) / 600, y = -0.5 + (b + 0.5) / 600, depth = inside(x, y);
          const bool covered = d.distance(Vec(x, y, 0)) < 1e-9;
          if (depth < 0 && covered) reach = std::max(reach, -depth);
          if (depth > 0.5 * sp) ++deep, open += !covered;
        }
      std::cerr << "  " << name << (hole_rims ? "" : " (hole_rims off)") << ", " << (given ? "given" : "estimated")
                << " normals: the discs reach " << reach / sp << " spacings past the rim; " << open << " of " << deep
                << " points deeper inside left open\n";
      EXPECT_LE(reach, max_reach * sp) << name;
      EXPECT_LE(open, 4u) << name;  // 0-3 of 100,000-270,000
      farthest = std::max(farthest, reach / sp);
    }
    return farthest;
  };
  check("disc", [](double x, double y) { return 0.45 - std::hypot(x, y); }, 1.1);  // 0.77; 1.83 without the cuts
  const auto square = [](double x, double y) { return std::min({x + 0.45, 0.45 - x, y + 0.45, 0.45 - y}); };
  const std::function<double(double, double)> hole = [&](double x, double y) { return std::min(square(x, y), std::hypot(x, y) - 0.1); };
  const std::function<double(double, double)> slot = [&](double x, double y) {
    return std::min(square(x, y), std::max(std::abs(x) - 0.02, std::abs(y) - 0.3));
  };
  const std::function<double(double, double)> star = [](double x, double y) {
    return 0.3 + 0.12 * std::cos(5 * std::atan2(y, x)) - std::hypot(x, y);
  };
  constexpr double kAny = std::numeric_limits<double>::infinity();
  check("square with a slot", slot, kAny);
  // The limits on the reach, and on the reach against hole_rims off in the same run.
  for (const auto& [name, shape, limit] : {std::tuple{"square with a hole", hole, 2.1}, std::tuple{"star", star, 2.5}}) {
    const double now = check(name, shape, limit), before = check(name, shape, kAny, false);
    EXPECT_LE(now, 0.7 * before) << name;
  }
}

// A cloud with every point twice (merged scans, a mesh's unwelded vertices) or a stack of copies of
// one point: with hole_rims each place counts once among a point's neighbours. Before, a square
// with a hole, 20,000 points each twice, had 178 boundary samples more than 4 spacings inside
// (596 with the first hole_rims rules, which also took a stack of 30 copies for a hole's rim,
// its spacing 0); each point six times, 19,806, with 5.6e-3 of the inside open. Now exactly twice
// and six times those of the points once.
TEST(DataSurface, CopiesOfAPointCountOnceAmongItsNeighbours) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Vec> points, normals;
  while (points.size() < 10000) {
    const double x = u(rng), y = u(rng);
    if (std::hypot(x, y) > 0.1) points.emplace_back(x, y, 0), normals.emplace_back(0, 0, 1);
  }
  const auto count = [](const std::vector<Vec>& p, const std::vector<Vec>& n, std::size_t& inside, std::size_t& open) {
    const DataSurface d = DataSurface::from_points(p, n);
    std::vector<DataSurface::BoundarySample> edge;
    d.boundary_near(Vec::Zero(), 2.0, edge);
    inside = 0;
    for (const auto& e : edge)  // farther than 0.05 (about 4 spacings) from the square's sides and the hole's rim
      inside += std::min({0.5 - std::abs(e.point.x()), 0.5 - std::abs(e.point.y()), std::hypot(e.point.x(), e.point.y()) - 0.1}) > 0.05;
    open = 0;
    for (int a = 0; a < 200; ++a)
      for (int b = 0; b < 200; ++b) {
        const double x = -0.45 + 0.9 * (a + 0.5) / 200, y = -0.45 + 0.9 * (b + 0.5) / 200;
        if (std::hypot(x, y) > 0.15) open += !(d.distance(Vec(x, y, 0)) < 1e-9);
      }
    return edge.size();
  };
  std::size_t inside1 = 0, open1 = 0;
  const std::size_t once = count(points, normals, inside1, open1);
  for (const int times : {2, 6}) {
    std::vector<Vec> p, n;
    for (int t = 0; t < times; ++t) p.insert(p.end(), points.begin(), points.end()), n.insert(n.end(), normals.begin(), normals.end());
    std::size_t inside = 0, open = 0;
    const std::size_t edge = count(p, n, inside, open);
    std::cerr << "  each point " << times << " times: " << edge << " boundary samples (" << once << " once), " << inside
              << " deep inside (" << inside1 << "), " << open << " grid points open inside (" << open1 << ")\n";
    EXPECT_LE(edge, std::size_t(times * 1.05 * once)) << times;
    EXPECT_LE(inside, std::size_t(times) * inside1 + 2) << times;
    EXPECT_LE(open, open1) << times;
  }
  std::vector<Vec> p = points, n = normals;
  for (int k = 0; k < 30; ++k) p.emplace_back(0.3, 0.3, 0), n.emplace_back(0, 0, 1);
  const DataSurface d = DataSurface::from_points(p, n);
  std::vector<DataSurface::BoundarySample> edge;
  d.boundary_near(Vec(0.3, 0.3, 0), 0.05, edge);
  EXPECT_EQ(edge.size(), 0u) << "a stack of 30 copies of a point taken for a rim";
}

// An open box (no top) fitted at 1e-3 without normals: where its data reached two spacings past
// the rim, the fit stood up to 9.8E past it (in four samplings, p99.9 of the true box's pixels
// 1.9-2.7E, 0.097-0.15 % beyond 2E); with the rim cuts (DataSurface::cut_at_rims) the data stops
// within a spacing of the rim, and the fit with it: 6.0-6.3E, 0.77-1.14E, 0.044-0.052 %.
// The rim's p99.9 moves by ±0.3E from sampling to sampling and with any change in which points
// are boundary points: over 16 further samplings it was 0.77-2.20E (mean 1.21E, 4 over 1.3E)
// before the hole_rims rules (DataSurfaceOptions) and 0.58-1.62E (mean 1.04E, 3 over 1.3E) with
// them, where these four gave 0.77-1.14E and 0.62-1.43E. So the mean over the four is bounded,
// and each sampling more loosely. The whole discs are the data before both (rim cuts and
// hole_rims off): hole_rims alone took one sampling's share beyond 2E from 0.15 % to 0.04 %.
TEST(FitSlimHard, AnOpenBoxStopsAtItsRim) {
  double p999_sum = 0;
  std::vector<Sheet> sheets = box({0, 0, 0}, {1, 0.6, 0.3});
  sheets.erase(sheets.begin() + 3);  // the top (y = 0.6)
  for (const std::uint64_t seed : {2, 3, 4, 5}) {
    Shape s = make(sheets, 20000, seed);
    s.cloud.normals.clear();
    const DataSurface truth = DataSurface::from_mesh(s.mesh);
    std::array<SurfaceError, 2> e;
    double E = 0;
    for (const bool cut : {false, true}) {
      const SlimFitResult fit = fit_slim(s.cloud, {.max_error = 1e-3, .rim_cuts = cut, .hole_rims = cut});
      E = fit.stats.max_error_abs;
      e[cut] = measure_surface_error(fit.model, truth, s.box, {.views = 8, .resolution = 256, .bound = 2 * E});
      std::cerr << "  seed " << seed << (cut ? ", rim cuts: " : ", whole discs: ") << fit.stats.patches
                << " patches; the true box's pixels beyond 2E " << e[cut].share_beyond << ", p99.9 " << e[cut].p999 / E << "E, max "
                << e[cut].max / E << "E, open " << e[cut].hole_share << "\n";
    }
    EXPECT_LE(e[1].p999, 1.6 * E) << seed;
    p999_sum += e[1].p999 / E;
    EXPECT_LT(e[1].share_beyond, 0.8 * e[0].share_beyond) << seed;
    EXPECT_LT(e[1].max, e[0].max) << seed;
    EXPECT_LE(e[1].hole_share, 2e-4) << seed;
  }
  EXPECT_LE(p999_sum / 4, 1.2);  // 0.97E before the hole_rims rules, 1.10E with them
}

// The hole_rims rules (DataSurfaceOptions) beside a concave crease: a prism of stairs (three
// steps, sampled by 20,000 points with their faces' normals) fitted at 1e-3. Where the paired
// sector widening also held beside another sheet, the treads' discs stopped short of the risers
// (the nearer sector was the edge's) and the fit left holes along the concave edges: 3.1e-4 of
// the true stairs' pixels against 8.9e-5 without the rules; and the runs that keep boundary
// points the rules alone made passed through the creases' sides, keeping them beside every edge.
TEST(FitSlimHard, HoleRimsLeaveAConcaveCreaseAsItWas) {
  const std::vector<Eigen::Vector2d> outline = {{0, 0}, {0.6, 0}, {0.6, 0.2}, {0.4, 0.2}, {0.4, 0.4}, {0.2, 0.4}, {0.2, 0.6}, {0, 0.6}};
  PolygonMesh mesh;  // the outline in (y, z), extruded along x over [0, 1], capped
  const int n = int(outline.size());
  for (int s = 0; s < 2; ++s)
    for (const auto& p : outline) mesh.vertices.emplace_back(s, p.x(), p.y());
  for (int i = 1; i + 1 < n; ++i) mesh.add_face(std::vector<int>{0, i + 1, i}), mesh.add_face(std::vector<int>{n, n + i, n + i + 1});
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    mesh.add_face(std::vector<int>{i, j, n + j}), mesh.add_face(std::vector<int>{i, n + j, n + i});
  }
  const PointCloud cloud = sample_faces_uniformly(mesh, 20000, 54);
  const DataSurface truth = DataSurface::from_mesh(mesh);
  Box3 box;
  for (const auto& v : mesh.vertices) box.extend(v);
  std::array<SurfaceError, 2> e;
  double E = 0;
  for (const bool rims : {false, true}) {
    const SlimFitResult fit = fit_slim(cloud, {.max_error = 1e-3, .hole_rims = rims});
    E = fit.stats.max_error_abs;
    e[rims] = measure_surface_error(fit.model, truth, box, {.views = 8, .resolution = 256, .bound = 2 * E});
    std::cerr << "  hole_rims " << rims << ": " << fit.stats.patches << " patches; the true stairs' pixels open " << e[rims].hole_share
              << ", beyond 2E " << e[rims].share_beyond << "\n";
  }
  EXPECT_LE(e[1].hole_share, std::max(1.2 * e[0].hole_share, 2e-5));
  EXPECT_LE(e[1].share_beyond, std::max(1.2 * e[0].share_beyond, 1e-5));
}

// A plate 1 x 1 x 0.05 without normals (5 spacings thick): PCA rounds the normals of the points
// beside its edges; they take their faces' planes, those beside the edges too (where the other
// face shows only as a row along the edge, and where the faces' planes spread to the points
// beside), so the crease cuts stop their discs at the edges.
TEST(DataSurface, CreasePointsOfAThinPlateTakeTheirFacesPlanesBesideTheEdges) {
  const Shape s = make(box({0, 0, 0}, {1, 1, 0.05}), 20000, 52);
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  const double E = 3e-3 * s.box.diagonal();
  const std::vector<Vec> pca = estimate_normals(s.cloud.points, {}).normals;
  const DataSurface with = DataSurface::from_points(s.cloud.points, pca, {.crease_points = true});
  const DataSurface without = DataSurface::from_points(s.cloud.points, pca);
  const double one_degree = std::cos(std::numbers::pi / 180.0);
  std::size_t rounded = 0, faced = 0;
  for (std::size_t i = 0; i < pca.size(); ++i) {
    if (std::abs(pca[i].dot(s.cloud.normals[i])) >= one_degree) continue;
    ++rounded;
    faced += with.normal(i).dot(s.cloud.normals[i]) >= one_degree;
  }
  const SurfaceError a = discs_against(with, truth, s.box, 2 * E), b = discs_against(without, truth, s.box, 2 * E);
  std::cerr << "  PCA normals more than 1° off their face: " << rounded << ", now on it " << faced
            << "; discs beyond 2E of the plate " << a.share_beyond << " (without " << b.share_beyond << ")\n";
  EXPECT_GE(double(faced), 0.95 * double(rounded));  // 0.75 when the faces' planes did not spread
  // 0.13 when the planes do not spread; 0.076 when they spread but the faced points' discs are
  // not cut unless planar by their neighbours' heights; 0.049 with both.
  EXPECT_LE(a.share_beyond, 0.07 * b.share_beyond);
}

// A 30° wedge's knife edge without normals: its faces' normals turn 150°, past the 139° the crease
// points and cuts took for a crease (beyond it, a thin plate's two sides), and the crease points
// left the other face's points out of a point's neighbours (turned past 101.5°: the far side of a
// thin part), so PCA's rounded normals stayed at the edge, their discs uncut: 3.6 % of the wedge
// beyond 2E of the discs at 1e-3, p99.9 19E, max 33E. With knife_cos (faces turned up to 166°)
// the edge's points take their faces' planes and the cuts stop them: 1.8 %, 12E, 21E.
TEST(DataSurface, AKnifeEdgesPointsTakeTheirFacesPlanes) {
  // A shape's discs (20,000 points, PCA normals, crease points) against it, with creases to 139°
  // only (knife_cos = crease_cos: the code before) and with knife edges.
  const auto compare = [](const char* name, const Shape& s) {
    const DataSurface truth = DataSurface::from_mesh(s.mesh);
    const double E = 1e-3 * s.box.diagonal();
    const std::vector<Vec> pca = estimate_normals(s.cloud.points, {}).normals;
    std::array<SurfaceError, 2> e;
    for (const bool knife : {false, true}) {
      DataSurfaceOptions o{.crease_points = true};
      if (!knife) o.knife_cos = o.crease_cos;
      e[knife] = discs_against(DataSurface::from_points(s.cloud.points, pca, o), truth, s.box, 2 * E);
      std::cerr << "  " << name << ", " << (knife ? "knife edges: " : "creases to 139° only: ") << "discs beyond 2E "
                << e[knife].share_beyond << ", p99.9 " << e[knife].p999 / E << "E, max " << e[knife].max / E << "E\n";
    }
    return e;
  };
  const double h = 0.6 * std::tan(std::numbers::pi / 6);
  // Its three sides and two triangular caps ((u, uv) over the triangle: denser towards its
  // right-angled corner).
  const auto cap = [&](double x) {
    return Sheet{[=](double u, double v) { return Vec(x, 0.6 * u * (1 - v), h * u * v); }, 1, 60};
  };
  const std::vector<Sheet> wedge = {quad({0, 0, 0}, {1, 0, 0}, {0, 0.6, 0}), quad({0, 0.6, 0}, {1, 0, 0}, {0, -0.6, h}),
                                    quad({0, 0, 0}, {1, 0, 0}, {0, 0, h}), cap(0), cap(1)};
  const std::array<SurfaceError, 2> e = compare("30° wedge", make(wedge, 20000, 54));
  EXPECT_LT(e[1].share_beyond, 0.7 * e[0].share_beyond);
  EXPECT_LT(e[1].p999, 0.8 * e[0].p999);
  EXPECT_LT(e[1].max, 0.8 * e[0].max);
  // A plate 0.02 thick (about two spacings): its far side's rounded normals, within 166° of a
  // point's, are now neighbours, and its plane, parallel, is no reason to leave the point as it
  // is: 6.5 % → 4.2 % beyond 2E (when it was, 14.6 %: a reviewer's case).
  const std::array<SurfaceError, 2> p = compare("plate 0.02 thick", make(box({0, 0, 0}, {1, 1, 0.02}), 20000, 7));
  EXPECT_LE(p[1].share_beyond, p[0].share_beyond);
}

// The plate fitted at 3e-3. When only its edges' crease points took their planes, the rounded
// discs beside them reached past the edges uncut, and the fit counted slits at the creases where
// the true plate shows no hole: 7-31 in six samplings (mean 19.5, hole share 1e-3, exit 7). Now
// 0-5 (mean 1.7): four of the six keep the 1e-4 promise; this sampling counted 27 before, 0 now.
TEST(FitSlimHard, ThinPlateWithoutNormalsCountsFewSlitsAtItsEdges) {
  const Shape s = make(box({0, 0, 0}, {1, 1, 0.05}), 20000, 52);
  const DataSurface truth = DataSurface::from_mesh(s.mesh);
  PointCloud cloud = s.cloud;
  cloud.normals.clear();
  SlimFitOptions opt;
  opt.max_error = 3e-3;
  const SlimFitResult fit = fit_slim(cloud, opt);
  const double E = fit.stats.max_error_abs;
  const SurfaceError e = measure_surface_error(fit.model, truth, s.box, {.views = 8, .resolution = 256, .bound = 2 * E});
  std::cerr << "  patches " << fit.stats.patches << ", crease gaps " << fit.stats.crease_gaps << ", hole share "
            << fit.stats.hole_share << "; against the plate: p99.9/E " << e.p999 / E << ", max/E " << e.max / E
            << ", beyond 2E " << e.share_beyond << ", holes " << e.hole_share << "\n";
  // (With the faces' planes spread but the old slit check, 6 slits here; with neither, 27.)
  EXPECT_LE(fit.stats.crease_gaps, 3u);
  EXPECT_LE(fit.stats.hole_share, 2 * opt.max_hole_share);
  EXPECT_LE(e.share_beyond, 1e-4);
  EXPECT_LE(e.hole_share, 1e-4);
}

TEST(PolygonMesh, FannedSplitsEachFaceFromItsFirstCorner) {
  PolygonMesh m;
  for (int k = 0; k < 6; ++k) m.vertices.emplace_back(std::cos(k), std::sin(k), 0.1 * k);
  m.add_face(std::vector<int>{0, 1, 2});
  m.add_face(std::vector<int>{0, 2, 3, 4, 5});
  const PolygonMesh t = m.fanned();
  EXPECT_TRUE(t.is_triangles());
  EXPECT_FALSE(m.is_triangles());
  EXPECT_EQ(t.vertices, m.vertices);
  ASSERT_EQ(t.face_count(), 4u);
  const std::vector<int> want{0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5};
  EXPECT_EQ(t.indices, want);
}

}  // namespace
}  // namespace quadrix


