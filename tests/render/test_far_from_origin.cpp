// Relative-to-eye rendering: tetrahedron patches (per-chunk origins), SLIM patches and glyphs
// (one fixed-point origin per model: render/passes/frame.h FixedOrigin) and meshes, moved 10⁴ and
// 10⁶ of its diagonals from the origin with the camera framed on it, renders as the CPU reference (double) does: depth p99
// ≤ 1e-5 of the depth range, normals p99 ≤ 0.1°, coverage agreement ≥ 99.9 % away from the
// silhouette. Meshes (not in the CPU reference) against their own render at the origin.
// Primitives 10⁻⁴ of their scene, far from the scene's origin and 10⁶ scene diagonals from the
// world's, the camera close to them: the same goals over every pixel, the silhouette's (where
// rays graze the surface) included, and flat ones seen 3° above their plane, where most rays
// graze: the goals on the grazing pixels by themselves.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "convert/quads.h"
#include "core/reference.h"
#include "core/synth.h"
#include "tests/render/gl_compare.h"
#include "tests/render/gl_test.h"
#include "tests/render/random_models.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {

Model translated(Model m, const Vector3d& t) {
  for (auto& s : m.slims) s.centre += t;
  for (auto& p : m.tets)
    for (auto& c : p.corners) c += t;  // the quadric is relative to the centroid: unchanged
  for (auto& g : m.glyphs) g.centre += t;
  return m;
}

Model model_of(const std::string& kind) {
  if (kind == "quad-blob") {
    std::mt19937_64 rng(3);
    return convert_quads(test::random_quad_blob(rng, 6)).model;
  }
  return synth_model(kind, {.resolution = 8});
}

class FarFromOrigin : public GlTest, public ::testing::WithParamInterface<std::string> {};

}  // namespace

namespace {

// x → s·x + t for every primitive (a tetrahedron's quadric, relative to its centroid, scaled).
Model scaled(const Model& m, double s, const Vector3d& t) {
  Model out = m;
  for (auto& p : out.slims) p.centre = s * p.centre + t, p.radius *= s;  // the local quadric is in units of R
  for (auto& p : out.tets) {
    for (auto& c : p.corners) c = s * c + t;
    p.quadric = p.quadric.from_local(Vector3d::Zero(), s).normalized();
  }
  for (auto& g : out.glyphs) g.centre = s * g.centre + t, g.radius *= s, g.axes *= s;
  return out;
}

Model joined(Model a, const Model& b) {
  a.slims.insert(a.slims.end(), b.slims.begin(), b.slims.end());
  a.tets.insert(a.tets.end(), b.tets.begin(), b.tets.end());
  a.glyphs.insert(a.glyphs.end(), b.glyphs.begin(), b.glyphs.end());
  return a;
}

// GL against the reference over every pixel, the 1-pixel silhouette band included.
struct EveryPixel {
  int foreground = 0;         // pixels the reference covers
  int mismatched = 0;         // pixels covered by one image only
  int grazing = 0;            // covered by both, the ray within 6° of the tangent plane (|n·d| < 0.1)
  double depth_p99 = 0;       // of the reference's depth range
  double normal_p99_deg = 0;
  double grazing_depth_max = 0, grazing_normal_max_deg = 0;
  double grazing_depth_p99 = 0, grazing_normal_p99_deg = 0;
};

EveryPixel compare_every_pixel(const ReferenceImage& ref, const render::GBuffer& gl, const Camera& cam) {
  EveryPixel e;
  float lo = INFINITY, hi = -INFINITY;
  for (std::size_t i = 0; i < ref.depth.size(); ++i)
    if (ref.coverage[i]) lo = std::min(lo, ref.depth[i]), hi = std::max(hi, ref.depth[i]);
  std::vector<double> depth, normal, grazing_depth, grazing_normal;
  for (int y = 0; y < ref.height; ++y)
    for (int x = 0; x < ref.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * ref.width + x;
      e.foreground += ref.coverage[i];
      e.mismatched += ref.coverage[i] != gl.coverage[i];
      if (!(ref.coverage[i] && gl.coverage[i])) continue;
      const double d = std::abs(double(gl.depth[i]) - ref.depth[i]) / (hi - lo);
      const double n = std::acos(std::clamp(double(gl.normal[i].normalized().dot(ref.normal[i])), -1.0, 1.0)) * 180 /
                       std::numbers::pi;
      depth.push_back(d), normal.push_back(n);
      if (std::abs(ref.normal[i].cast<double>().dot(cam.pixel_ray(x + 0.5, y + 0.5).dir)) < 0.1) {
        ++e.grazing;
        e.grazing_depth_max = std::max(e.grazing_depth_max, d);
        e.grazing_normal_max_deg = std::max(e.grazing_normal_max_deg, n);
        grazing_depth.push_back(d), grazing_normal.push_back(n);
      }
    }
  const auto p99 = [](std::vector<double>& v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() * 99 / 100];
  };
  e.depth_p99 = p99(depth), e.normal_p99_deg = p99(normal);
  e.grazing_depth_p99 = p99(grazing_depth), e.grazing_normal_p99_deg = p99(grazing_normal);
  return e;
}

