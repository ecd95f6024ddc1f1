#include "render/passes/slim_pass.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

#include <fmt/format.h>

#include "core/error.h"
#include "core/primitive.h"
#include "core/slim.h"
#include "render/context.h"
#include "render/shaders.h"

namespace quadrix::render {
namespace {

// std430 layout of `Ball` in slim.vert (11 vec4 = 176 bytes).
struct GpuBall {
  float centre_hi[4];
  float centre_lo[4];
  float q0[4], q1[4], q2[4];
  float slab[4];
  float clip[ClipPlanes::kMax][4];
  float extra[4];  // [0]: the ball's own push bound (SlimPatch::max_push), −1: none
};
static_assert(sizeof(GpuBall) == 176);
constexpr std::size_t kBallFloats = sizeof(GpuBall) / sizeof(float);
constexpr std::size_t kIdFloat = offsetof(GpuBall, q2) / sizeof(float) + 2;  // q2[2]: the primitive id

// `origin`: the model's origin, which the stored centre is relative to (as quanta and a rest).
GpuBall pack(const SlimPatch& b, std::int32_t id, const FixedOrigin& origin) {
  GpuBall g{};
  const FixedOrigin::Offset cs = origin.offset(b.centre - origin.origin);
  for (int i = 0; i < 3; ++i) {
    g.centre_hi[i] = bits_float(static_cast<std::uint32_t>(cs.q[i]));
    g.centre_lo[i] = cs.rest[i];
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
  // Unit normals (so the shader's test is a distance in units of R); unused slots stay zero.
  for (int k = 0; k < b.clips.size(); ++k) {
    const ClipPlane& p = b.clips[k];
    const double n = p.n.norm();
    if (!(n > 0)) continue;
    for (int i = 0; i < 3; ++i) g.clip[k][i] = float(p.n[i] / n);
    g.clip[k][3] = float(p.d / n);
  }
  g.extra[0] = b.max_push ? float(*b.max_push) : -1.0f;
  g.extra[1] = float(slab.r0), g.extra[2] = float(slab.r1);
  return g;
}

const float kZero[4] = {0, 0, 0, 0};

// Balls per spatial chunk (frustum culling and the screen bound of the early-depth path).
constexpr std::size_t kChunkSize = 256;

void scissor(const PixelRect& r) { glScissor(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0); }

// A texture-level clear of the rectangle: a scissored framebuffer clear is a drawn quad on
// llvmpipe (fragment-shader runs over the rectangle), this one is not.
void clear_pixels(const gl::Texture& t, const PixelRect& r, GLenum format, const float* value) {
  glClearTexSubImage(t.id(), 0, r.x0, r.y0, 0, r.x1 - r.x0, r.y1 - r.y0, 1, format, GL_FLOAT, value);
}

void set_colour_writes(GLboolean on) {
  for (GLuint i = 0; i < 3; ++i) glColorMaski(i, on, on, on, on);
}

}  // namespace

SlimPass::SlimPass()
    : visibility_("slim pass 1", shader_source("slim.vert"), shader_source("slim.frag"), "#define SLIM_PASS 1\n"),
      accumulate_("slim pass 2", shader_source("slim.vert"), shader_source("slim.frag"), "#define SLIM_PASS 2\n"),
      resolve_("slim pass 3", shader_source("fullscreen.vert"), shader_source("slim_resolve.frag")),
      resolve_drawn_("slim pass 3, where drawn", shader_source("fullscreen.vert"), shader_source("slim_resolve.frag"),
                     "#define FULLSCREEN_AT_FAR 1\n#define SLIM_RESOLVE_KEEPS_DEPTH 1\n"),
      visibility_early_("slim pass 1, early depth", shader_source("slim.vert"), shader_source("slim.frag"),
                        "#define SLIM_PASS 1\n#define SLIM_EARLY 1\n"),
      accumulate_early_("slim pass 2, early depth", shader_source("slim.vert"), shader_source("slim.frag"),
                        "#define SLIM_PASS 2\n#define SLIM_EARLY 1\n"),
      from_depth_("slim pass-1 depth from the depth buffer", shader_source("fullscreen.vert"),
                  shader_source("slim_depth_copy.frag")),
      software_(current_context_is_software()) {}

void SlimPass::upload_chunked(std::span<const float> balls, std::span<const Box3> boxes) {
  chunks_ = make_chunks(boxes, {.chunk_size = kChunkSize});
  std::vector<float> data(balls.size());
  for (std::size_t s = 0; s < chunks_.order.size(); ++s)
    std::memcpy(data.data() + s * kBallFloats, balls.data() + std::size_t{chunks_.order[s]} * kBallFloats,
                kBallFloats * sizeof(float));
  if (!data.empty())
    glNamedBufferSubData(balls_.id(), 0, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data());
  count_ = boxes.size();
}

void SlimPass::upload(std::span<const SlimPatch> patches) {
  if (patches.size() > kMaxPrimitiveIndex + 1)
    throw InvalidInput(fmt::format("{} SLIM patches: the GL renderer draws at most 2^{}", patches.size(),
                                   kPrimitiveIndexBits));
  Box3 box;
  for (const SlimPatch& p : patches) box.extend(p.centre);
  origin_ = FixedOrigin::of(box);
  std::vector<float> data(patches.size() * kBallFloats);
  std::vector<Box3> boxes(patches.size());
  for (std::size_t i = 0; i < patches.size(); ++i) {
    const GpuBall g = pack(patches[i], primitive_id(PrimitiveKind::slim, i), origin_);
    std::memcpy(data.data() + i * kBallFloats, &g, sizeof g);
    boxes[i] = bounds(patches[i]);
  }
  balls_ = gl::make_buffer(static_cast<GLsizeiptr>(data.size() * sizeof(float)), nullptr, GL_DYNAMIC_STORAGE_BIT);
  upload_chunked(data, boxes);
}

void SlimPass::upload(const Model& model) {
  lod_.reset();
  cut_ = {};
  has_cut_ = false;
  packed_.clear();
  if (model.slim_hierarchy.empty()) {
    upload(model.slims);
    return;
  }
  lod_.emplace(model);
  const std::size_t n = lod_->size();
  if (n > kMaxPrimitiveIndex + 1)
    throw InvalidInput(fmt::format("{} SLIM balls: the GL renderer draws at most 2^{}", n, kPrimitiveIndexBits));
  Box3 box;
  for (std::size_t b = 0; b < n; ++b) box.extend(slim_ball(model, b).centre);
  origin_ = FixedOrigin::of(box);
  packed_.resize(n * kBallFloats);
  boxes_.resize(n);
  for (std::size_t b = 0; b < n; ++b) {
    const GpuBall g = pack(slim_ball(model, b), 0, origin_);
    std::memcpy(packed_.data() + b * kBallFloats, &g, sizeof g);
    boxes_[b] = bounds(slim_ball(model, b));
  }
  // Room for every ball: a cut never holds more balls than the hierarchy.
  balls_ = gl::make_buffer(static_cast<GLsizeiptr>(n * sizeof(GpuBall)), nullptr, GL_DYNAMIC_STORAGE_BIT);
  count_ = 0;
  chunks_ = {};
}

bool SlimPass::select_cut(const Camera& camera, const SlimLodOptions& options) {
  if (!lod_) return false;
  SlimLodCut c = lod_->cut(camera, options);
  if (has_cut_ && c == cut_) return false;
  std::vector<float> data(c.balls.size() * kBallFloats);
  std::vector<Box3> boxes(c.balls.size());
  for (std::size_t i = 0; i < c.balls.size(); ++i) {
    std::memcpy(data.data() + i * kBallFloats, packed_.data() + static_cast<std::size_t>(c.balls[i]) * kBallFloats,
                sizeof(GpuBall));
    data[i * kBallFloats + kIdFloat] = bits_float(static_cast<std::uint32_t>(primitive_id(PrimitiveKind::slim, i)));
    boxes[i] = boxes_[c.balls[i]];
  }
  upload_chunked(data, boxes);
  cut_ = std::move(c);
  has_cut_ = true;
  return true;
}

void SlimPass::ensure_accumulation(const FrameTargets& t, bool half) {
  // Reuse the slot made for these targets; else remake the other one (the view's and the
  // light's targets alternate when shadows are on).
  Accumulation* a = acc_[0].targets == &t ? &acc_[0] : acc_[1].targets == &t ? &acc_[1]
                    : current_ == &acc_[0] ? &acc_[1] : &acc_[0];
  current_ = a;
  if (a->fbo && a->targets == &t && a->half == half && a->generation == t.generation) return;
  a->half = half;
  a->targets = &t;
  a->generation = t.generation;
  const GLenum format = half ? GL_RGBA16F : GL_RGBA32F;
  a->normal_weight = gl::make_texture_2d(format, t.width, t.height);
  a->depth_colour = gl::make_texture_2d(format, t.width, t.height);
  a->pass1_depth = gl::make_texture_2d(GL_R32F, t.width, t.height);
  for (const bool with_depth : {true, false}) {
    GLuint id = 0;
    glCreateFramebuffers(1, &id);
    (with_depth ? a->pass1_fbo : a->copy_fbo) = gl::Framebuffer(id);
    glNamedFramebufferTexture(id, GL_COLOR_ATTACHMENT0, a->pass1_depth.id(), 0);
    if (with_depth) glNamedFramebufferTexture(id, GL_DEPTH_ATTACHMENT, t.depth.id(), 0);
    glNamedFramebufferDrawBuffer(id, GL_COLOR_ATTACHMENT0);
    if (glCheckNamedFramebufferStatus(id, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw GlError("SLIM pass-1 depth framebuffer incomplete");
  }
  GLuint fb = 0;
  glCreateFramebuffers(1, &fb);
  a->fbo = gl::Framebuffer(fb);
  glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT0, a->normal_weight.id(), 0);
  glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT1, a->depth_colour.id(), 0);
  glNamedFramebufferTexture(fb, GL_DEPTH_ATTACHMENT, t.depth.id(), 0);
  const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glNamedFramebufferDrawBuffers(fb, 2, bufs);
  if (glCheckNamedFramebufferStatus(fb, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GlError("SLIM accumulation framebuffer incomplete");
}

// Vertices per splat (render/shaders/slim.vert): the tight polygon's sides; rectangles (the
// ball splats) as 4.
GLsizei SlimPass::splat_sides(const RenderOptions& o) const {
  if (!o.slim_tight_splats) return 4;
  return static_cast<GLsizei>(std::clamp(o.slim_splat_sides.value_or(software_ ? 4 : 8) / 4 * 4, 4, 8));
}

void SlimPass::set_uniforms(const gl::Program& p, const Frame& f, int count_stats) const {
  set_camera_uniforms(p, f.camera);
  set_origin_uniforms(p, origin_, f.camera);
  p.set("u_offset", f.options.slim_offset);
  p.set("u_max_push", std::min(f.options.slim_max_push, std::numeric_limits<float>::max()));
  p.set("u_count_stats", count_stats);
  p.set("u_cull", f.slim_cull ? 1 : 0);
  p.set("u_tight", f.options.slim_tight_splats ? 1 : 0);
  p.set("u_sides", splat_sides(f.options));
  p.set("u_base", 0);
}

void SlimPass::run(const Frame& f) {
  ensure_accumulation(f.targets, f.options.slim_half_float);
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, balls_.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, f.stats_buffer);
  glBindVertexArray(f.empty_vao);
  if (f.options.slim_early_depth) {
    run_early_depth(f);
    return;
  }
  visibility(f);
  accumulate(f);
  resolve(f);
}

void SlimPass::run_early_depth(const Frame& f) {
  // The chunks in the view frustum, drawn as runs of consecutive GPU slots, and their pixels.
  const Camera& cam = f.camera.world;
  ChunkSelection selection = select_chunks(chunks_, cam);
  std::sort(selection.chunks.begin(), selection.chunks.end());
  std::vector<std::pair<GLint, GLsizei>> runs;  // first slot, count
  PixelRect all;
  for (const std::uint32_t c : selection.chunks) {
    all.extend(box_pixels(chunks_.boxes[c], cam));
    if (!runs.empty() && runs.back().first + runs.back().second == static_cast<GLint>(chunks_.first[c]))
      runs.back().second += static_cast<GLsizei>(chunks_.count[c]);
    else
      runs.emplace_back(static_cast<GLint>(chunks_.first[c]), static_cast<GLsizei>(chunks_.count[c]));
  }
  if (all.empty()) return;
  const auto draw = [&](const gl::Program& program) {
    for (const auto& [first, count] : runs) {
      program.set("u_base", first);
      program.use();
      glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, splat_sides(f.options), count);
    }
  };
  const Accumulation& a = *current_;
  glEnable(GL_SCISSOR_TEST);
  scissor(all);
  // The pass-1 depth target starts as the depth buffer: what the frame drew before SLIM.
  glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);  // clears honour the write masks
  if (f.is_depth_clear_before_slim) {
    const float far = 1;
    clear_pixels(a.pass1_depth, all, GL_RED, &far);
  } else {
    glBindFramebuffer(GL_FRAMEBUFFER, a.copy_fbo.id());
    glDisable(GL_DEPTH_TEST);
    glBindTextureUnit(0, f.targets.depth.id());
    from_depth_.use();
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glEnable(GL_DEPTH_TEST);
  }

