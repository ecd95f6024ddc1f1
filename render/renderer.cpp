#include "render/renderer.h"

#include <glad/gl.h>

#include <chrono>
#include <cstring>

#include <fmt/format.h>

#include "core/bounds.h"
#include "core/error.h"
#include "render/context.h"
#include "render/gl/objects.h"
#include "render/shaders.h"

#ifndef GL_FRAGMENT_SHADER_INVOCATIONS_ARB
#define GL_FRAGMENT_SHADER_INVOCATIONS_ARB 0x82F4
#endif

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

struct Split {
  Eigen::Vector3f hi, lo;
};
Split split(const Eigen::Vector3d& p) {
  const Eigen::Vector3f hi = p.cast<float>();
  return {hi, (p - hi.cast<double>()).cast<float>()};
}

float bits_float(std::uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

GpuTet pack(const TetPatch& t, std::int32_t id) {
  const Eigen::Vector3d c = t.centroid();
  std::array<Eigen::Vector3d, 4> p = t.corners;
  if ((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]) < 0) std::swap(p[1], p[2]);
  double s = 0;
  for (const auto& q : p) s = std::max(s, (q - c).norm());
  // Relative to the centroid already; scaled by s so local coordinates are O(1).
  const Quadric local = t.quadric.to_local(Eigen::Vector3d::Zero(), s).normalized();
  GpuTet g{};
  const Split cs = split(c);
  for (int i = 0; i < 3; ++i) {
    g.centre_hi[i] = cs.hi[i];
    g.centre_lo[i] = cs.lo[i];
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

// std430 layout of `Ball` in slim.vert (6 vec4 = 96 bytes).
struct GpuBall {
  float centre_hi[4];
  float centre_lo[4];
  float q0[4], q1[4], q2[4];
  float clip[4];
};
static_assert(sizeof(GpuBall) == 96);

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
  if (b.clip) {
    const double n = b.clip->n.norm();
    if (n > 0)
      for (int i = 0; i < 3; ++i) g.clip[i] = float(b.clip->n[i] / n);
    if (n > 0) g.clip[3] = float(b.clip->d / n);
  }
  return g;
}

struct Mesh {
  gl::VertexArray vao;
  gl::Buffer vbo;
  GLsizei vertices = 0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Rgb colour{180, 180, 190};
};

}  // namespace

bool has_pipeline_statistics() {
  GLint n = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &n);
  for (GLint i = 0; i < n; ++i) {
    const auto* e = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, i));
    if (e && std::strcmp(e, "GL_ARB_pipeline_statistics_query") == 0) return true;
  }
  return false;
}

struct Renderer::Impl {
  GlContext* context;
  gl::Program tet_program, mesh_program;
  gl::Program shade_programs[3];  // one per Shading mode
  gl::Program slim_visibility, slim_accumulate, slim_resolve, slim_outline;
  gl::Buffer balls;
  std::size_t ball_count = 0;
  gl::Texture acc_normal_weight, acc_depth_colour;
  gl::Framebuffer acc_fbo;
  bool acc_half = false;
  gl::VertexArray empty_vao;
  gl::Buffer tets, stats;
  gl::Buffer tet_indices;  // 12 per tetrahedron: its 4 faces over vertices 4·t + corner
  gl::VertexArray tet_vao;  // holds tet_indices as its element buffer
  std::size_t tet_count = 0;
  std::optional<Mesh> mesh;
  int width = 0, height = 0;
  gl::Texture normal_depth, albedo, ids, depth, colour;
  gl::Framebuffer gbuffer, final_fbo;
  gl::Query q_samples, q_invocations;
  bool pipeline_stats = false;