// `unit` scaled to 1e-4 of the scene's diagonal, 0.4 diagonals from the scene's centre, k scene
// diagonals from the world's origin, seen through `view` framed on it; the rest of the scene (the
// same primitives, 3000 times larger) behind the eye. GL against the reference over every pixel,
// and the reference there against the reference of the same view at the origin (the truth's own error).
struct TinyFar {
  EveryPixel gl, truth;
  double scene = 0;
};

TinyFar tiny_far(render::Renderer& renderer, const Model& unit, double k, const FramingOptions& view) {
  const double d0 = bounds(unit).diagonal();
  const Vector3d place(0.25, -0.2, 0.2);
  const Vector3d far = k * Vector3d(0.6, -0.48, 0.64);  // the scene's diagonal is about 0.65
  const Model tiny = scaled(unit, 1e-4 / d0, far + place);
  const Camera cam = frame_box(bounds(tiny), view);
  const Vector3d back = (cam.eye - cam.target).normalized();
  const Model m = joined(tiny, scaled(unit, 0.3 / d0, cam.target + 0.5 * back));
  TinyFar r;
  r.scene = bounds(m).diagonal();
  renderer.set_model(m);
  renderer.draw(cam, {});
  const ReferenceImage ref = render_reference(ReferenceScene(m), cam);
  r.gl = compare_every_pixel(ref, renderer.read_gbuffer(), cam);
  Camera c0 = cam;
  c0.eye -= far, c0.target -= far;
  const ReferenceImage r0 = render_reference(ReferenceScene(scaled(unit, 1e-4 / d0, place)), c0);
  render::GBuffer as_gl;
  as_gl.width = ref.width, as_gl.height = ref.height;
  as_gl.coverage = ref.coverage, as_gl.depth = ref.depth;
  for (const auto& n : ref.normal) as_gl.normal.push_back(n);
  r.truth = compare_every_pixel(r0, as_gl, c0);
  return r;
}

void print(const std::string& kind, double k, const TinyFar& t) {
  const EveryPixel& e = t.gl;
  std::printf("%-10s reference at %.0e against the origin's: %d mismatched, depth p99 %.2e, normal p99 %.4f deg\n",
              kind.c_str(), k, t.truth.mismatched, t.truth.depth_p99, t.truth.normal_p99_deg);
  std::printf("%-10s 1e-4 of a %.2f scene, %.0e from the origin: %d px, %d mismatched (%.3f %%), depth p99 %.2e, "
              "normal p99 %.4f deg; %d grazing px: depth p99 %.2e max %.2e, normal p99 %.3f max %.3f deg\n",
              kind.c_str(), t.scene, k, e.foreground, e.mismatched, 100.0 * e.mismatched / std::max(1, e.foreground),
              e.depth_p99, e.normal_p99_deg, e.grazing, e.grazing_depth_p99, e.grazing_depth_max,
              e.grazing_normal_p99_deg, e.grazing_normal_max_deg);
}

class TinyFarPrimitives : public GlTest, public ::testing::WithParamInterface<std::string> {};

}  // namespace

