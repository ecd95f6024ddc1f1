#include "render/passes/tet_pass.h"

#include <algorithm>
#include <array>
#include <cstdint>

#include <fmt/format.h>

#include "core/error.h"
#include "core/primitive.h"
#include "render/shaders.h"

namespace quadrix::render {
namespace {

// std430 layout of `Tet` in tet.vert (9 vec4 = 144 bytes).
struct GpuTet {
  float centre_hi[4];
  float centre_lo[4];
  float corner[4][4];
  float q0[4], q1[4], q2[4];
};
static_assert(sizeof(GpuTet) == 144);

// `origin`: the model's origin, which the stored centre is relative to (as quanta and a rest, so
// the shader's sum with the origin − target cancels exactly: a float hi + lo relative to a chunk
// holding a large and a tiny part rounded the tiny one's centre at the large one's scale).
GpuTet pack(const TetPatch& t, std::int32_t id, const FixedOrigin& origin) {
  const Eigen::Vector3d c = t.centroid();
  std::array<Eigen::Vector3d, 4> p = t.corners;
  if ((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]) < 0) std::swap(p[1], p[2]);
  double s = 0;
  for (const auto& q : p) s = std::max(s, (q - c).norm());
  // Relative to the centroid already; scaled by s so local coordinates are O(1).
  const Quadric local = t.quadric.to_local(Eigen::Vector3d::Zero(), s).normalized();
  GpuTet g{};
  const FixedOrigin::Offset cs = origin.offset(c - origin.origin);
  for (int i = 0; i < 3; ++i) {
    g.centre_hi[i] = bits_float(static_cast<std::uint32_t>(cs.q[i]));
    g.centre_lo[i] = cs.rest[i];
  }
  g.centre_hi[3] = static_cast<float>(s);
  const Rgb col = t.colour.value_or(Rgb{200, 200, 200});
  g.centre_lo[3] = bits_float(col[0] | (col[1] << 8) | (col[2] << 16));
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3f l = ((p[k] - c) / s).cast<float>();
    g.corner[k][0] = l.x(), g.corner[k][1] = l.y(), g.corner[k][2] = l.z();
  }
  g.corner[0][3] = bits_float(static_cast<std::uint32_t>(id));
  const auto& A = local.A;
  g.q0[0] = float(A(0, 0)), g.q0[1] = float(A(1, 1)), g.q0[2] = float(A(2, 2)), g.q0[3] = float(A(0, 1));
  g.q1[0] = float(A(1, 2)), g.q1[1] = float(A(0, 2)), g.q1[2] = float(local.b.x()), g.q1[3] = float(local.b.y());
  g.q2[0] = float(local.b.z()), g.q2[1] = float(local.c);
  return g;
}

}  // namespace

const gl::Program& TetPass::program(bool entry_face_depth, bool corner_colours) {
  std::optional<gl::Program>& p = programs_[2 * int(entry_face_depth) + int(corner_colours)];
  if (!p)
    p.emplace(fmt::format("tet{}{}", entry_face_depth ? " (entry-face depth)" : "", corner_colours ? " (corner colours)" : ""),
              shader_source("tet.vert"), shader_source("tet.frag"),
              fmt::format("{}#define TET_CORNER_COLOURS {}\n", entry_face_depth ? "" : "#define TET_EXACT_DEPTH 1\n",
                          corner_colours ? 1 : 0));
  return *p;
}

TetPass::TetPass()
    : depth_program_("depth from G-buffer", shader_source("fullscreen.vert"), shader_source("depth_from_gbuffer.frag")) {}