  // Pass 1 as on the other path, its depth also kept in a colour target.
  glBindFramebuffer(GL_FRAMEBUFFER, a.pass1_fbo.id());
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  set_uniforms(visibility_early_, f, f.options.statistics ? 1 : 0);
  draw(visibility_early_);

  // Pass 2: the depth test before the shader, each hit tested against pass 1's depth.
  const GLuint fbo = a.fbo.id();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  set_colour_writes(GL_TRUE);
  clear_pixels(a.normal_weight, all, GL_RGBA, kZero);
  clear_pixels(a.depth_colour, all, GL_RGBA, kZero);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  glBindTextureUnit(0, a.pass1_depth.id());
  set_uniforms(accumulate_early_, f, f.options.statistics ? 1 : 0);
  draw(accumulate_early_);
  glDisable(GL_BLEND);
  resolve(f);
  glDisable(GL_SCISSOR_TEST);
}

// Pass 1: the pushed-back depth of each ball's first hit, no colour writes.
void SlimPass::visibility(const Frame& f) {
  glBindFramebuffer(GL_FRAMEBUFFER, f.targets.gbuffer.id());
  set_colour_writes(GL_FALSE);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  set_uniforms(visibility_, f, f.options.statistics ? 1 : 0);
  visibility_.use();
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, splat_sides(f.options), static_cast<GLsizei>(count_));
  set_gbuffer_colour_writes(f);
}