// The primitives of one kind, 10⁻⁴ of the scene's diagonal, 0.4 diagonals from the scene's centre
// (the renderer's origin for SLIM balls and glyphs: a float hi + lo split of the offsets left the
// SLIM balls and the 1,000-glyph set at depth p99 3e-3 and 6e-4, as llvmpipe reorders float sums;
// render/passes/frame.h FixedOrigin) and 10⁴ and 10⁶ diagonals from the world's origin; the camera
// framed on them. At 10⁶ the primitives sit 10¹⁰ of their size from the origin, where double itself
// resolves 1e-6 of them: the reference there is measured against the reference at the origin first
// (a sphere's depth p99 1.7e-5), and GL may miss the goal by that much.
TEST_P(TinyFarPrimitives, MatchTheCpuReferenceOnEveryPixel) {
  const std::string kind = GetParam();
  const Model unit = kind == "tets" ? synth_model("hyperboloid1", {.resolution = 8}) : synth_model(kind, {});
  ASSERT_FALSE(unit.empty());
  for (const double k : {1e4, 1e6}) {
    SCOPED_TRACE(testing::Message() << kind << " at " << k << " diagonals");
    const TinyFar t = tiny_far(*renderer_, unit, k, {.azimuth_deg = 35, .elevation_deg = 25, .width = 200, .height = 200});
    print(kind, k, t);
    ASSERT_GT(t.scene, 0.5);
    EXPECT_LE(t.truth.mismatched, 0.001 * t.truth.foreground);
    EXPECT_LE(t.truth.depth_p99, k < 1e5 ? 1e-6 : 1e-4);
    const EveryPixel& e = t.gl;
    EXPECT_GT(e.foreground, 3000);
    EXPECT_GT(e.grazing, 20) << "no grazing rays: the case tests nothing of them";
    EXPECT_LE(e.mismatched, 0.001 * e.foreground);
    EXPECT_LE(e.depth_p99, 1e-5 + t.truth.depth_p99);  // at 10⁶, beyond 1e-5 only by the reference's own error
    EXPECT_LE(e.normal_p99_deg, 0.1);
  }
}

namespace {

// Flat pieces of every primitive kind that has one, in the plane y = 0 (the framing's horizontal
// plane), so that a view 3° above it meets most of their pixels at |n·d| ≈ 0.05.
Model flat_unit(const std::string& kind) {
  Model m;
  if (kind == "pancake") {  // an ellipsoid glyph 40 times wider than thick
    m.glyphs.push_back({GlyphKind::ellipsoid, {0, 0, 0}, 1.0, Eigen::Vector3d(1.0, 0.025, 1.0).asDiagonal(), {}});
  } else if (kind == "plane-tets") {  // a flat 4 x 4 quad grid: tetrahedra clipping the exact plane
    PolygonMesh grid;
    for (int j = 0; j <= 4; ++j)
      for (int i = 0; i <= 4; ++i) grid.vertices.emplace_back(0.25 * i, 0.0, 0.25 * j);
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        const int v = j * 5 + i;
        grid.indices.insert(grid.indices.end(), {v, v + 1, v + 6, v + 5});
        grid.offsets.push_back(static_cast<int>(grid.indices.size()));
      }
    m = convert_quads(grid).model;
  } else if (kind == "slim-plane") {  // overlapping SLIM balls, each the plane y = 0 (k_y = 1)
    QuadricCoefficients k{};
    k[7] = 1;
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) m.slims.push_back({.centre = {0.25 * i, 0, 0.25 * j}, .radius = 0.3, .local = Quadric::from_coefficients(k), .clips = {}, .colour = std::nullopt, .measured_error = std::nullopt, .max_push = std::nullopt});
  }
  return m;
}

class TinyFarGrazing : public GlTest, public ::testing::WithParamInterface<std::string> {};

}  // namespace

// Rays grazing tiny far primitives: the flat pieces above, 10⁻⁴ of their scene, 10⁴ and 10⁶
// diagonals from the origin, seen 3° above their plane; most covered pixels are grazing
// (|n·d| < 0.1), and the goals hold on those pixels by themselves, not only in a p99 over all.
TEST_P(TinyFarGrazing, MatchTheCpuReferenceWhereRaysGraze) {
  const std::string kind = GetParam();
  const Model unit = flat_unit(kind);
  ASSERT_FALSE(unit.empty());
  for (const double k : {1e4, 1e6}) {
    SCOPED_TRACE(testing::Message() << kind << " at " << k << " diagonals");
    const TinyFar t = tiny_far(*renderer_, unit, k, {.azimuth_deg = 35, .elevation_deg = 3, .width = 400, .height = 400});
    print(kind, k, t);
    ASSERT_GT(t.scene, 0.5);
    const EveryPixel& e = t.gl;
    EXPECT_GT(e.foreground, 1500);  // the tetrahedron grid covers 1,929 px, the others about 3,100
    EXPECT_GT(e.grazing, e.foreground / 2) << "the view does not graze";
    EXPECT_LE(e.mismatched, 0.001 * e.foreground);
    EXPECT_LE(e.grazing_depth_p99, 1e-5 + t.truth.grazing_depth_p99);
    EXPECT_LE(e.grazing_normal_p99_deg, 0.1);
  }
}

