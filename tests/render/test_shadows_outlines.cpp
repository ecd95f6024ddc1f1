// Shadows and outlines ([Sigg06] §5) against the CPU reference: the GL shadow map against shadow
// rays (a tolerance for the map's resolution), the GL outline pass against the same detector on
// the reference's G-buffer, for glyphs, tetrahedron patches, SLIM patches and a volume
// iso-surface; and the detector itself on analytic G-buffers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "convert/volume.h"
#include "core/camera.h"
#include "core/lighting.h"
#include "core/outlines.h"
#include "core/reference.h"
#include "core/shade.h"
#include "core/synth.h"
#include "render/renderer.h"
#include "tests/render/gl_test.h"

using namespace quadrix;

namespace {

constexpr int kSize = 128;

// Several primitive kinds casting shadows on each other.
Model glyph_scene() { return synth_model("glyphs", {.count = 40, .seed = 3}); }

Model tet_scene() {
  Model m = synth_model("hyperboloid1", {.resolution = 6});
  Glyph g;  // a ball between the light and the sheet
  g.kind = GlyphKind::sphere;
  g.centre = Eigen::Vector3d(-0.25, 0.45, 0.55);
  g.radius = 0.22;
  g.colour = Rgb{220, 60, 60};
  m.glyphs.push_back(g);
  return m;
}

Model slim_scene() {
  Model m = synth_model("slim-sphere", {.count = 200});
  Glyph g;
  g.kind = GlyphKind::sphere;
  g.centre = Eigen::Vector3d(-0.8, 1.1, 0.9);
  g.radius = 0.35;
  g.colour = Rgb{60, 60, 220};
  m.glyphs.push_back(g);
  return m;
}

Model volume_scene() {
  VolumeIsoOptions o;
  o.iso = 0.5;
  o.colour = Rgb{200, 190, 160};
  return convert_volume(marschner_lobb_volume(24), o).model;
}

// A smooth iso-surface: three Gaussian blobs merged (no creases; lines belong on silhouettes).
Model blob_volume_scene() {
  Volume v;
  const int n = 28;
  v.dims = {n, n, n};
  v.spacing = Eigen::Vector3d::Constant(2.0 / (n - 1));
  v.origin = Eigen::Vector3d::Constant(-1.0);
  v.values.resize(static_cast<std::size_t>(n) * n * n);
  const Eigen::Vector3d c[3] = {{-0.35, -0.2, 0.0}, {0.35, -0.15, 0.1}, {0.0, 0.35, -0.1}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        double f = 0;
        for (const auto& ci : c) f += std::exp(-(v.position(i, j, k) - ci).squaredNorm() / (2 * 0.3 * 0.3));
        v.values[v.index(i, j, k)] = static_cast<float>(f);
      }
  VolumeIsoOptions o;
  o.iso = 0.5;
  o.colour = Rgb{200, 190, 160};
  return convert_volume(v, o).model;
}

Camera camera_for(const Model& m, int size = kSize) {
  return frame_box(bounds(m), {.azimuth_deg = 35, .elevation_deg = 25, .width = size, .height = size});
}

int channel_sum(const Image8& img, std::size_t i) { return img.rgba[4 * i] + img.rgba[4 * i + 1] + img.rgba[4 * i + 2]; }

bool near_mask(const std::vector<std::uint8_t>& mask, int w, int h, int x, int y, int r) {
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const int xx = x + dx, yy = y + dy;
      if (xx >= 0 && yy >= 0 && xx < w && yy < h && mask[static_cast<std::size_t>(yy) * w + xx]) return true;
    }
  return false;
}

struct ShadowAgreement {
  int compared = 0;     // covered pixels where the key light's share is visible
  int cpu_shadowed = 0;
  int mismatched = 0;   // GL and the shadow rays disagree
  int mismatched_off_boundary = 0;  // ... further than 2 pixels from a reference shadow boundary
};

  struct OutlineAgreement {
    int covered = 0, cpu = 0, gl = 0;
    double gl_near_cpu = 0, cpu_near_gl = 0;  // fraction of each one's pixels within 1 px of the other's
    int interior = 0, interior_lines = 0;     // covered pixels 3+ px inside silhouettes; GL lines there
  };

class ShadowsOutlines : public GlTest {
protected:
  Image8 draw(const Model& m, const Camera& cam, const render::RenderOptions& o) {
    renderer_->set_model(m);
    renderer_->draw(cam, o);
    return renderer_->read_colour();
  }

