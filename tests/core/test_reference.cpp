// The CPU reference ray caster against analytic truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "core/bounds.h"
#include "core/camera.h"
#include "core/lighting.h"
#include "core/reference.h"
#include "core/slim.h"
#include "core/synth.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// Pixels whose 3×3 neighbourhood is uniformly covered or uniformly empty in `mask`
// (outside the 1-pixel silhouette band).
bool interior(const std::vector<std::uint8_t>& mask, int w, int h, int x, int y) {
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
      if (mask[yy * w + xx] != mask[y * w + x]) return false;
    }
  return true;
}
}  // namespace

TEST(Reference, SphereGlyphMatchesAnalyticImage) {
  const Model m = synth_model("sphere");
  const ReferenceScene scene(m);
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 10, .elevation_deg = 35, .width = 160, .height = 120});
  const ReferenceImage img = render_reference(scene, cam);
  std::vector<std::uint8_t> truth(img.coverage.size());
  int covered = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Ray r = cam.pixel_ray(x + 0.5, y + 0.5);
      const double b = r.dir.dot(r.origin), c = r.origin.squaredNorm() - 1.0;
      const std::size_t i = y * img.width + x;
      truth[i] = b * b - c > 0;
      if (!img.coverage[i]) continue;
      ++covered;
      const double t = -b - std::sqrt(b * b - c);
      EXPECT_NEAR(img.distance[i], t, 1e-5 * t);  // stored as float
      const Vector3d p = r.at(t);
      EXPECT_LT((img.normal[i].cast<double>() - p).norm(), 1e-6);
    }
  int agree = 0, counted = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (interior(truth, img.width, img.height, x, y)) {
        ++counted;
        agree += truth[y * img.width + x] == img.coverage[y * img.width + x];
      }
  EXPECT_EQ(agree, counted);
  EXPECT_GT(covered, 3000);
}

TEST(Reference, SlimSphereBlendIsTheSphere) {
  // Every patch holds the exact unit sphere, so the per-ray blend must reproduce it exactly.
  const Model m = synth_model("slim-sphere", {.count = 300});
  const ReferenceScene scene(m);
  const Camera cam = frame_box(bounds(m), {.width = 96, .height = 96});
  const ReferenceImage img = render_reference(scene, cam);
  int covered = 0, holes = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Ray r = cam.pixel_ray(x + 0.5, y + 0.5);
      const double b = r.dir.dot(r.origin), c = r.origin.squaredNorm() - 1.0;
      const std::size_t i = y * img.width + x;
      // Inside the sphere's silhouette by more than a pixel's worth: must be covered.
      const bool deep = b * b - c > 0.05;
      if (deep && !img.coverage[i]) ++holes;
      if (!img.coverage[i]) continue;
      ++covered;
      const Vector3d p = r.at(img.distance[i]);
      EXPECT_NEAR(p.norm(), 1.0, 1e-6);
      EXPECT_LT((img.normal[i].cast<double>() - p.normalized()).norm(), 1e-5);
    }
  EXPECT_EQ(holes, 0);
  EXPECT_GT(covered, 1000);
}

TEST(Reference, HyperboloidTetsLieOnTheQuadricAndMatchAnalyticHits) {
  for (const char* kind : {"hyperboloid1", "hyperboloid2"}) {
    const Model m = synth_model(kind, {.resolution = 8});
    ASSERT_GT(m.tets.size(), 50u);
    const Quadric q = synth_quadric(kind);
    const ReferenceScene scene(m);
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = 25, .elevation_deg = 15, .width = 120, .height = 120});
    TraceOptions opt;
    opt.cull_backfaces = false;
    int agree = 0, total = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const Ray r = cam.pixel_ray(x + 0.5, y + 0.5);
        const auto hit = scene.trace(r, 0, kInf, opt);
        // Analytic: nearest root inside the cube [−1.5, 1.5]³.
        const auto in_cube = [](const Vector3d& p) { return (p.array().abs() <= 1.5 - 1e-12).all(); };
        Hit h;
        const bool truth = intersect_quadric(q, r, 0, kInf, false, in_cube, h);
        ++total;
        if (hit) {
          EXPECT_LT(q.taubin_distance(hit->point), 1e-9);
        }
        if (truth == hit.has_value() && (!truth || std::abs(hit->t - h.t) < 1e-9 * h.t)) ++agree;
      }
    EXPECT_GE(agree, total * 995 / 1000) << kind;
  }
}