INSTANTIATE_TEST_SUITE_P(Kinds, TinyFarGrazing, ::testing::Values("pancake", "plane-tets", "slim-plane"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

INSTANTIATE_TEST_SUITE_P(Kinds, TinyFarPrimitives,
                         ::testing::Values("tets", "sphere", "ellipsoid", "cylinder", "glyphs", "slim-sphere"));

TEST_P(FarFromOrigin, MatchesTheCpuReference) {
  const Model at_origin = model_of(GetParam());
  ASSERT_FALSE(at_origin.empty());
  const double diagonal = bounds(at_origin).diagonal();
  for (const double k : {0.0, 1e4, 1e6}) {
    SCOPED_TRACE(testing::Message() << GetParam() << " at " << k << " diagonals");
    const Model m = translated(at_origin, k * diagonal * Vector3d(0.6, -0.48, 0.64));
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = 35, .elevation_deg = 25, .width = 200, .height = 200});
    renderer_->set_model(m);
    renderer_->draw(cam, {});
    const render::GBuffer g = renderer_->read_gbuffer();
    const ReferenceImage ref = render_reference(ReferenceScene(m), cam);
    const testing_gl::Comparison c = testing_gl::compare(ref, g);
    {  // the truth itself: the reference far away equals the reference at the origin
      Camera c0 = cam;
      const Vector3d t = k * diagonal * Vector3d(0.6, -0.48, 0.64);
      c0.eye -= t, c0.target -= t;
      const ReferenceImage r0 = render_reference(ReferenceScene(at_origin), c0);
      render::GBuffer as_gl;
      as_gl.width = ref.width, as_gl.height = ref.height;
      as_gl.coverage = ref.coverage, as_gl.depth = ref.depth;
      as_gl.normal.resize(ref.normal.size());
      for (std::size_t i = 0; i < ref.normal.size(); ++i) as_gl.normal[i] = ref.normal[i].cast<float>();
      const testing_gl::Comparison rc = testing_gl::compare(r0, as_gl);
      EXPECT_GE(rc.coverage_agreement, 0.9999);
      EXPECT_LE(rc.depth_p99, 1e-9);
    }
    const EveryPixel e = compare_every_pixel(ref, g, cam);  // the silhouette band included
    EXPECT_GT(c.covered, 3000);
    EXPECT_GE(c.coverage_agreement, 0.999);
    EXPECT_LE(e.mismatched, 0.001 * e.foreground);
    EXPECT_LE(c.depth_p99, 1e-5);
    EXPECT_LE(c.normal_p99_deg, 0.1);
    std::printf("%-12s %8.0e diagonals: coverage %.5f depth p99 %.2e normal p99 %.3f deg; every pixel: %d of %d "
                "mismatched, %d grazing px: depth p99 %.2e, normal p99 %.3f deg\n",
                GetParam().c_str(), k, c.coverage_agreement, c.depth_p99, c.normal_p99_deg, e.mismatched, e.foreground,
                e.grazing, e.grazing_depth_p99, e.grazing_normal_p99_deg);
  }
}

