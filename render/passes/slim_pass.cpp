#include "render/passes/slim_pass.h"

#include <array>

#include <fmt/format.h>

#include "core/error.h"
#include "core/primitive.h"
#include "core/slim.h"
#include "render/shaders.h"

namespace quadrix::render {
namespace {

// std430 layout of `Ball` in slim.vert (7 vec4 = 112 bytes).
struct GpuBall {
  float centre_hi[4];
  float centre_lo[4];
  float q0[4], q1[4], q2[4];
  float clip[4];
  float slab[4];
};
static_assert(sizeof(GpuBall) == 112);

// The octagonal prism's 28 triangles over its 16 corners (kProxyIndex in slim.vert).
constexpr std::array<std::uint8_t, 84> kProxyIndex = {
    0, 2, 1, 0, 3, 2, 0, 4, 3, 0, 5, 4, 0, 6, 5, 0, 7, 6,
    8, 9, 10, 8, 10, 11, 8, 11, 12, 8, 12, 13, 8, 13, 14, 8, 14, 15,
    0, 1, 9, 0, 9, 8, 1, 2, 10, 1, 10, 9, 2, 3, 11, 2, 11, 10, 3, 4, 12, 3, 12, 11,
    4, 5, 13, 4, 13, 12, 5, 6, 14, 5, 14, 13, 6, 7, 15, 6, 15, 14, 7, 0, 8, 7, 8, 15};

GpuBall pack(const SlimPatch& b, std::int32_t id) {
  GpuBall g{};
  const Split cs = split(b.centre);
  for (int i = 0; i < 3; ++i) {
    g.centre_hi[i] = cs.hi[i];
    g.centre_lo[i] = cs.lo[i];
  }
  g.centre_hi[3] = static_cast<float>(b.radius);
  const Rgb col = b.colour.value_or(Rgb{200, 200, 200});
  g.centre_lo[3] = bits_float(col[0] | (col[1] << 8) | (col[2] << 16));
  const Quadric q = b.local.normalized();
  const auto& A = q.A;
  g.q0[0] = float(A(0, 0)), g.q0[1] = float(A(1, 1)), g.q0[2] = float(A(2, 2)), g.q0[3] = float(A(0, 1));
  g.q1[0] = float(A(1, 2)), g.q1[1] = float(A(0, 2)), g.q1[2] = float(q.b.x()), g.q1[3] = float(q.b.y());
  g.q2[0] = float(q.b.z()), g.q2[1] = float(q.c), g.q2[2] = bits_float(static_cast<std::uint32_t>(id));
  // The slab of the surface piece (computed once, here at load time); s0 > s1: the whole ball.
  const SlimSlab slab = slim_patch_slab(b);
  for (int i = 0; i < 3; ++i) g.slab[i] = float(slab.axis[i]);
  g.slab[3] = slab.tight ? float(slab.s0) : 1.0f;
  g.q2[3] = slab.tight ? float(slab.s1) : -1.0f;
  if (b.clip) {
    const double n = b.clip->n.norm();
    if (n > 0)
      for (int i = 0; i < 3; ++i) g.clip[i] = float(b.clip->n[i] / n);
    if (n > 0) g.clip[3] = float(b.clip->d / n);
  }
  return g;
}

const float kZero[4] = {0, 0, 0, 0};

void set_colour_writes(GLboolean on) {
  for (GLuint i = 0; i < 3; ++i) glColorMaski(i, on, on, on, on);
}

}  // namespace

SlimPass::SlimPass()
    : visibility_("slim pass 1", shader_source("slim.vert"), shader_source("slim.frag"), "#define SLIM_PASS 1\n"),
      accumulate_("slim pass 2", shader_source("slim.vert"), shader_source("slim.frag"), "#define SLIM_PASS 2\n"),
      resolve_("slim pass 3", shader_source("fullscreen.vert"), shader_source("slim_resolve.frag")) {}

void SlimPass::upload(std::span<const SlimPatch> patches) {
  if (patches.size() > kMaxPrimitiveIndex + 1)
    throw InvalidInput(fmt::format("{} SLIM patches: the GL renderer draws at most 2^{}", patches.size(),
                                   kPrimitiveIndexBits));
  std::vector<GpuBall> data;
  data.reserve(patches.size());
  for (std::size_t i = 0; i < patches.size(); ++i)
    data.push_back(pack(patches[i], primitive_id(PrimitiveKind::slim, i)));
  balls_ = gl::make_buffer(static_cast<GLsizeiptr>(data.size() * sizeof(GpuBall)), data.data());
  count_ = data.size();
  if (!proxy_indices_) {
    proxy_indices_ = gl::make_buffer(sizeof kProxyIndex, kProxyIndex.data());
    proxy_vao_ = gl::make_vertex_array();
    glVertexArrayElementBuffer(proxy_vao_.id(), proxy_indices_.id());
  }
}

void SlimPass::ensure_accumulation(const FrameTargets& t, bool half) {
  if (acc_fbo_ && acc_half_ == half && acc_generation_ == t.generation) return;
  acc_half_ = half;
  acc_generation_ = t.generation;
  const GLenum format = half ? GL_RGBA16F : GL_RGBA32F;
  acc_normal_weight_ = gl::make_texture_2d(format, t.width, t.height);
  acc_depth_colour_ = gl::make_texture_2d(format, t.width, t.height);
  GLuint fb = 0;
  glCreateFramebuffers(1, &fb);
  acc_fbo_ = gl::Framebuffer(fb);
  glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT0, acc_normal_weight_.id(), 0);
  glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT1, acc_depth_colour_.id(), 0);
  glNamedFramebufferTexture(fb, GL_DEPTH_ATTACHMENT, t.depth.id(), 0);
  const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glNamedFramebufferDrawBuffers(fb, 2, bufs);
  if (glCheckNamedFramebufferStatus(fb, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GlError("SLIM accumulation framebuffer incomplete");
}

void SlimPass::set_uniforms(const gl::Program& p, const Frame& f, int count_stats) const {
  set_camera_uniforms(p, f.camera);
  p.set("u_offset", f.options.slim_offset);
  p.set("u_count_stats", count_stats);
  p.set("u_cull", f.slim_cull ? 1 : 0);
  p.set("u_tight", f.options.slim_tight_splats ? 1 : 0);
  // The statistics frame draws unindexed, so each ball's corner 0 runs (and counts) once.
  p.set("u_indexed", count_stats != 0 || f.options.statistics ? 0 : 1);
}

void SlimPass::draw_proxies(const Frame& f) const {
  if (f.options.statistics) {
    glBindVertexArray(f.empty_vao);
    glDrawArraysInstanced(GL_TRIANGLES, 0, static_cast<GLsizei>(kProxyIndex.size()), static_cast<GLsizei>(count_));
  } else {
    glBindVertexArray(proxy_vao_.id());
    glDrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(kProxyIndex.size()), GL_UNSIGNED_BYTE, nullptr,
                            static_cast<GLsizei>(count_));
  }
}

