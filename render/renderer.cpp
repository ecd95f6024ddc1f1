#include "render/renderer.h"

#include <glad/gl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <chrono>
#include <cstring>
#include <limits>

#include "core/culling.h"
#include "core/error.h"
#include "core/lighting.h"
#include "core/limits.h"
#include "render/context.h"
#include "render/gl/objects.h"
#include "render/passes/frame.h"
#include "render/passes/glyph_pass.h"
#include "render/passes/implicit_pass.h"
#include "render/passes/mesh_pass.h"
#include "render/passes/outline_pass.h"
#include "render/passes/shade_pass.h"
#include "render/passes/slim_pass.h"
#include "render/passes/statistics.h"
#include "render/passes/tet_pass.h"

namespace quadrix::render {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

}  // namespace

struct Renderer::Impl {
  GlContext* context;
  FrameTargets targets;
  FrameStatistics statistics;
  gl::VertexArray empty_vao = gl::make_vertex_array();
  TetPass tet;
  GlyphPass glyph;
  MeshPass mesh;
  SlimPass slim;
  ImplicitPass implicit;
  ShadePass shade;
  OutlinePass outline;
  SlimOutlinePass slim_outline{slim};
  FrameTargets light_targets;  // the key light's view (shadows)
  Box3 box;            // of the model's primitives
  Box3 mesh_box;       // of the triangles of set_mesh
  bool closed = true;  // its tetrahedron patches and glyphs bound solids (core/culling.h)

  /// A pass and the FrameStats figure its time adds to (time_passes only).
  struct Step {
    Pass* pass;
    double FrameStats::*ms;
  };
  // Passes that fill the G-buffer (inside the statistics queries), then those that make the image.
  std::array<Step, 5> gbuffer_steps{{{&tet, &FrameStats::ms_geometry},
                                     {&glyph, &FrameStats::ms_geometry},
                                     {&mesh, &FrameStats::ms_geometry},
                                     {&implicit, &FrameStats::ms_geometry},
                                     {&slim, &FrameStats::ms_slim}}};
  std::array<Step, 3> image_steps{{{&shade, &FrameStats::ms_shading},
                                   {&outline, &FrameStats::ms_shading},
                                   {&slim_outline, &FrameStats::ms_shading}}};

  /// No G-buffer pass before SLIM's (the last) draws anything.
  bool depth_clear_before_slim(const RenderOptions& o) const {
    return !tet.needed(o) && !glyph.needed(o) && !mesh.needed(o) && !implicit.needed(o);
  }
  /// Draws the G-buffer passes from the key light into light_targets, depth only.
  ShadowMap draw_shadow_map(const Camera& camera, const Box3& scene, const RenderOptions& o);
};

