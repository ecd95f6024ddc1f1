// Implicit surfaces drawn by adaptive marching points on the GL renderer (OSMesa or EGL)
// against the CPU reference's guaranteed interval root isolation, at 128².
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include <unistd.h>

#include "core/camera.h"
#include "core/implicit/gallery.h"
#include "core/implicit/march.h"
#include "core/model_io.h"
#include "core/primitive.h"
#include "core/reference.h"
#include "core/synth.h"
#include "render/context.h"
#include "render/passes/implicit_pass.h"
#include "render/renderer.h"
#include "tests/render/gl_test.h"

using namespace quadrix;

namespace {

struct Agreement {
  double coverage = 1;  ///< of pixels either image covers, outside the reference's 1-px silhouette band
  double depth = 1;     ///< of pixels both cover there: |Δdepth| ≤ 1e-4 of the reference's depth range
  int covered = 0;      ///< pixels the reference covers
};

bool near_silhouette(const ReferenceImage& r, int x, int y) {
  const auto at = [&](int xx, int yy) {
    xx = std::clamp(xx, 0, r.width - 1), yy = std::clamp(yy, 0, r.height - 1);
    return std::pair(r.coverage[yy * r.width + xx], r.primitive[yy * r.width + xx]);
  };
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (at(x + dx, y + dy) != at(x, y)) return true;
  // Depth discontinuities inside one surface (an inner silhouette) are bands too.
  const float d = r.depth[y * r.width + x];
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int xx = std::clamp(x + dx, 0, r.width - 1), yy = std::clamp(y + dy, 0, r.height - 1);
      if (std::abs(r.depth[yy * r.width + xx] - d) > 0.02f * std::abs(d)) return true;
    }
  return false;
}

Agreement agreement(const ReferenceImage& ref, const render::GBuffer& gl) {
  Agreement a;
  float dmin = INFINITY, dmax = -INFINITY;
  for (std::size_t i = 0; i < ref.depth.size(); ++i)
    if (ref.coverage[i]) dmin = std::min(dmin, ref.depth[i]), dmax = std::max(dmax, ref.depth[i]);
  const double range = std::max(1e-30, double(dmax) - dmin);
  int either = 0, same = 0, both = 0, close = 0;
  for (int y = 0; y < ref.height; ++y)
    for (int x = 0; x < ref.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * ref.width + x;
      a.covered += ref.coverage[i];
      if (near_silhouette(ref, x, y) || !(ref.coverage[i] || gl.coverage[i])) continue;
      ++either;
      same += ref.coverage[i] == gl.coverage[i];
      if (!(ref.coverage[i] && gl.coverage[i])) continue;
      ++both;
      close += std::abs(double(gl.depth[i]) - ref.depth[i]) <= 1e-4 * range;
    }
  if (either) a.coverage = double(same) / either;
  if (both) a.depth = double(close) / both;
  return a;
}

class GlImplicit : public GlTest {
protected:
  Agreement run(const Model& m, const Camera& cam, const render::AmpOptions& amp, const std::string& what) {
    renderer_->set_model(m, amp);
    const auto t0 = std::chrono::steady_clock::now();
    renderer_->draw(cam, {});
    const auto t1 = std::chrono::steady_clock::now();
    const ReferenceScene scene(m);
    const ReferenceImage ref = render_reference(scene, cam);
    const auto t2 = std::chrono::steady_clock::now();
    const Agreement a = agreement(ref, renderer_->read_gbuffer());
    const auto ms = [](auto d) { return std::chrono::duration<double, std::milli>(d).count(); };
    // GL marches in float, the reference isolates roots in double: their disagreement per surface.
    std::printf("%-22s float vs double: coverage %.5f depth %.5f covered %5d  gl %.0f ms (compile %.0f ms) reference %.0f ms\n",
                what.c_str(), a.coverage, a.depth, a.covered, ms(t1 - t0), renderer_->implicit_compile_ms(),
                ms(t2 - t1));
    return a;
  }
};

void expect_agree(const Agreement& a, int min_covered) {
  EXPECT_GT(a.covered, min_covered);
  EXPECT_GE(a.coverage, 0.995);
  EXPECT_GE(a.depth, 0.995);
}