// Pass 2: every hit in front of pass 1's depth adds its weighted normal, depth and colour.
void SlimPass::accumulate(const Frame& f) {
  const GLuint fbo = current_->fbo.id();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  set_colour_writes(GL_TRUE);  // the light's depth-only view still needs the sums for its depth
  glClearNamedFramebufferfv(fbo, GL_COLOR, 0, kZero);
  glClearNamedFramebufferfv(fbo, GL_COLOR, 1, kZero);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  set_uniforms(accumulate_, f, f.options.statistics ? 1 : 0);
  accumulate_.use();
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, splat_sides(f.options), static_cast<GLsizei>(count_));
  glDisable(GL_BLEND);
}

// Pass 3: divide by Σw into the G-buffer; the deferred pass shades it with the rest.
void SlimPass::resolve(const Frame& f) {
  glBindFramebuffer(GL_FRAMEBUFFER, f.targets.gbuffer.id());
  set_gbuffer_colour_writes(f);
  const bool keep_depth = !f.depth_only;
  const gl::Program& program = keep_depth ? resolve_drawn_ : resolve_;
  glDepthFunc(keep_depth ? GL_GREATER : GL_ALWAYS);
  glDepthMask(keep_depth ? GL_FALSE : GL_TRUE);
  set_camera_uniforms(program, f.camera);
  program.use();
  glBindTextureUnit(0, current_->normal_weight.id());
  glBindTextureUnit(1, current_->depth_colour.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthMask(GL_TRUE);
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
  set_origin_uniforms(program_, slim_.origin(), f.camera);
  program_.set("u_count_stats", 0);
  program_.set("u_cull", f.slim_cull ? 1 : 0);
  program_.set("u_tight", 0);
  program_.set("u_sides", 4);
  program_.set("u_base", 0);
  program_.use();
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, slim_.balls());
  glBindVertexArray(f.empty_vao);
  glDrawArraysInstanced(GL_LINE_STRIP, 0, 5, static_cast<GLsizei>(slim_.count()));
}

}  // namespace quadrix::render
