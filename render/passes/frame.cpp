#include "render/passes/frame.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/error.h"

namespace quadrix::render {

Split split(const Eigen::Vector3d& p) {
  const Eigen::Vector3f hi = p.cast<float>();
  return {hi, (p - hi.cast<double>()).cast<float>()};
}

float bits_float(std::uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

CameraUniforms::CameraUniforms(const Camera& camera)
    : proj(camera.projection().cast<float>()),
      view_rot(camera.view().topLeftCorner<3, 3>().cast<float>()),
      target(split(camera.target)),
      target_minus_eye((camera.target - camera.eye).cast<float>()),
      target_distance(static_cast<float>((camera.target - camera.eye).norm())),
      near_plane(static_cast<float>(camera.near_plane)),
      viewport(float(camera.width), float(camera.height)),
      target_world(camera.target),
      world(camera) {}

FixedOrigin FixedOrigin::of(const Box3& box) {
  FixedOrigin f;
  if (box.empty()) return f;
  f.origin = box.centre();
  const double extent = (box.max - box.min).cwiseAbs().maxCoeff();
  // Half the box within 2²⁷ quanta; a point box (one primitive) gets a quantum of its own scale.
  const double scale = extent > 0 ? extent : std::max(1e-30, f.origin.cwiseAbs().maxCoeff() * 1e-7);
  f.quantum = std::ldexp(scale, -28);
  return f;
}

FixedOrigin::Offset FixedOrigin::offset(const Eigen::Vector3d& d) const {
  Offset o;
  constexpr double kMax = 1 << 30;
  for (int i = 0; i < 3; ++i) {
    const double n = std::clamp(std::round(d[i] / quantum), -kMax, kMax);  // beyond: the rest holds it
    o.q[i] = static_cast<int>(n);
    o.rest[i] = static_cast<float>(d[i] - n * quantum);
  }
  return o;
}

void set_origin_uniforms(const gl::Program& p, const FixedOrigin& origin, const CameraUniforms& c) {
  const FixedOrigin::Offset o = origin.offset(origin.origin - c.world.target);
  p.set("u_origin_q", o.q);
  p.set("u_origin_rest", o.rest);
  p.set("u_quantum", static_cast<float>(origin.quantum));
}

void set_camera_uniforms(const gl::Program& p, const CameraUniforms& c) {
  p.set("u_proj", c.proj);
  p.set("u_view_rot", c.view_rot);
  p.set("u_target_hi", c.target.hi);
  p.set("u_target_lo", c.target.lo);
  p.set("u_target_minus_eye", c.target_minus_eye);
  p.set("u_target_distance", c.target_distance);
  p.set("u_near", c.near_plane);
  p.set("u_viewport", c.viewport);
}

void begin_gbuffer_draw(const Frame& f) {
  glBindFramebuffer(GL_FRAMEBUFFER, f.targets.gbuffer.id());
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  set_gbuffer_colour_writes(f);
}

void set_gbuffer_colour_writes(const Frame& f) {
  const GLboolean on = f.depth_only ? GL_FALSE : GL_TRUE;
  for (GLuint i = 0; i < 3; ++i) glColorMaski(i, on, on, on, on);
}

void FrameTargets::resize(int w, int h) {
  if (w == width && h == height) return;
  width = w, height = h;
  ++generation;
  normal_depth = gl::make_texture_2d(GL_RGBA32F, w, h);
  albedo = gl::make_texture_2d(GL_RGBA8, w, h);
  ids = gl::make_texture_2d(GL_R32I, w, h);
  depth = gl::make_texture_2d(GL_DEPTH_COMPONENT32F, w, h);
  colour = gl::make_texture_2d(GL_RGBA8, w, h);
  GLuint fb = 0;
  glCreateFramebuffers(1, &fb);
  gbuffer = gl::Framebuffer(fb);
  glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT0, normal_depth.id(), 0);
  glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT1, albedo.id(), 0);
  glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT2, ids.id(), 0);
  glNamedFramebufferTexture(fb, GL_DEPTH_ATTACHMENT, depth.id(), 0);
  const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  glNamedFramebufferDrawBuffers(fb, 3, bufs);
  if (glCheckNamedFramebufferStatus(fb, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GlError("G-buffer framebuffer incomplete");
  glCreateFramebuffers(1, &fb);
  output = gl::Framebuffer(fb);
  glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT0, colour.id(), 0);
  glNamedFramebufferTexture(fb, GL_DEPTH_ATTACHMENT, depth.id(), 0);  // read by the shading's test
  if (glCheckNamedFramebufferStatus(fb, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GlError("output framebuffer incomplete");
  gl::check_error("allocating render targets");
}

void FrameTargets::clear() const {
  const float zero[4] = {0, 0, 0, 0};
  const GLint minus_one[4] = {-1, -1, -1, -1};
  const float one = 1.0f;
  glDepthMask(GL_TRUE);  // clears honour the write masks
  glClearNamedFramebufferfv(gbuffer.id(), GL_COLOR, 0, zero);
  glClearNamedFramebufferfv(gbuffer.id(), GL_COLOR, 1, zero);
  glClearNamedFramebufferiv(gbuffer.id(), GL_COLOR, 2, minus_one);
  glClearNamedFramebufferfv(gbuffer.id(), GL_DEPTH, 0, &one);
}

}  // namespace quadrix::render