[[maybe_unused]] std::string fmt_sphere(const Eigen::Vector3d& c, double r) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "(x - %.17g)^2 + (y - %.17g)^2 + (z - %.17g)^2 - %.17g", c.x(), c.y(), c.z(), r * r);
  return buf;
}

// The expression with x, y, z replaced by (x − cx), (y − cy), (z − cz).
[[maybe_unused]] std::string moved(const std::string& e) {
  std::string out;
  for (std::size_t i = 0; i < e.size();) {
    if (std::isalpha(static_cast<unsigned char>(e[i])) || e[i] == '_') {
      std::size_t j = i;
      while (j < e.size() && (std::isalnum(static_cast<unsigned char>(e[j])) || e[j] == '_')) ++j;
      const std::string id = e.substr(i, j - i);
      out += id == "x" || id == "y" || id == "z" ? "(" + id + " - c" + id + ")" : id;
      i = j;
    } else {
      out += e[i++];
    }
  }
  return out;
}

Camera view(const Box3& box, double azimuth, double elevation) {
  return frame_box(box, {.azimuth_deg = azimuth, .elevation_deg = elevation, .width = 128, .height = 128});
}

render::AmpOptions amp_for(const implicit::GalleryEntry& g) {
  render::AmpOptions o;
  o.test = g.test == "taylor" ? render::RootTest::taylor : render::RootTest::sign;
  return o;
}

}  // namespace

// The CPU march (the shader's maths in double) against the guaranteed first root on Chmutov 50,
// whose sheets near the cube's faces come in pairs 0.001–0.01 apart while |S| ≈ 2 allows the
// doubled step 2b ≈ 0.017: without the remainder test a step holds both roots of a pair.
TEST(AmpMarch, RemainderTestKeepsChmutovFiftysFirstSheet) {
  for (const char* name : {"chmutov-iter-50", "chmutov-trig-50"}) {
    const implicit::GalleryEntry g = implicit::gallery_surface(name);
    const implicit::CompiledImplicit c = implicit::compile(g.surface);
    const render::AmpOptions defaults = amp_for(g);
    render::AmpOptions off = defaults;
    off.remainder = 0;
    const implicit::MarchSettings with = render::amp_settings(g.surface, defaults);
    const implicit::MarchSettings plain = render::amp_settings(g.surface, off);
    int rays = 0, good_on = 0, good_off = 0;
    long steps_on = 0, steps_off = 0;
    for (const auto& [az, el] : {std::pair(30.0, 20.0), std::pair(250.0, 60.0)}) {
      const Camera cam = frame_box(g.surface.bounds, {.azimuth_deg = az, .elevation_deg = el, .width = 64, .height = 64});
      for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
          const Ray ray = cam.pixel_ray(x + 0.5, y + 0.5);
          const double tmin = cam.near_plane / ray.dir.dot(cam.forward());
          const auto truth = implicit::first_root(c, ray, tmin, INFINITY);
          if (!truth) continue;
          ++rays;
          const auto on = implicit::march_first_root(c, ray, tmin, INFINITY, with);
          const auto without = implicit::march_first_root(c, ray, tmin, INFINITY, plain);
          steps_on += on.steps, steps_off += without.steps;
          good_on += on.t && std::abs(*on.t - truth->t) < 1e-4;
          good_off += without.t && std::abs(*without.t - truth->t) < 1e-4;
        }
    }
    const double on = double(good_on) / rays, without = double(good_off) / rays;
    std::printf("%s: %d rays, first root found %.5f with the remainder test (%ld steps), %.5f without (%ld steps)\n",
                name, rays, on, steps_on, without, steps_off);
    EXPECT_GT(rays, 3000);
    EXPECT_GE(on, 0.999);
    EXPECT_LT(without, on);  // the test matters here
    EXPECT_LT(steps_on, 1.1 * steps_off);  // and costs little
  }
}

#ifdef QUADRIX_IMPLICIT_STRESS
// The whole gallery from three views (label slow).
TEST_F(GlImplicit, EveryGallerySurfaceMatchesTheReference) {
  for (const auto& g : implicit::gallery()) {
    Model m;
    m.implicits.push_back(g.surface);
    for (const auto& [az, el] : {std::pair(30.0, 20.0), std::pair(125.0, -35.0), std::pair(250.0, 60.0)}) {
      SCOPED_TRACE(testing::Message() << g.name << " azimuth " << az << " elevation " << el);
      // Chmutov 50 included: its close sheets near the cube's faces need the remainder test.
      expect_agree(run(m, view(g.surface.bounds, az, el), amp_for(g), g.name), 500);
    }
  }
}