void SlimPass::run(const Frame& f) {
  ensure_accumulation(f.targets, f.options.slim_half_float);
  glEnable(GL_DEPTH_TEST);
  // The prisms' back faces: every pixel of a splat is covered once (pass 2 adds it up).
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  glDisable(GL_BLEND);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, balls_.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, f.stats_buffer);
  visibility(f);
  accumulate(f);
  glDisable(GL_CULL_FACE);
  glBindVertexArray(f.empty_vao);
  resolve(f);
}

// Pass 1: the pushed-back depth of each ball's first hit, no colour writes.
void SlimPass::visibility(const Frame& f) {
  glBindFramebuffer(GL_FRAMEBUFFER, f.targets.gbuffer.id());
  set_colour_writes(GL_FALSE);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  set_uniforms(visibility_, f, f.options.statistics ? 1 : 0);
  visibility_.use();
  draw_proxies(f);
  set_colour_writes(GL_TRUE);
}

// Pass 2: every hit in front of pass 1's depth adds its weighted normal, depth and colour.
void SlimPass::accumulate(const Frame& f) {
  glBindFramebuffer(GL_FRAMEBUFFER, acc_fbo_.id());
  glClearNamedFramebufferfv(acc_fbo_.id(), GL_COLOR, 0, kZero);
  glClearNamedFramebufferfv(acc_fbo_.id(), GL_COLOR, 1, kZero);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  set_uniforms(accumulate_, f, 0);
  accumulate_.use();
  draw_proxies(f);
  glDisable(GL_BLEND);
}

// Pass 3: divide by Σw into the G-buffer; the deferred pass shades it with the rest.
void SlimPass::resolve(const Frame& f) {
  glBindFramebuffer(GL_FRAMEBUFFER, f.targets.gbuffer.id());
  glDepthFunc(GL_ALWAYS);
  glDepthMask(GL_TRUE);
  set_camera_uniforms(resolve_, f.camera);
  resolve_.use();
  glBindTextureUnit(0, acc_normal_weight_.id());
  glBindTextureUnit(1, acc_depth_colour_.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthFunc(GL_LESS);
}

SlimOutlinePass::SlimOutlinePass(const SlimPass& slim)
    : slim_(slim),
      program_("slim outline", shader_source("slim.vert"), shader_source("slim_outline.frag"),
               "#define SLIM_OUTLINE 1\n") {}

void SlimOutlinePass::run(const Frame& f) {
  glBindFramebuffer(GL_FRAMEBUFFER, f.targets.output.id());
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  set_camera_uniforms(program_, f.camera);
  program_.set("u_count_stats", 0);
  program_.set("u_cull", f.slim_cull ? 1 : 0);
  program_.set("u_tight", 0);
  program_.set("u_indexed", 0);
  program_.use();
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, slim_.balls());
  glBindVertexArray(f.empty_vao);
  glDrawArraysInstanced(GL_LINE_STRIP, 0, 5, static_cast<GLsizei>(slim_.count()));
}

}  // namespace quadrix::render