void TetPass::upload(std::span<const TetPatch> tets, bool tessellation) {
  tessellation_ = tessellation;
  if (tets.size() > kMaxPrimitiveIndex + 1)
    throw InvalidInput(fmt::format("{} tetrahedron patches: the GL renderer draws at most 2^{}", tets.size(),
                                   kPrimitiveIndexBits));
  std::vector<Box3> boxes;
  boxes.reserve(tets.size());
  for (const TetPatch& t : tets) boxes.push_back(bounds(t));
  chunks_ = make_chunks(boxes, {.chunk_size = kChunkSize});
  Box3 all;
  for (const Box3& b : boxes) all.extend(b);
  origin_ = FixedOrigin::of(all);
  selection_ = {};
  drawn_last_.assign(chunks_.size(), 0);
  has_history_ = false;
  // GPU slots in chunk order; each patch keeps its own id.
  std::vector<GpuTet> data;
  data.reserve(tets.size());
  for (std::size_t c = 0; c < chunks_.size(); ++c)
    for (std::uint32_t s = chunks_.first[c]; s < chunks_.first[c] + chunks_.count[c]; ++s) {
      const std::uint32_t i = chunks_.order[s];
      data.push_back(pack(tets[i], primitive_id(PrimitiveKind::tet, i), origin_));
    }
  tets_ = gl::make_buffer(static_cast<GLsizeiptr>(data.size() * sizeof(GpuTet)), data.data());
  count_ = data.size();
  // Faces with outward counter-clockwise order for a positively oriented tetrahedron (pack()
  // orients them): corners of each face, as tet.vert's kFace.
  constexpr std::array<std::uint32_t, 12> kFace{1, 2, 3, 0, 3, 2, 0, 1, 3, 0, 2, 1};
  std::vector<std::uint32_t> indices(12 * data.size());
  for (std::size_t t = 0; t < data.size(); ++t)
    for (std::size_t j = 0; j < 12; ++j) indices[12 * t + j] = static_cast<std::uint32_t>(4 * t) + kFace[j];
  indices_ = gl::make_buffer(static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data());
  // Per-corner colours (binding 2) per GPU slot (chunk order), in the corner order pack() leaves
  // (it may swap corners 1, 2).
  has_corner_colours_ = std::any_of(tets.begin(), tets.end(), [](const TetPatch& t) { return t.corner_colours.has_value(); });
  std::vector<std::uint32_t> colours(has_corner_colours_ ? 4 * tets.size() : 4, 0);
  if (has_corner_colours_)
    for (std::size_t slot = 0; slot < tets.size(); ++slot) {
      const std::size_t i = chunks_.order[slot];
      const TetPatch& t = tets[i];
      const Rgb c = t.colour.value_or(Rgb{200, 200, 200});
      std::array<Rgb, 4> cs = t.corner_colours.value_or(std::array<Rgb, 4>{c, c, c, c});
      const auto& p = t.corners;
      if ((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]) < 0) std::swap(cs[1], cs[2]);
      for (std::size_t k = 0; k < 4; ++k) colours[4 * slot + k] = cs[k][0] | (cs[k][1] << 8) | (cs[k][2] << 16);
    }
  corner_colours_ = gl::make_buffer(static_cast<GLsizeiptr>(colours.size() * sizeof(std::uint32_t)), colours.data());
  vao_ = gl::make_vertex_array();
  glVertexArrayElementBuffer(vao_.id(), indices_.id());
}