TEST(Reference, FarCameraNarrowFieldOfView) {
  // The unit sphere from 10⁴ sizes away through a narrow field of view: hits stay exact.
  const Model m = synth_model("sphere");
  const ReferenceScene scene(m);
  Camera cam;
  cam.eye = Vector3d(1e4, 3e3, 2e4);
  cam.target = Vector3d::Zero();
  cam.fov_y_deg = 0.007;
  cam.width = cam.height = 64;
  const ReferenceImage img = render_reference(scene, cam);
  int covered = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const std::size_t i = y * 64 + x;
      if (!img.coverage[i]) continue;
      ++covered;
      const Ray r = cam.pixel_ray(x + 0.5, y + 0.5);
      const auto hit = scene.trace(r, 0, kInf, {});
      ASSERT_TRUE(hit);
      EXPECT_NEAR(hit->point.norm(), 1.0, 1e-9);
    }
  EXPECT_GT(covered, 1000);
}

TEST(Reference, BvhAgreesWithBruteForce) {
  const Model m = synth_model("glyphs", {.count = 3000, .seed = 4});
  const ReferenceScene scene(m);
  Model single;
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0, 1);
  const Box3 box = bounds(m);
  for (int i = 0; i < 300; ++i) {
    const Vector3d o = box.centre() + box.diagonal() * Vector3d(u(rng) - 0.5, u(rng) - 0.5, 1.2);
    const Vector3d target = box.min + (box.max - box.min).cwiseProduct(Vector3d(u(rng), u(rng), u(rng)));
    const Ray r{o, (target - o).normalized()};
    const auto hit = scene.trace(r, 0, kInf, {});
    double best = kInf;
    int best_index = -1;
    for (std::size_t g = 0; g < m.glyphs.size(); ++g) {
      single.glyphs = {m.glyphs[g]};
      const auto h = ReferenceScene(single).trace(r, 0, kInf, {});
      if (h && h->t < best) best = h->t, best_index = static_cast<int>(g);
    }
    ASSERT_EQ(hit.has_value(), best_index >= 0) << i;
    if (hit) {
      EXPECT_EQ(hit->index, best_index);
      EXPECT_DOUBLE_EQ(hit->t, best);
    }
  }
}

TEST(Reference, CylinderCapsAndEllipsoidOnSurface) {
  for (const char* kind : {"cylinder", "ellipsoid"}) {
    const Model m = synth_model(kind);
    const Glyph& g = m.glyphs[0];
    const ReferenceScene scene(m);
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = 40, .elevation_deg = 50, .width = 80, .height = 80});
    const ReferenceImage img = render_reference(scene, cam);
    int covered = 0;
    for (int y = 0; y < 80; ++y)
      for (int x = 0; x < 80; ++x) {
        const std::size_t i = y * 80 + x;
        if (!img.coverage[i]) continue;
        ++covered;
        const Vector3d p = cam.pixel_ray(x + 0.5, y + 0.5).at(img.distance[i]);
        if (g.kind == GlyphKind::ellipsoid) {
          EXPECT_NEAR((g.axes.inverse() * p).norm(), 1.0, 1e-5);
        } else {
          const Vector3d a = g.axes.col(0).normalized();
          const double h = g.axes.col(0).norm(), along = p.dot(a), radial = (p - along * a).norm();
          // On the side (radial = r, |along| ≤ h) or on a cap (|along| = h, radial ≤ r).
          const bool side = std::abs(radial - g.radius) < 1e-5 && std::abs(along) <= h + 1e-5;
          const bool cap = std::abs(std::abs(along) - h) < 1e-5 && radial <= g.radius + 1e-5;
          EXPECT_TRUE(side || cap) << radial << " " << along;
        }
      }
    EXPECT_GT(covered, 500) << kind;
  }
}