  // map_size 0: the default, two texels per view pixel.
  ShadowAgreement shadows(const Model& m, int size = kSize, int map_size = 1024) {
    const Camera cam = camera_for(m, size);
    const ReferenceScene scene(m);
    ReferenceRenderOptions with_shadows;
    with_shadows.shadows = true;
    const ReferenceImage ref = render_reference(scene, cam, with_shadows);
    // What the key light adds where lit: the reference shaded fully lit and fully dark.
    ReferenceImage lit = ref, dark = ref;
    std::fill(lit.key_light.begin(), lit.key_light.end(), 1.0f);
    std::fill(dark.key_light.begin(), dark.key_light.end(), 0.0f);
    const Image8 cpu_lit = shade_phong(lit, cam), cpu_dark = shade_phong(dark, cam);
    render::RenderOptions shadowed;
    shadowed.shadows = true;
    shadowed.shadow_map_size = map_size;
    const Image8 gl_plain = draw(m, cam, {}), gl_shadow = draw(m, cam, shadowed);
    const int w = ref.width, h = ref.height;
    std::vector<std::uint8_t> boundary(ref.coverage.size(), 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x + 1 < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        for (const std::size_t j : {i + 1, y + 1 < h ? i + w : i})
          if (ref.coverage[i] && ref.coverage[j] && ref.key_light[i] != ref.key_light[j]) boundary[i] = boundary[j] = 1;
      }
    ShadowAgreement a;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        const int share = channel_sum(cpu_lit, i) - channel_sum(cpu_dark, i);
        if (!ref.coverage[i] || share < 30) continue;
        ++a.compared;
        const bool cpu = ref.key_light[i] == 0.0f;
        const bool gl = channel_sum(gl_plain, i) - channel_sum(gl_shadow, i) > share / 2;
        a.cpu_shadowed += cpu;
        if (cpu != gl) {
          ++a.mismatched;
          a.mismatched_off_boundary += !near_mask(boundary, w, h, x, y, 2);
        }
      }
    std::printf("shadows: %d compared, %d in shadow (rays), %d disagree, %d of them off the boundary\n", a.compared,
                a.cpu_shadowed, a.mismatched, a.mismatched_off_boundary);
    return a;
  }

  OutlineAgreement outlines(const Model& m, render::Shading shading = render::Shading::phong) {
    const Camera cam = camera_for(m);
    const ReferenceScene scene(m);
    const ReferenceImage ref = render_reference(scene, cam);
    const std::vector<std::uint8_t> cpu =
        detect_outlines({.width = ref.width, .height = ref.height, .coverage = ref.coverage.data(),
                         .depth = ref.depth.data(), .normal = ref.normal.data(), .fov_y_deg = cam.fov_y_deg,
                         .scene_radius = ref.scene_radius});
    const Image8 plain = draw(m, cam, {});  // Phong, no lines (NPR draws them always)
    render::RenderOptions outlined;
    outlined.shading = shading;
    outlined.outlines = true;
    const Image8 lined = draw(m, cam, outlined);
    const int w = ref.width, h = ref.height;
    std::vector<std::uint8_t> gl(cpu.size(), 0);
    OutlineAgreement a;
    for (std::size_t i = 0; i < gl.size(); ++i) {
      gl[i] = channel_sum(lined, i) == 0 && channel_sum(plain, i) != 0;
      a.covered += ref.coverage[i];
      a.cpu += cpu[i];
      a.gl += gl[i];
    }
    int gl_ok = 0, cpu_ok = 0;
    std::vector<std::uint8_t> uncovered(ref.coverage.size());
    for (std::size_t i = 0; i < uncovered.size(); ++i) uncovered[i] = !ref.coverage[i];
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        gl_ok += gl[i] && near_mask(cpu, w, h, x, y, 1);
        cpu_ok += cpu[i] && near_mask(gl, w, h, x, y, 1);
        if (ref.coverage[i] && !near_mask(uncovered, w, h, x, y, 3)) {
          ++a.interior;
          a.interior_lines += gl[i];
        }
      }
    a.gl_near_cpu = a.gl ? double(gl_ok) / a.gl : 0;
    a.cpu_near_gl = a.cpu ? double(cpu_ok) / a.cpu : 0;
    std::printf("outlines: %d covered, %d reference, %d GL; %.4f of GL near reference, %.4f of reference near GL; "
                "%d of %d interior pixels on lines\n",
                a.covered, a.cpu, a.gl, a.gl_near_cpu, a.cpu_near_gl, a.interior_lines, a.interior);
    return a;
  }
};

void expect_shadows_agree(const ShadowAgreement& a) {
  EXPECT_GT(a.compared, 1000);
  EXPECT_GT(a.cpu_shadowed, a.compared / 50) << "the scene casts too little shadow to test";
  EXPECT_LT(a.cpu_shadowed, a.compared) << "everything in shadow";
  // The map's resolution moves shadow boundaries by a pixel or two; elsewhere they agree.
  EXPECT_LE(a.mismatched, a.compared / 25);
  EXPECT_LE(a.mismatched_off_boundary, a.compared / 500);
}

void expect_outlines_agree(const OutlineAgreement& a) {
  EXPECT_GT(a.cpu, 100);
  EXPECT_GE(a.gl_near_cpu, 0.98);
  EXPECT_GE(a.cpu_near_gl, 0.98);
}

}  // namespace