// Gallery surfaces moved far from the origin (25–70 times their size; the GL side works in
// float) and made very thin (tubes and slabs 1 % of their extent), from two views each.
TEST_F(GlImplicit, FarAndThinGallerySurfacesMatchTheReference) {
  std::vector<std::pair<std::string, ImplicitSurface>> cases;
  const Eigen::Vector3d far(60, -40, 25);
  for (const char* name : {"torus", "goursat", "barth-sextic", "superquadric", "chmutov-iter-14"}) {
    const implicit::GalleryEntry g = implicit::gallery_surface(name);
    ImplicitSurface s = g.surface;
    s.expression = moved(s.expression);
    s.parameters.insert({{"cx", far.x()}, {"cy", far.y()}, {"cz", far.z()}});
    s.bounds = {s.bounds.min + far, s.bounds.max + far};
    cases.push_back({std::string(name) + " at (60, -40, 25)", s});
  }
  const Box3 unit{Eigen::Vector3d(-1.1, -1.1, -0.02), Eigen::Vector3d(1.1, 1.1, 0.02)};
  cases.push_back({"torus tube 0.01", {"(x^2 + y^2 + z^2 + 1 - r^2)^2 - 4*(x^2 + y^2)", {{"r", 0.01}},
                                       {Eigen::Vector3d(-1.1, -1.1, -0.011), Eigen::Vector3d(1.1, 1.1, 0.011)}, {}}});
  cases.push_back({"slab 0.02", {"x^4 + y^4 + (z/0.01)^4 - 1", {}, unit, {}}});
  for (const auto& [what, s] : cases) {
    Model m;
    m.implicits.push_back(s);
    render::AmpOptions o;
    o.step_divisions = 2000;
    for (const auto& [az, el] : {std::pair(30.0, 40.0), std::pair(200.0, 70.0)}) {
      SCOPED_TRACE(testing::Message() << what << " azimuth " << az << " elevation " << el);
      expect_agree(run(m, view(s.bounds, az, el), o, what), 100);  // the 0.01 tube covers ~130 px
    }
  }
}
#else
// A sample of the gallery, one view each, every order and kind of form represented.
TEST_F(GlImplicit, GallerySampleMatchesTheReference) {
  for (const char* name : {"ding-dong", "torus", "cross-cap", "steiner", "barth-sextic", "heart", "endrass",
                           "barth-decic", "chmutov-iter-14", "chmutov-iter-50", "superquadric", "blinn-8", "diamond",
                           "scherk"}) {
    const implicit::GalleryEntry g = implicit::gallery_surface(name);
    Model m;
    m.implicits.push_back(g.surface);
    SCOPED_TRACE(name);
    expect_agree(run(m, view(g.surface.bounds, 40, 25), amp_for(g), g.name), 500);
  }
}

// The comparison is not blind: a base step of a quarter of the bounds misses most of the Barth decic.
TEST_F(GlImplicit, CoarseStepsAreCaught) {
  const implicit::GalleryEntry g = implicit::gallery_surface("barth-decic");
  Model m;
  m.implicits.push_back(g.surface);
  render::AmpOptions o;
  o.step_divisions = 4;
  o.newton_fraction = 0;
  const Agreement a = run(m, view(g.surface.bounds, 40, 25), o, "barth-decic b = d/4");
  EXPECT_LT(std::min(a.coverage, a.depth), 0.9);
}