INSTANTIATE_TEST_SUITE_P(Kinds, FarFromOrigin,
                         ::testing::Values("hyperboloid1", "quad-blob", "slim-sphere", "glyphs"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

class FarMesh : public GlTest {};

namespace {

// The random quad blob both far-mesh tests draw, and its box.
std::pair<PolygonMesh, Box3> quad_blob_and_box() {
  std::mt19937_64 rng(8);
  std::pair<PolygonMesh, Box3> r{test::random_quad_blob(rng, 6), {}};
  for (const auto& v : r.first.vertices) r.second.extend(v);
  return r;
}

// A mesh's G-buffer g against g0, the same mesh's image taken as the truth (meshes are not in the
// CPU reference): coverage mismatches, and depth (÷ g0's depth range) and normal errors' p99.
struct MeshImageError {
  int covered = 0, mismatch = 0;
  double depth_p99 = 0, normal_p99_deg = 0;
};

MeshImageError compare_mesh_images(const render::GBuffer& g, const render::GBuffer& g0) {
  MeshImageError e;
  float lo = INFINITY, hi = -INFINITY;
  for (std::size_t i = 0; i < g0.coverage.size(); ++i)
    if (g0.coverage[i]) lo = std::min(lo, g0.depth[i]), hi = std::max(hi, g0.depth[i]), ++e.covered;
  std::vector<double> depth_err, normal_err;
  for (std::size_t i = 0; i < g.coverage.size(); ++i) {
    e.mismatch += g.coverage[i] != g0.coverage[i];
    if (!(g.coverage[i] && g0.coverage[i])) continue;
    depth_err.push_back(std::abs(double(g.depth[i]) - g0.depth[i]) / (hi - lo));
    normal_err.push_back(std::acos(std::clamp(double(g.normal[i].normalized().dot(g0.normal[i].normalized())), -1.0, 1.0)) *
                         180 / std::numbers::pi);
  }
  std::sort(depth_err.begin(), depth_err.end());
  std::sort(normal_err.begin(), normal_err.end());
  if (!depth_err.empty())
    e.depth_p99 = depth_err[depth_err.size() * 99 / 100], e.normal_p99_deg = normal_err[normal_err.size() * 99 / 100];
  return e;
}

// The accuracy goals of relative-to-eye rendering.
void expect_same_mesh_image(const MeshImageError& e) {
  EXPECT_LE(e.mismatch, 0.001 * e.covered);
  EXPECT_LE(e.depth_p99, 1e-5);
  EXPECT_LE(e.normal_p99_deg, 0.1);
}

}  // namespace

TEST_F(FarMesh, SameImageAsAtTheOrigin) {
  const auto [base, box] = quad_blob_and_box();
  const Camera cam0 = frame_box(box, {.azimuth_deg = 35, .elevation_deg = 25, .width = 200, .height = 200});
  renderer_->set_mesh(base);
  renderer_->draw(cam0, {});
  const render::GBuffer g0 = renderer_->read_gbuffer();
  ASSERT_GT(std::count(g0.coverage.begin(), g0.coverage.end(), 1), 3000);
  for (const double k : {1e4, 1e6}) {
    SCOPED_TRACE(k);
    const Vector3d t = k * box.diagonal() * Vector3d(0.6, -0.48, 0.64);
    PolygonMesh mesh = base;
    for (auto& v : mesh.vertices) v += t;
    Camera cam = cam0;
    cam.eye += t;
    cam.target += t;
    renderer_->set_mesh(mesh);
    renderer_->draw(cam, {});
    const MeshImageError e = compare_mesh_images(renderer_->read_gbuffer(), g0);
    std::printf("mesh %8.0e diagonals: coverage mismatch %d of %d, depth p99 %.2e normal p99 %.3f deg\n", k, e.mismatch,
                e.covered, e.depth_p99, e.normal_p99_deg);
    expect_same_mesh_image(e);
  }
}

namespace {

// The mesh scaled by s about the origin, then moved by t.
PolygonMesh scaled(PolygonMesh m, double s, const Vector3d& t) {
  for (auto& v : m.vertices) v = s * v + t;
  return m;
}

PolygonMesh joined(PolygonMesh a, const PolygonMesh& b) {
  const int base = static_cast<int>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (std::size_t f = 0; f < b.face_count(); ++f) {
    std::vector<int> face(b.face(f).begin(), b.face(f).end());
    for (int& i : face) i += base;
    a.add_face(face);
  }
  return a;
}

}  // namespace

// A mesh's triangles 10⁻⁴ of its extent, 0.4 of it from its centre and 10⁴ and 10⁶ extents from
// the world's origin (the rest of the mesh behind the eye), the camera framed on them: the same
// image as those triangles drawn as a mesh by themselves, from the same double inputs (meshes are
// not in the CPU reference; at 10⁶ double itself moves them by 1.8e-5 of their depth range
// against the same part at the origin, so the image at the origin is not the truth there).
TEST_F(FarMesh, TinyPartOfALargeMeshAsByItself) {
  const auto [unit, ub] = quad_blob_and_box();
  const double d0 = ub.diagonal();
  const Vector3d place(0.25, -0.2, 0.2);
  const FramingOptions view{.azimuth_deg = 35, .elevation_deg = 25, .width = 200, .height = 200};
  for (const double k : {1e4, 1e6}) {
    SCOPED_TRACE(k);
    const PolygonMesh tiny = scaled(unit, 1e-4 / d0, k * Vector3d(0.6, -0.48, 0.64) + place);
    Box3 tb;
    for (const auto& v : tiny.vertices) tb.extend(v);
    const Camera cam = frame_box(tb, view);
    renderer_->set_mesh(tiny);
    renderer_->draw(cam, {});
    const render::GBuffer g0 = renderer_->read_gbuffer();
    ASSERT_GT(std::count(g0.coverage.begin(), g0.coverage.end(), 1), 3000);
    const Vector3d back = (cam.eye - cam.target).normalized();
    renderer_->set_mesh(joined(tiny, scaled(unit, 0.3 / d0, cam.target + 0.5 * back)));
    renderer_->draw(cam, {});
    const MeshImageError e = compare_mesh_images(renderer_->read_gbuffer(), g0);
    std::printf("tiny mesh part %8.0e extents out: coverage mismatch %d of %d, depth p99 %.2e normal p99 %.3f deg\n", k,
                e.mismatch, e.covered, e.depth_p99, e.normal_p99_deg);
    expect_same_mesh_image(e);
  }
}