TEST_F(ShadowsOutlines, GlyphShadowsMatchShadowRays) { expect_shadows_agree(shadows(glyph_scene())); }
TEST_F(ShadowsOutlines, TetPatchShadowsMatchShadowRays) { expect_shadows_agree(shadows(tet_scene())); }
TEST_F(ShadowsOutlines, SlimShadowsMatchShadowRays) { expect_shadows_agree(shadows(slim_scene())); }
TEST_F(ShadowsOutlines, VolumeShadowsMatchShadowRays) { expect_shadows_agree(shadows(volume_scene())); }
// The default map (two texels per view pixel, fitted to the scene's box) at a view size where
// it is not clamped: the same tolerance as the 8-texel maps above.
TEST_F(ShadowsOutlines, DefaultMapSizeMatchesShadowRays) {
  expect_shadows_agree(shadows(glyph_scene(), 512, 0));
  expect_shadows_agree(shadows(volume_scene(), 512, 0));
}

TEST_F(ShadowsOutlines, GlyphOutlinesMatchReference) { expect_outlines_agree(outlines(glyph_scene())); }
TEST_F(ShadowsOutlines, TetPatchOutlinesMatchReference) { expect_outlines_agree(outlines(tet_scene())); }
TEST_F(ShadowsOutlines, SlimOutlinesMatchReference) { expect_outlines_agree(outlines(slim_scene())); }

// Volume iso-surfaces were almost black under the old NPR outlines: on a smooth one the lines
// stay on its silhouettes, and the wavy Marschner–Lobb surface agrees with the reference.
TEST_F(ShadowsOutlines, VolumeOutlinesAreLegible) {
  const auto a = outlines(blob_volume_scene(), render::Shading::npr);
  expect_outlines_agree(a);
  EXPECT_GT(a.interior, 2000);
  EXPECT_LE(a.interior_lines, a.interior / 100) << "lines inside a smooth surface";
  expect_outlines_agree(outlines(volume_scene(), render::Shading::npr));
}

// The detector on analytic G-buffers: a tilted plane has no lines, a step and a crease have.
TEST(Outlines, PlanesStepsAndCreases) {
  const int w = 64, h = 64;
  Camera cam;
  cam.width = w, cam.height = h;
  const Eigen::Matrix3d R = cam.view().topLeftCorner<3, 3>();
  std::vector<std::uint8_t> cov(w * h, 1);
  std::vector<float> depth(w * h);
  std::vector<Eigen::Vector3f> normal(w * h);
  // The plane n·p = d in eye space, n tilted 70° from the view axis.
  const auto plane = [&](const Eigen::Vector3d& n_eye, double d, int x0, int x1) {
    for (int y = 0; y < h; ++y)
      for (int x = x0; x < x1; ++x) {
        const Eigen::Vector3d dir = R * cam.pixel_ray(x + 0.5, y + 0.5).dir;  // eye space
        const double t = d / n_eye.dot(dir);
        depth[y * w + x] = static_cast<float>(-t * dir.z());
        normal[y * w + x] = (R.transpose() * n_eye).cast<float>();
      }
  };
  const double a = 70.0 * std::numbers::pi / 180.0;
  const Eigen::Vector3d tilted(std::sin(a), 0, std::cos(a));
  plane(tilted, -5.0 * std::cos(a), 0, w);
  const OutlineInput in{.width = w, .height = h, .coverage = cov.data(), .depth = depth.data(),
                        .normal = normal.data(), .fov_y_deg = cam.fov_y_deg, .scene_radius = 1.0};
  auto edges = detect_outlines(in);
  EXPECT_EQ(std::count(edges.begin(), edges.end(), 1), 0) << "a tilted plane";
  // A step: the right half 1 further away (parallel planes).
  plane(tilted, -6.0 * std::cos(a), w / 2, w);
  edges = detect_outlines(in);
  for (int y = 1; y + 1 < h; ++y) EXPECT_TRUE(edges[y * w + w / 2 - 1] || edges[y * w + w / 2]) << "row " << y;
  EXPECT_LE(std::count(edges.begin(), edges.end(), 1), h) << "one pixel wide";
  // A crease: the right half turned by 90° about the line where they meet.
  plane(tilted, -5.0 * std::cos(a), 0, w);
  for (int y = 0; y < h; ++y)
    for (int x = w / 2; x < w; ++x) normal[y * w + x] = (R.transpose() * Eigen::Vector3d(-std::cos(a), 0, std::sin(a))).cast<float>();
  edges = detect_outlines(in);
  for (int y = 0; y < h; ++y) EXPECT_TRUE(edges[y * w + w / 2 - 1] || edges[y * w + w / 2]) << "row " << y;
  EXPECT_EQ(std::count(edges.begin(), edges.end(), 1), h) << "one pixel wide";
}