  void resize(int w, int h) {
    if (w == width && h == height) return;
    width = w, height = h;
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
    final_fbo = gl::Framebuffer(fb);
    glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT0, colour.id(), 0);
    if (glCheckNamedFramebufferStatus(fb, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw GlError("output framebuffer incomplete");
    gl::check_error("allocating render targets");
    acc_fbo.reset();  // re-made on demand with the new size
  }

  // Accumulation targets for SLIM pass 2; they share the G-buffer's depth texture.
  void ensure_accumulation(bool half) {
    if (acc_fbo && acc_half == half) return;
    acc_half = half;
    const GLenum format = half ? GL_RGBA16F : GL_RGBA32F;
    acc_normal_weight = gl::make_texture_2d(format, width, height);
    acc_depth_colour = gl::make_texture_2d(format, width, height);
    GLuint fb = 0;
    glCreateFramebuffers(1, &fb);
    acc_fbo = gl::Framebuffer(fb);
    glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT0, acc_normal_weight.id(), 0);
    glNamedFramebufferTexture(fb, GL_COLOR_ATTACHMENT1, acc_depth_colour.id(), 0);
    glNamedFramebufferTexture(fb, GL_DEPTH_ATTACHMENT, depth.id(), 0);
    const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(fb, 2, bufs);
    if (glCheckNamedFramebufferStatus(fb, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw GlError("SLIM accumulation framebuffer incomplete");
  }
};

Renderer::Renderer(GlContext& context) : impl_(std::make_unique<Impl>()) {
  impl_->context = &context;
  impl_->tet_program = gl::Program("tet", shader_source("tet.vert"), shader_source("tet.frag"));
  impl_->mesh_program = gl::Program("mesh", shader_source("mesh.vert"), shader_source("mesh.frag"));
  for (int mode = 0; mode < 3; ++mode)
    impl_->shade_programs[mode] = gl::Program("shade", shader_source("fullscreen.vert"), shader_source("shade.frag"),
                                              fmt::format("#define SHADING_MODE {}\n", mode));
  impl_->slim_visibility = gl::Program("slim pass 1", shader_source("slim.vert"), shader_source("slim.frag"),
                                       "#define SLIM_PASS 1\n");
  impl_->slim_accumulate = gl::Program("slim pass 2", shader_source("slim.vert"), shader_source("slim.frag"),
                                       "#define SLIM_PASS 2\n");
  impl_->slim_resolve = gl::Program("slim pass 3", shader_source("fullscreen.vert"), shader_source("slim_resolve.frag"));
  impl_->slim_outline = gl::Program("slim outline", shader_source("slim.vert"), shader_source("slim_outline.frag"),
                                    "#define SLIM_OUTLINE 1\n");
  impl_->empty_vao = gl::make_vertex_array();
  impl_->stats = gl::make_buffer(4 * sizeof(GLuint), nullptr, GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
  impl_->q_samples = gl::make_query(GL_SAMPLES_PASSED);
  impl_->pipeline_stats = has_pipeline_statistics();
  if (impl_->pipeline_stats) impl_->q_invocations = gl::make_query(GL_FRAGMENT_SHADER_INVOCATIONS_ARB);
  gl::check_error("renderer setup");
}

Renderer::~Renderer() = default;

void Renderer::set_model(const Model& model) {
  if (!model.glyphs.empty())
    throw InvalidInput("the GL renderer does not draw glyphs yet: use --backend cpu");
  std::vector<GpuTet> data;
  data.reserve(model.tets.size());
  for (std::size_t i = 0; i < model.tets.size(); ++i)
    data.push_back(pack(model.tets[i], static_cast<std::int32_t>((2 << 28) | i)));
  if (data.size() > (std::size_t(1) << 29))
    throw InvalidInput(fmt::format("{} tetrahedron patches: the GL renderer draws at most 2^29", data.size()));
  impl_->tets = gl::make_buffer(static_cast<GLsizeiptr>(data.size() * sizeof(GpuTet)), data.data());
  impl_->tet_count = data.size();
  // Faces with outward counter-clockwise order for a positively oriented tetrahedron (pack()
  // orients them): corners of each face, as tet.vert's kFace.
  constexpr std::array<std::uint32_t, 12> kFace{1, 2, 3, 0, 3, 2, 0, 1, 3, 0, 2, 1};
  std::vector<std::uint32_t> indices(12 * data.size());
  for (std::size_t t = 0; t < data.size(); ++t)
    for (std::size_t j = 0; j < 12; ++j) indices[12 * t + j] = static_cast<std::uint32_t>(4 * t) + kFace[j];
  impl_->tet_indices = gl::make_buffer(static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data());
  impl_->tet_vao = gl::make_vertex_array();
  glVertexArrayElementBuffer(impl_->tet_vao.id(), impl_->tet_indices.id());
  std::vector<GpuBall> balls;
  balls.reserve(model.slims.size());
  for (std::size_t i = 0; i < model.slims.size(); ++i)
    balls.push_back(pack(model.slims[i], static_cast<std::int32_t>((1 << 28) | i)));
  impl_->balls = gl::make_buffer(static_cast<GLsizeiptr>(balls.size() * sizeof(GpuBall)), balls.data());
  impl_->ball_count = balls.size();
}

void Renderer::set_mesh(const PolygonMesh& mesh, Rgb colour) {
  Mesh m;
  Box3 box;
  for (const auto& v : mesh.vertices) box.extend(v);
  m.origin = box.empty() ? Eigen::Vector3d::Zero() : box.centre();
  m.colour = colour;
  std::vector<float> data;  // position, normal per vertex; flat face normals
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto face = mesh.face(f);
    for (std::size_t k = 1; k + 1 < face.size(); ++k) {
      const Eigen::Vector3d a = mesh.vertices[face[0]], b = mesh.vertices[face[k]], c = mesh.vertices[face[k + 1]];
      Eigen::Vector3d n = (b - a).cross(c - a);
      if (!(n.norm() > 0)) continue;
      n.normalize();
      for (const auto* p : {&a, &b, &c}) {
        const Eigen::Vector3f q = (*p - m.origin).cast<float>();
        data.insert(data.end(), {q.x(), q.y(), q.z(), float(n.x()), float(n.y()), float(n.z())});
      }
    }
  }
  m.vertices = static_cast<GLsizei>(data.size() / 6);
  m.vbo = gl::make_buffer(static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data());
  m.vao = gl::make_vertex_array();
  glVertexArrayVertexBuffer(m.vao.id(), 0, m.vbo.id(), 0, 6 * sizeof(float));
  for (GLuint a = 0; a < 2; ++a) {
    glEnableVertexArrayAttrib(m.vao.id(), a);
    glVertexArrayAttribFormat(m.vao.id(), a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
    glVertexArrayAttribBinding(m.vao.id(), a, 0);
  }
  impl_->mesh = std::move(m);
}

FrameStats Renderer::draw(const Camera& camera, const RenderOptions& o) {
  auto& I = *impl_;
  const auto start = std::chrono::steady_clock::now();
  I.resize(camera.width, camera.height);
  FrameStats st;
  st.primitives = I.tet_count + I.ball_count;

  const Eigen::Matrix4f P = camera.projection().cast<float>();
  const Eigen::Matrix3f R = camera.view().topLeftCorner<3, 3>().cast<float>();
  const Split target = split(camera.target);
  const Eigen::Vector3d target_minus_eye = camera.target - camera.eye;
  const float target_distance = static_cast<float>(target_minus_eye.norm());

  glViewport(0, 0, I.width, I.height);
  glBindFramebuffer(GL_FRAMEBUFFER, I.gbuffer.id());
  const float zero[4] = {0, 0, 0, 0};
  const GLint minus_one[4] = {-1, -1, -1, -1};
  const float one = 1.0f;
  glClearNamedFramebufferfv(I.gbuffer.id(), GL_COLOR, 0, zero);
  glClearNamedFramebufferfv(I.gbuffer.id(), GL_COLOR, 1, zero);
  glClearNamedFramebufferiv(I.gbuffer.id(), GL_COLOR, 2, minus_one);
  glClearNamedFramebufferfv(I.gbuffer.id(), GL_DEPTH, 0, &one);
  using clock = std::chrono::steady_clock;
  auto mark = clock::now();
  const auto lap = [&](double& ms) {
    if (!o.time_passes) return;
    glFinish();
    const auto now = clock::now();
    ms = std::chrono::duration<double, std::milli>(now - mark).count();
    mark = now;
  };
  lap(st.ms_clear);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);

  if (o.statistics) {
    glBeginQuery(GL_SAMPLES_PASSED, I.q_samples.id());
    if (I.pipeline_stats) glBeginQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB, I.q_invocations.id());
    const GLuint z[4] = {0, 0, 0, 0};
    glNamedBufferSubData(I.stats.id(), 0, sizeof(z), z);
  }
  if (I.tet_count > 0) {
    // Front faces of each tetrahedron only: every covered pixel gets exactly one ray.
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    const auto& p = I.tet_program;
    p.use();
    p.set("u_proj", P);
    p.set("u_view_rot", R);
    p.set("u_target_hi", target.hi);
    p.set("u_target_lo", target.lo);
    p.set("u_target_minus_eye", Eigen::Vector3f(target_minus_eye.cast<float>()));
    p.set("u_target_distance", target_distance);
    p.set("u_cull", o.cull ? 1 : 0);
    p.set("u_count_stats", o.statistics ? 1 : 0);
    p.set("u_clip_eps", o.clip_eps);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, I.tets.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, I.stats.id());
    // Statistics frames draw instanced so each tetrahedron is counted exactly once; other frames
    // indexed, 4 vertex-shader runs per tetrahedron instead of 12 (measured on llvmpipe).
    p.set("u_indexed", o.statistics ? 0 : 1);
    if (o.statistics) {
      glBindVertexArray(I.empty_vao.id());
      glDrawArraysInstanced(GL_TRIANGLES, 0, 12, static_cast<GLsizei>(I.tet_count));
    } else {
      glBindVertexArray(I.tet_vao.id());
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(12 * I.tet_count), GL_UNSIGNED_INT, nullptr);
    }
  }
  if (I.mesh) {
    glDisable(GL_CULL_FACE);
    const auto& p = I.mesh_program;
    p.use();
    p.set("u_proj", P);
    p.set("u_view_rot", R);
    p.set("u_origin_minus_target", Eigen::Vector3f((I.mesh->origin - camera.target).cast<float>()));
    p.set("u_target_distance", target_distance);
    p.set("u_colour", Eigen::Vector3f(I.mesh->colour[0] / 255.f, I.mesh->colour[1] / 255.f, I.mesh->colour[2] / 255.f));
    p.set("u_id_base", 4 << 28);
    glBindVertexArray(I.mesh->vao.id());
    glDrawArrays(GL_TRIANGLES, 0, I.mesh->vertices);
  }
  lap(st.ms_geometry);

  if (I.ball_count > 0) {
    // SLIM, three passes ([Stoll06] §5.1.1). Pass 1: pushed-back depth of each ball's first hit.
    I.ensure_accumulation(o.slim_half_float);
    glDisable(GL_CULL_FACE);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, I.balls.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, I.stats.id());
    glBindVertexArray(I.empty_vao.id());
    const auto setup = [&](const gl::Program& p, int count_stats) {
      p.use();
      p.set("u_proj", P);
      p.set("u_view_rot", R);
      p.set("u_target_hi", target.hi);
      p.set("u_target_lo", target.lo);
      p.set("u_target_distance", target_distance);
      p.set("u_near", static_cast<float>(camera.near_plane));
      p.set("u_offset", o.slim_offset);
      p.set("u_count_stats", count_stats);
      p.set("u_cull", o.cull ? 1 : 0);
    };
    glBindFramebuffer(GL_FRAMEBUFFER, I.gbuffer.id());
    glColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glColorMaski(2, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    setup(I.slim_visibility, o.statistics ? 1 : 0);
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(I.ball_count));
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glColorMaski(2, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    // Pass 2: every hit in front of pass 1's depth adds its weighted normal, depth and colour.
    glBindFramebuffer(GL_FRAMEBUFFER, I.acc_fbo.id());
    glClearNamedFramebufferfv(I.acc_fbo.id(), GL_COLOR, 0, zero);
    glClearNamedFramebufferfv(I.acc_fbo.id(), GL_COLOR, 1, zero);
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_ONE, GL_ONE);
    setup(I.slim_accumulate, 0);
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(I.ball_count));
    glDisable(GL_BLEND);
    // Pass 3: divide by Σw into the G-buffer; the deferred pass below shades it with the rest.
    glBindFramebuffer(GL_FRAMEBUFFER, I.gbuffer.id());
    glDepthFunc(GL_ALWAYS);
    glDepthMask(GL_TRUE);
    I.slim_resolve.use();
    I.slim_resolve.set("u_proj", P);
    glBindTextureUnit(0, I.acc_normal_weight.id());
    glBindTextureUnit(1, I.acc_depth_colour.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthFunc(GL_LESS);
    lap(st.ms_slim);
  }
  if (o.statistics) {
    glEndQuery(GL_SAMPLES_PASSED);
    if (I.pipeline_stats) glEndQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB);
  }

  // Deferred shading into the output target.
  glBindFramebuffer(GL_FRAMEBUFFER, I.final_fbo.id());
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  const auto& s = I.shade_programs[static_cast<int>(o.shading)];
  s.use();
  s.set("u_view_rot", R);
  s.set("u_proj", P);
  s.set("u_viewport", Eigen::Vector2f(float(I.width), float(I.height)));
  s.set("u_background", Eigen::Vector3f(o.background[0] / 255.f, o.background[1] / 255.f, o.background[2] / 255.f));
  glBindTextureUnit(0, I.normal_depth.id());
  glBindTextureUnit(1, I.albedo.id());
  glBindVertexArray(I.empty_vao.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  if (o.slim_outlines && I.ball_count > 0) {
    const auto& p = I.slim_outline;
    p.use();
    p.set("u_proj", P);
    p.set("u_view_rot", R);
    p.set("u_target_hi", target.hi);
    p.set("u_target_lo", target.lo);
    p.set("u_target_distance", target_distance);
    p.set("u_near", static_cast<float>(camera.near_plane));
    p.set("u_count_stats", 0);
    p.set("u_cull", o.cull ? 1 : 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, I.balls.id());
    glDrawArraysInstanced(GL_LINE_STRIP, 0, 5, static_cast<GLsizei>(I.ball_count));
  }
  lap(st.ms_shading);
  glFinish();
  gl::check_error("draw");
  if (o.statistics) {
    GLuint64 v = 0;
    glGetQueryObjectui64v(I.q_samples.id(), GL_QUERY_RESULT, &v);
    st.fragments_hit = v;
    if (I.pipeline_stats) {
      glGetQueryObjectui64v(I.q_invocations.id(), GL_QUERY_RESULT, &v);
      st.fragments = v;
    } else {
      st.fragments = static_cast<std::uint64_t>(-1);
    }
    GLuint counts[4] = {0, 0, 0, 0};
    glGetNamedBufferSubData(I.stats.id(), 0, sizeof(counts), counts);
    st.culled = counts[0];
    st.slim_splat_fragments = counts[2];
    st.slim_hit_fragments = counts[3];
  }
  st.ms_total = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return st;
}