// The shadow light's view fits the box's corners (none outside, one near the edge) and never
// widens past the bounding sphere; the default map size follows the view's pixel size.
TEST(ShadowLight, FrustumFitsTheBoxAndTheMapFollowsTheView) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1), ext(0.05, 2);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector3d c(3 * u(rng), 3 * u(rng), 3 * u(rng)), h(ext(rng), ext(rng), ext(rng));
    const Box3 box{c - h, c + h};
    const Camera view = frame_box(box, {.azimuth_deg = 180 * u(rng), .elevation_deg = 80 * u(rng), .width = 512, .height = 512});
    const Camera light = shadow_light_camera(view, box, 1024);
    const Eigen::Matrix4d P = light.projection() * light.view();
    double widest = 0;
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d p((k & 1 ? box.max : box.min).x(), (k & 2 ? box.max : box.min).y(),
                              (k & 4 ? box.max : box.min).z());
      const Eigen::Vector4d q = P * p.homogeneous();
      widest = std::max({widest, std::abs(q.x() / q.w()), std::abs(q.y() / q.w())});
      EXPECT_LT(std::abs(q.z() / q.w()), 1.0);
    }
    EXPECT_LT(widest, 1.0) << "a corner outside the light's view";
    EXPECT_GT(widest, 0.95) << "the light's view is not tight";
    EXPECT_LE(light.fov_y_deg, 2.0 * std::asin(1.02 / kShadowLightDistance) * 180.0 / 3.14159265358979 + 1e-9);
    Camera big = view;
    big.width = big.height = 1024;
    const int n = matched_shadow_map_size(view, box), m = matched_shadow_map_size(big, box);
    if (n > 256 && m < 4096) {
      EXPECT_NEAR(double(m) / n, 2.0, 0.01);
    }
  }
}