// An implicit sphere and a tetrahedron-patch model overlapping: each pixel shows the nearer.
TEST_F(GlImplicit, MixesDepthCorrectWithQuadricPatches) {
  Model m = synth_model("hyperboloid1", {.resolution = 6});
  const Box3 b = bounds(m);
  const Eigen::Vector3d c = b.centre() + Eigen::Vector3d(0.15, 0, 0.15) * b.diagonal();
  const double r = 0.1 * b.diagonal();
  m.implicits.push_back({fmt_sphere(c, r), {}, {c.array() - r * 1.01, c.array() + r * 1.01}, Rgb{200, 80, 80}});
  const Camera cam = view(bounds(m), 20, 15);
  renderer_->set_model(m);
  renderer_->draw(cam, {});
  const render::GBuffer gl = renderer_->read_gbuffer();
  const ReferenceImage ref = render_reference(ReferenceScene(m), cam);
  int kinds = 0, agree = 0, implicit_pixels = 0;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      const std::size_t i = y * 128 + x;
      if (!ref.coverage[i] || near_silhouette(ref, x, y)) continue;
      ++kinds;
      agree += primitive_kind(gl.primitive[i]) == primitive_kind(ref.primitive[i]);
      implicit_pixels += primitive_kind(ref.primitive[i]) == PrimitiveKind::implicit;
    }
  EXPECT_GT(implicit_pixels, 50);
  EXPECT_GT(kinds - implicit_pixels, 50);  // both kinds visible
  std::printf("mixed: %d pixels, %d implicit, kind agreement %.5f\n", kinds, implicit_pixels, double(agree) / kinds);
  EXPECT_GE(double(agree) / kinds, 0.995);
}

// Every kind in one .qxm file: tetrahedron patches, a glyph, SLIM patches and an implicit torus
// crossing them, written and read back, drawn by GL and by the CPU reference: the same kind,
// coverage and depth at each pixel.
TEST_F(GlImplicit, ModelFileMixesImplicitsWithEveryKind) {
  Model m = synth_model("hyperboloid1", {.resolution = 5});
  m.glyphs.push_back({GlyphKind::sphere, {1.1, 0.2, 1.1}, 0.55, Eigen::Matrix3d::Identity(), Rgb{90, 90, 220}});
  for (SlimPatch s : synth_model("slim-sphere", {.count = 120}).slims) {
    s.centre += Eigen::Vector3d(-1.3, 0.3, 1.0);
    m.slims.push_back(s);
  }
  m.implicits.push_back({"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + z^2)", {{"r", 0.3}, {"R", 1.4}},
                         {Eigen::Vector3d(-1.75, -0.35, -1.75), Eigen::Vector3d(1.75, 0.35, 1.75)}, Rgb{200, 80, 80}});
  const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                     ("quadrix-mixed-" + std::to_string(::getpid()) + ".qxm");
  write_model(m, file);
  const Model r = read_model(file);
  std::filesystem::remove(file);
  ASSERT_EQ(r.implicits.size(), 1u);
  const Camera cam = view(bounds(r), 30, 35);
  const Agreement a = run(r, cam, {}, "mixed .qxm");
  expect_agree(a, 3000);
  const render::GBuffer gl = renderer_->read_gbuffer();
  const ReferenceImage ref = render_reference(ReferenceScene(r), cam);
  std::map<PrimitiveKind, int> seen;
  int pixels = 0, agree = 0;
  // Kind boundaries (not every patch's edge) make the band here.
  const auto kind_at = [&](int x, int y) {
    x = std::clamp(x, 0, 127), y = std::clamp(y, 0, 127);
    return ref.coverage[y * 128 + x] ? primitive_kind(ref.primitive[y * 128 + x]) : PrimitiveKind::none;
  };
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      const std::size_t i = y * 128 + x;
      bool band = !ref.coverage[i];
      for (int d = 0; d < 9; ++d) band = band || kind_at(x + d % 3 - 1, y + d / 3 - 1) != kind_at(x, y);
      if (band) continue;
      ++pixels;
      ++seen[primitive_kind(ref.primitive[i])];
      agree += primitive_kind(gl.primitive[i]) == primitive_kind(ref.primitive[i]);
    }
  for (PrimitiveKind k : {PrimitiveKind::tet, PrimitiveKind::glyph, PrimitiveKind::slim, PrimitiveKind::implicit})
    EXPECT_GT(seen[k], 100) << "kind " << static_cast<int>(k) << " barely visible";
  std::printf("mixed .qxm: %d pixels (tet %d glyph %d slim %d implicit %d), kind agreement %.5f\n", pixels,
              seen[PrimitiveKind::tet], seen[PrimitiveKind::glyph], seen[PrimitiveKind::slim],
              seen[PrimitiveKind::implicit], double(agree) / pixels);
  EXPECT_GE(double(agree) / pixels, 0.995);
}