ShadowMap Renderer::Impl::draw_shadow_map(const Camera& camera, const Box3& scene, const RenderOptions& o) {
  const int size = o.shadow_map_size > 0 ? std::clamp(o.shadow_map_size, 16, 16384) : matched_shadow_map_size(camera, scene);
  const Camera light = shadow_light_camera(camera, scene, size);
  light_targets.resize(size, size);
  const CameraUniforms light_uniforms(light);
  RenderOptions lo = o;
  lo.statistics = false;
  lo.glyph_proxies = false;
  // The glyphs' early-depth path agrees with shadow rays here too since its buffer clear waits
  // for the previous resolve (render/passes/glyph_pass.cpp), but it is slower in this view: 1aon
  // at 1024² (a 1622² map, depth only) spent 419 ms on the map with it against 296 ms without
  // (spacefill; balls-and-sticks 427 against 267 ms).
  lo.glyph_early_depth = false;
  lo.cull = o.cull && backface_culling_is_exact(box, closed, light);
  Frame frame{light_uniforms, lo, light_targets, statistics.buffer(), empty_vao.id(), o.cull, /*depth_only=*/true};
  frame.is_depth_clear_before_slim = depth_clear_before_slim(lo);
  glViewport(0, 0, size, size);
  light_targets.clear();
  for (const auto& s : gbuffer_steps)
    if (s.pass->needed(lo)) s.pass->run(frame);
  for (GLuint i = 0; i < 3; ++i) glColorMaski(i, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  ShadowMap map;
  map.depth = light_targets.depth.id();
  // View eye space → world → light clip, in double (the eye offsets cancel before the cast).
  const Eigen::Matrix4d M = light.projection() * light.view() * camera.view().inverse();
  map.eye_to_light = M.cast<float>();
  const Eigen::Matrix4d P = light.projection();
  map.proj22 = static_cast<float>(P(2, 2));
  map.proj32 = static_cast<float>(P(2, 3));
  map.texel_world = static_cast<float>(2.0 * (light.eye - light.target).norm() *
                                       std::tan(0.5 * light.fov_y_deg * 3.14159265358979323846 / 180.0) / size);
  map.size = size;
  return map;
}

Renderer::Renderer(GlContext& context) : impl_(std::make_unique<Impl>()) {
  impl_->context = &context;
  gl::check_error("renderer setup");
}

Renderer::~Renderer() = default;

void Renderer::set_model(const Model& model) { set_model(model, AmpOptions{}); }

void Renderer::set_model(const Model& model, const AmpOptions& amp) {
  const Box3 box = bounds(model);
  check_drawable_extent(box.min, box.max, "the model");
  impl_->tet.upload(model.tets, tetrahedra_tessellate(model));
  impl_->glyph.upload(model.glyphs);
  impl_->slim.upload(model);
  impl_->box = box;
  for (const SlimPatch& s : model.slim_hierarchy.others) impl_->box.extend(bounds(s));  // coarser cuts
  impl_->closed = surfaces_are_closed(model);
  impl_->implicit.upload(model.implicits, amp);
}

double Renderer::implicit_compile_ms() const { return impl_->implicit.compile_ms(); }

void Renderer::set_implicit_parameters(std::size_t i, const std::map<std::string, double>& values) {
  impl_->implicit.set_parameters(i, values);
}

void Renderer::set_mesh(const PolygonMesh& mesh, Rgb colour) {
  impl_->mesh.upload(mesh, colour);
  impl_->mesh_box = Box3{};
  for (const auto& v : mesh.vertices) impl_->mesh_box.extend(v);
}

FrameStats Renderer::draw(const Camera& camera, const RenderOptions& o) {
  auto& I = *impl_;
  const auto start = Clock::now();
  I.targets.resize(camera.width, camera.height);
  FrameStats st;
  st.slim_cut_uploaded = I.slim.select_cut(camera, {.pixel_error = o.slim_pixel_error});
  st.slim_balls = I.slim.count();
  if (I.slim.has_hierarchy()) st.slim_level_counts = I.slim.cut().level_counts;
  st.primitives = I.tet.count() + I.glyph.count() + I.slim.count() + I.implicit.count();
  const CameraUniforms camera_uniforms(camera);
  // Back sides are culled only where no ray from the eye can see them (core/culling.h).
  RenderOptions exact = o;
  exact.cull = o.cull && backface_culling_is_exact(I.box, I.closed, camera);
  Box3 scene = I.box;
  if (I.mesh.needed(o)) scene.extend(I.mesh_box);
  Frame frame{camera_uniforms, exact, I.targets, I.statistics.buffer(), I.empty_vao.id(), o.cull};
  frame.depth_needed_after_tets = I.glyph.needed(o) || I.mesh.needed(o) || I.implicit.needed(o) || I.slim.needed(o);
  frame.is_depth_clear_before_slim = I.depth_clear_before_slim(o);
  frame.scene_radius = scene.empty() ? 1.0f : static_cast<float>(0.5 * scene.diagonal());
  ShadowMap shadow;
  if (o.shadows && !scene.empty()) {
    const auto t = Clock::now();
    shadow = I.draw_shadow_map(camera, scene, o);
    frame.shadow = &shadow;
    if (o.time_passes) {
      glFinish();
      st.ms_shadows = ms_since(t);
    }
  }

  glViewport(0, 0, I.targets.width, I.targets.height);
  glBindFramebuffer(GL_FRAMEBUFFER, I.targets.gbuffer.id());
  I.targets.clear();
  // time_passes: glFinish after each pass, its CPU time added to the pass's figure.
  auto mark = Clock::now();
  const auto lap = [&](double& ms) {
    if (!o.time_passes) return;
    glFinish();
    ms += ms_since(mark);
    mark = Clock::now();
  };
  lap(st.ms_clear);
  const auto run = [&](const auto& steps) {
    for (const auto& s : steps)
      if (s.pass->needed(o)) {
        s.pass->run(frame);
        lap(st.*s.ms);
      }
  };
  if (o.statistics) I.statistics.begin();
  run(I.gbuffer_steps);
  if (o.statistics) I.statistics.end();
  run(I.image_steps);
  glFinish();
  gl::check_error("draw");
  if (o.statistics) I.statistics.read(st);
  if (I.tet.needed(o)) {
    st.chunks = I.tet.chunk_count();
    st.chunks_culled = I.tet.culled_chunks();
    st.culled_in_chunks = I.tet.culled_in_chunks();
    st.chunks_occluded = I.tet.occluded_chunks();
    st.occluded_in_chunks = I.tet.occluded_in_chunks();
  }
  st.ms_total = ms_since(start);
  return st;
}

Image8 Renderer::read_colour() const {
  const auto& I = *impl_;
  Image8 img;
  img.width = I.targets.width;
  img.height = I.targets.height;
  img.rgba.resize(static_cast<std::size_t>(I.targets.width) * I.targets.height * 4);
  std::vector<std::uint8_t> tmp(img.rgba.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(I.targets.colour.id(), 0, GL_RGBA, GL_UNSIGNED_BYTE, static_cast<GLsizei>(tmp.size()), tmp.data());
  const std::size_t row = static_cast<std::size_t>(I.targets.width) * 4;
  for (int y = 0; y < I.targets.height; ++y)
    std::memcpy(img.rgba.data() + y * row, tmp.data() + (I.targets.height - 1 - y) * row, row);
  return img;
}

GBuffer Renderer::read_gbuffer() const {
  const auto& I = *impl_;
  const std::size_t n = static_cast<std::size_t>(I.targets.width) * I.targets.height;
  std::vector<float> nd(4 * n);
  std::vector<std::int32_t> ids(n);
  glGetTextureImage(I.targets.normal_depth.id(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(nd.size() * 4), nd.data());
  glGetTextureImage(I.targets.ids.id(), 0, GL_RED_INTEGER, GL_INT, static_cast<GLsizei>(ids.size() * 4), ids.data());
  gl::check_error("reading the G-buffer");
  GBuffer g;
  g.width = I.targets.width;
  g.height = I.targets.height;
  g.coverage.assign(n, 0);
  g.depth.assign(n, std::numeric_limits<float>::infinity());
  g.normal.assign(n, Eigen::Vector3f::Zero());
  g.primitive.assign(n, -1);
  for (int y = 0; y < I.targets.height; ++y)
    for (int x = 0; x < I.targets.width; ++x) {
      const std::size_t src = static_cast<std::size_t>(I.targets.height - 1 - y) * I.targets.width + x;
      const std::size_t dst = static_cast<std::size_t>(y) * I.targets.width + x;
      if (!(nd[4 * src + 3] > 0.0f)) continue;
      g.coverage[dst] = 1;
      g.depth[dst] = nd[4 * src + 3];
      g.normal[dst] = Eigen::Vector3f(nd[4 * src], nd[4 * src + 1], nd[4 * src + 2]);
      g.primitive[dst] = ids[src];
    }
  return g;
}

void Renderer::present(int window_width, int window_height) const {
  const auto& I = *impl_;
  glBlitNamedFramebuffer(I.targets.output.id(), 0, 0, 0, I.targets.width, I.targets.height, 0, 0, window_width, window_height,
                         GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

}  // namespace quadrix::render