namespace quadrix {
namespace {

// The rim of a patch (its zero set on its sphere): a tilted plane through the centre meets the
// sphere in a great circle, a sheet curling up (z = 0.6 x² − 0.1) in a lower loop; every sample
// lies on the sphere and on the zero set, they are spaced along the whole loop, and a clip plane
// keeps only its side.
TEST(SlimRim, SamplesLieOnTheSphereAndTheZeroSetAlongTheWholeLoop) {
  const double R = 3.0;
  const auto patch = [&](const Eigen::Vector3d& c, const Quadric& g, ClipPlanes clips = {}) {
    SlimPatch p;
    p.centre = c, p.radius = R, p.local = g, p.clips = clips;
    return p;
  };
  const auto check = [&](const SlimPatch& p, double spacing) {
    std::vector<SlimSurfaceSample> rim;
    sample_slim_rim(p, spacing, rim);
    for (const auto& s : rim) {
      const Eigen::Vector3d u = (s.point - p.centre) / R;
      EXPECT_NEAR(u.norm(), 1.0, 1e-8);
      EXPECT_NEAR(p.local.eval(u), 0.0, 1e-7);
      EXPECT_TRUE(p.clips.keeps(u));
      EXPECT_GT(s.normal.dot(p.local.gradient(u)), 0.0);
    }
    return rim;
  };
  const SlimPatch plane = patch(Eigen::Vector3d(10, -4, 2), Quadric::plane(Eigen::Vector3d(0.3, -0.2, 1.0).normalized(), 0.0));
  const auto circle = check(plane, 0.1);
  EXPECT_GE(circle.size(), std::size_t(2 * std::numbers::pi * R / 0.1));
  // The largest gap between neighbours along the circle is about the spacing.
  double widest = 0;
  for (const auto& a : circle) {
    double nearest = 1e9;
    for (const auto& b : circle)
      if (&a != &b) nearest = std::min(nearest, (a.point - b.point).norm());
    widest = std::max(widest, nearest);
  }
  EXPECT_LT(widest, 0.15);
  // A curled sheet: g = z − 0.6x² + 0.1 (local), its rim below the equator at x = 0.
  const Quadric curl = Quadric::from_coefficients({-0.6, 0, 0, 0, 0, 0, 0, 0, 1, 0.1});
  const auto loop = check(patch(Eigen::Vector3d::Zero(), curl), 0.1);
  EXPECT_GE(loop.size(), 150u);
  // Clipped to x ≥ 0.2: only that part of the loop.
  const SlimPatch half = patch(Eigen::Vector3d::Zero(), curl, ClipPlanes::of(ClipPlane{Eigen::Vector3d(1, 0, 0), -0.2}));
  const auto part = check(half, 0.1);
  EXPECT_GT(part.size(), 20u);
  EXPECT_LT(part.size(), loop.size() / 2);
}

// The rim's shortcuts (closed form for planes, jumps where no root can lie, clipped steps left
// unbisected, bisection then a secant step) find what the plain scan finds: every sign change of
// g between the 48 grid points of each meridian, kept by the clip planes, to 1e-8 of the radius.
TEST(SlimRim, ShortcutsFindWhatThePlainScanFinds) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const auto unit = [&] { return Eigen::Vector3d(U(rng), U(rng), U(rng)).normalized(); };
  const double R = 2.0, spacing = 0.25;
  constexpr double kRho = 1.0 - 1e-9;
  std::size_t total = 0;
  for (int trial = 0; trial < 60; ++trial) {
    SlimPatch p;
    p.centre = Eigen::Vector3d(U(rng), U(rng), U(rng)) * 5.0, p.radius = R;
    if (trial % 3 == 0) {
      p.local = Quadric::plane(unit(), 0.6 * U(rng));  // planes, some off the centre
    } else {
      QuadricCoefficients k;
      for (int i = 0; i < 10; ++i) k[i] = U(rng);
      k[9] *= 0.3;
      p.local = Quadric::from_coefficients(k);
    }
    for (int c = 0; c < trial % 3; ++c) p.clips.add(ClipPlane{unit(), 0.5 * U(rng)});
    std::vector<SlimSurfaceSample> rim;
    sample_slim_rim(p, spacing, rim);
    // The plain scan, in angles, with the same poles and meridians.
    const Eigen::Vector3d g0 = p.local.gradient(Eigen::Vector3d::Zero());
    const Eigen::Vector3d n = g0.normalized(), e1 = n.unitOrthogonal(), e2 = n.cross(e1);
    const int meridians = std::clamp(static_cast<int>(std::ceil(2.0 * std::numbers::pi * R / spacing)), 16, 4096);
    std::vector<Eigen::Vector3d> expected;
    std::size_t near_plane = 0;
    for (int m = 0; m < meridians; ++m) {
      const double phi = 2.0 * std::numbers::pi * m / meridians;
      const Eigen::Vector3d t = std::cos(phi) * e1 + std::sin(phi) * e2;
      const auto at = [&](double th) { return Eigen::Vector3d(kRho * (std::cos(th) * n + std::sin(th) * t)); };
      for (int k = 0; k < 48; ++k) {
        double lo = std::numbers::pi * k / 48, hi = std::numbers::pi * (k + 1) / 48;
        const double glo = p.local.eval(at(lo)), ghi = p.local.eval(at(hi));
        if ((glo < 0) == (ghi < 0)) continue;
        for (int it = 0; it < 60; ++it) {
          const double mid = 0.5 * (lo + hi);
          if ((p.local.eval(at(mid)) < 0) == (glo < 0)) lo = mid;
          else hi = mid;
        }
        const Eigen::Vector3d u = at(0.5 * (lo + hi));
        bool kept = true, close = false;
        for (const ClipPlane& c : p.clips) {
          const double v = c.n.dot(u) + c.d;
          kept &= v >= 0, close |= std::abs(v) < 1e-7;
        }
        if (close) ++near_plane;
        else if (kept) expected.push_back(p.centre + R * u);
      }
    }
    ASSERT_EQ(near_plane, 0u) << "trial " << trial << ": a root on a clip plane; choose another seed";
    ASSERT_EQ(rim.size(), expected.size()) << "trial " << trial;
    for (const auto& x : expected) {
      double best = 1e9;
      for (const auto& s : rim) best = std::min(best, (s.point - x).norm());
      EXPECT_LT(best, 1e-8 * R) << "trial " << trial;
    }
    total += expected.size();
  }
  EXPECT_GT(total, 1000u);  // the trials do cross their spheres
}

}  // namespace
}  // namespace quadrix