// Far from the origin and very thin: a torus tube of radius 0.02 around (40, −25, 30).
TEST_F(GlImplicit, FarAndThinSurfaces) {
  const Eigen::Vector3d c(40, -25, 30);
  Model m;
  m.implicits.push_back({"((x - cx)^2 + (y - cy)^2 + (z - cz)^2 + 1 - r^2)^2 - 4*((x - cx)^2 + (y - cy)^2)",
                         {{"cx", c.x()}, {"cy", c.y()}, {"cz", c.z()}, {"r", 0.02}},
                         {c - Eigen::Vector3d(1.1, 1.1, 0.1), c + Eigen::Vector3d(1.1, 1.1, 0.1)},
                         {}});
  render::AmpOptions o;
  o.step_divisions = 2000;
  expect_agree(run(m, view(m.implicits[0].bounds, 10, 50), o, "thin far torus"), 150);
}

// 10⁴ and 10⁶ of their diagonals from the world's origin, the centre written into the expression
// as literal numbers: float world coordinates keep none of (x − 3.7e6)'s digits near 3.7e6, so
// such surfaces are marched about their bounds' centre and evaluated in double (render/passes/
// implicit_pass.h). A torus, and a sphere rippled by sin (a float-only function in GLSL) of a
// difference that must be taken in double first.
TEST_F(GlImplicit, FarFromTheWorldsOriginMatchesTheReference) {
  const Eigen::Vector3d dir = Eigen::Vector3d(1.0, -0.6, 0.4).normalized();
  for (const double diagonals : {1e4, 1e6}) {
    struct Case {
      std::string what, expression;
      Eigen::Vector3d half;
    };
    const Eigen::Vector3d half_torus(1.35, 1.35, 0.35), half_ripple(1.1, 1.1, 1.1);
    const Eigen::Vector3d c = diagonals * 2.0 * half_torus.norm() * dir;
    const auto sq = [&](const char* v, double cv) { return fmt::format("({} - {:.17g})^2", v, cv); };
    const std::string r2 = sq("x", c.x()) + " + " + sq("y", c.y()) + " + " + sq("z", c.z());
    const std::vector<Case> cases = {
        {"torus", fmt::format("({} + 1 - 0.09)^2 - 4*({} + {})", r2, sq("x", c.x()), sq("y", c.y())), half_torus},
        {"rippled sphere", fmt::format("{} - 1 + 0.05*sin(12*(x - {:.17g}))", r2, c.x()), half_ripple},
    };
    for (const Case& k : cases) {
      Model m;
      m.implicits.push_back({k.expression, {}, {c - k.half, c + k.half}, {}});
      ASSERT_GT(c.cwiseAbs().maxCoeff(), render::kImplicitFarFactor * m.implicits[0].bounds.diagonal());
      render::AmpOptions o;
      o.step_divisions = 400;
      for (const auto& [az, el] : {std::pair(30.0, 40.0), std::pair(200.0, -25.0)}) {
        const std::string what = fmt::format("{} at {:g} diagonals", k.what, diagonals);
        SCOPED_TRACE(testing::Message() << what << " azimuth " << az << " elevation " << el);
        expect_agree(run(m, view(m.implicits[0].bounds, az, el), o, what), 2000);
      }
    }
  }
  // Every kind of operation on the double path (abs and a real power, sqrt, cheb, exp and cos),
  // the centre as parameters (double uniforms there), 10⁴ diagonals out.
  for (const char* name : {"superquadric", "torus-sqrt", "chmutov-iter-14", "scherk"}) {
    const implicit::GalleryEntry g = implicit::gallery_surface(name);
    ImplicitSurface s = g.surface;
    const Eigen::Vector3d c = 1e4 * s.bounds.diagonal() * dir;
    s.expression = moved(s.expression);
    s.parameters.insert({{"cx", c.x()}, {"cy", c.y()}, {"cz", c.z()}});
    s.bounds = {s.bounds.min + c, s.bounds.max + c};
    Model m;
    m.implicits.push_back(s);
    const std::string what = std::string(name) + " at 1e4 diagonals";
    SCOPED_TRACE(what);
    expect_agree(run(m, view(s.bounds, 40, 25), amp_for(g), what), 500);
  }
}
#endif