void TetPass::run(const Frame& f) {
  const RenderOptions& o = f.options;
  selection_ = select_chunks(chunks_, f.camera.world);
  // Entry-face depth needs the G-buffer to turn it back into hit depth: not for the light's
  // depth-only view (shadow map), which must hold the hit depth itself.
  const bool early_depth = o.tet_early_depth && tessellation_ && !f.depth_only;
  const gl::Program& program = this->program(early_depth, has_corner_colours_);
  begin_gbuffer_draw(f);
  // Front faces of each tetrahedron only: every covered pixel gets exactly one ray.
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  set_camera_uniforms(program, f.camera);
  set_origin_uniforms(program, origin_, f.camera);
  program.set("u_cull", o.cull ? 1 : 0);
  program.set("u_count_stats", o.statistics ? 1 : 0);
  program.set("u_clip_eps", o.clip_eps);
  program.set("u_base", 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, corner_colours_.id());
  // Statistics frames draw instanced so each tetrahedron is counted exactly once; other frames
  // indexed, 4 vertex-shader runs per tetrahedron instead of 12 (measured on llvmpipe).
  program.set("u_indexed", o.statistics ? 0 : 1);
  program.use();
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, tets_.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, f.stats_buffer);
  // The visible chunks, nearest first. With occlusion: first those drawn last frame (or, with
  // no history, the nearest eighth), then the rest that the depth drawn so far does not hide.
  const auto& visible = selection_.chunks;
  if (!o.tet_occlusion || visible.size() < kMinChunksForOcclusion) {
    draw_chunks(f, program, visible);
  } else {
    std::vector<std::uint32_t> first, rest;
    const std::size_t guess = std::max<std::size_t>(1, visible.size() / 8);
    for (std::size_t i = 0; i < visible.size(); ++i)
      ((has_history_ ? drawn_last_[visible[i]] != 0 : i < guess) ? first : rest).push_back(visible[i]);
    draw_chunks(f, program, first);
    const DepthTiles tiles = read_depth_tiles(f.targets);
    const Camera& cam = f.camera.world;
    std::fill(drawn_last_.begin(), drawn_last_.end(), std::uint8_t{0});
    // Chunks drawn in the first round that turn out hidden are not guessed again next frame.
    for (const std::uint32_t c : first) drawn_last_[c] = !box_occluded(chunks_.boxes[c], cam, tiles);
    std::vector<std::uint32_t> shown;
    for (const std::uint32_t c : rest) {
      if (box_occluded(chunks_.boxes[c], cam, tiles)) {
        ++selection_.occluded_chunks;
        selection_.occluded_primitives += chunks_.count[c];
      } else {
        shown.push_back(c);
        drawn_last_[c] = 1;
      }
    }
    draw_chunks(f, program, shown);
    has_history_ = true;
  }
  if (early_depth && f.depth_needed_after_tets) depth_from_gbuffer(f);
}

void TetPass::draw_chunks(const Frame& f, const gl::Program& program, std::span<const std::uint32_t> chunks) {
  if (chunks.empty()) return;
  if (f.options.statistics) {
    // Instanced, so each tetrahedron's faces are counted exactly once.
    glBindVertexArray(f.empty_vao);
    for (const std::uint32_t c : chunks) {
      program.set("u_base", static_cast<int>(chunks_.first[c]));
      glDrawArraysInstanced(GL_TRIANGLES, 0, 12, static_cast<GLsizei>(chunks_.count[c]));
    }
    return;
  }
  draw_counts_.clear();
  draw_offsets_.clear();
  for (const std::uint32_t c : chunks) {
    draw_counts_.push_back(static_cast<GLsizei>(12 * chunks_.count[c]));
    draw_offsets_.push_back(reinterpret_cast<const void*>(std::uintptr_t{12} * chunks_.first[c] * sizeof(std::uint32_t)));
  }
  glBindVertexArray(vao_.id());
  glMultiDrawElements(GL_TRIANGLES, draw_counts_.data(), GL_UNSIGNED_INT, draw_offsets_.data(),
                      static_cast<GLsizei>(draw_counts_.size()));
}

DepthTiles TetPass::read_depth_tiles(const FrameTargets& t) {
  depth_pixels_.resize(static_cast<std::size_t>(t.width) * t.height);
  glGetTextureImage(t.depth.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(depth_pixels_.size() * sizeof(float)),
                    depth_pixels_.data());
  return depth_tiles(depth_pixels_, t.width, t.height);
}

void TetPass::depth_from_gbuffer(const Frame& f) {
  const FrameTargets& t = f.targets;
  if (!depth_fbo_ || depth_generation_ != t.generation) {
    GLuint fb = 0;
    glCreateFramebuffers(1, &fb);
    depth_fbo_ = gl::Framebuffer(fb);
    depth_generation_ = t.generation;
    glNamedFramebufferTexture(fb, GL_DEPTH_ATTACHMENT, t.depth.id(), 0);
    glNamedFramebufferDrawBuffer(fb, GL_NONE);
    if (glCheckNamedFramebufferStatus(fb, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw GlError("depth-only framebuffer incomplete");
  }
  glBindFramebuffer(GL_FRAMEBUFFER, depth_fbo_.id());
  glDisable(GL_CULL_FACE);
  glDepthFunc(GL_ALWAYS);
  set_camera_uniforms(depth_program_, f.camera);
  depth_program_.use();
  glBindTextureUnit(0, t.normal_depth.id());
  glBindVertexArray(f.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthFunc(GL_LESS);
  glBindFramebuffer(GL_FRAMEBUFFER, t.gbuffer.id());
}

}  // namespace quadrix::render