Image8 Renderer::read_colour() const {
  const auto& I = *impl_;
  Image8 img;
  img.width = I.width;
  img.height = I.height;
  img.rgba.resize(static_cast<std::size_t>(I.width) * I.height * 4);
  std::vector<std::uint8_t> tmp(img.rgba.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(I.colour.id(), 0, GL_RGBA, GL_UNSIGNED_BYTE, static_cast<GLsizei>(tmp.size()), tmp.data());
  const std::size_t row = static_cast<std::size_t>(I.width) * 4;
  for (int y = 0; y < I.height; ++y)
    std::memcpy(img.rgba.data() + y * row, tmp.data() + (I.height - 1 - y) * row, row);
  return img;
}

GBuffer Renderer::read_gbuffer() const {
  const auto& I = *impl_;
  const std::size_t n = static_cast<std::size_t>(I.width) * I.height;
  std::vector<float> nd(4 * n);
  std::vector<std::int32_t> ids(n);
  glGetTextureImage(I.normal_depth.id(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(nd.size() * 4), nd.data());
  glGetTextureImage(I.ids.id(), 0, GL_RED_INTEGER, GL_INT, static_cast<GLsizei>(ids.size() * 4), ids.data());
  gl::check_error("reading the G-buffer");
  GBuffer g;
  g.width = I.width;
  g.height = I.height;
  g.coverage.assign(n, 0);
  g.depth.assign(n, std::numeric_limits<float>::infinity());
  g.normal.assign(n, Eigen::Vector3f::Zero());
  g.primitive.assign(n, -1);
  for (int y = 0; y < I.height; ++y)
    for (int x = 0; x < I.width; ++x) {
      const std::size_t src = static_cast<std::size_t>(I.height - 1 - y) * I.width + x;
      const std::size_t dst = static_cast<std::size_t>(y) * I.width + x;
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
  glBlitNamedFramebuffer(I.final_fbo.id(), 0, 0, 0, I.width, I.height, 0, 0, window_width, window_height,
                         GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

}  // namespace quadrix::render
