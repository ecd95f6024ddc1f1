#include "render/passes/glyph_pass.h"

#include <cmath>
#include <string>
#include <tuple>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <fmt/format.h>

#include "core/error.h"
#include "core/limits.h"
#include "core/primitive.h"
#include "render/context.h"
#include "render/shaders.h"

namespace quadrix::render {
namespace {

// std430 layout of `Glyph` in glyph.vert (8 vec4 = 128 bytes).
struct GpuGlyph {
  float centre_hi[4];
  float centre_lo[4];
  float inv[3][4];
  float s0[4], s1[4];  // S / s² (six entries), then s (the glyph's size)
  float axis[4];
};
static_assert(sizeof(GpuGlyph) == 128);

// A unit vector orthogonal to the unit vector a.
Eigen::Vector3d orthogonal(const Eigen::Vector3d& a) {
  const Eigen::Vector3d t = std::abs(a.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return a.cross(t).normalized();
}

// `origin`: the glyphs' origin, which the stored centre is relative to.
GpuGlyph pack(const Glyph& g, std::size_t index, const FixedOrigin& origin) {
  // M maps the parameter space (unit sphere, or unit cylinder |u_z| ≤ 1) to world offsets.
  Eigen::Matrix3d M;
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  double disc_radius = 0;  // cylinder
  switch (g.kind) {
    case GlyphKind::sphere: M = g.radius * Eigen::Matrix3d::Identity(); break;
    case GlyphKind::ellipsoid: M = g.axes; break;
    case GlyphKind::cylinder: {
      axis = g.axes.col(0);
      const double h = axis.norm();
      const Eigen::Vector3d a = axis / h, e1 = orthogonal(a), e2 = a.cross(e1);
      M.col(0) = g.radius * e1;
      M.col(1) = g.radius * e2;
      M.col(2) = axis;
      disc_radius = g.radius;
      break;
    }
  }
  // The glyph's size s (its longest semi-axis): S is stored as S / s², so neither S nor the
  // projection's fourth powers of lengths leave float's range for huge or tiny glyphs.
  const double size = M.colwise().stableNorm().maxCoeff();
  const Eigen::Matrix3d inv = M.inverse();
  if (size > 0 && size < kMinWorldSize)
    throw InvalidInput(fmt::format("glyph {}: its size {:g} is below {:g}, the smallest the GL renderer draws", index,
                                   size, kMinWorldSize));
  if (!(size > 0) || !inv.allFinite() || !(std::abs((M / size).determinant()) > 0))
    throw InvalidInput(fmt::format("glyph {}: its axes are singular (no volume)", index));
  Eigen::Matrix3d S;  // (M Mᵀ, or one end disc's for a cylinder) / s²
  if (g.kind == GlyphKind::cylinder) {
    const Eigen::Vector3d a = axis.normalized();
    S = (disc_radius / size) * (disc_radius / size) * (Eigen::Matrix3d::Identity() - a * a.transpose());
  } else {
    S = (M / size) * (M / size).transpose();
  }
  GpuGlyph p{};
  const FixedOrigin::Offset cs = origin.offset(g.centre - origin.origin);
  for (int i = 0; i < 3; ++i) {
    p.centre_hi[i] = bits_float(static_cast<std::uint32_t>(cs.q[i]));
    p.centre_lo[i] = cs.rest[i];
    for (int j = 0; j < 3; ++j) p.inv[i][j] = float(inv(i, j));
    p.axis[i] = float(axis[i]);
  }
  p.centre_hi[3] = float(static_cast<int>(g.kind));
  const Rgb col = g.colour.value_or(Rgb{200, 200, 200});
  p.centre_lo[3] = bits_float(col[0] | (col[1] << 8) | (col[2] << 16));
  p.inv[0][3] = bits_float(static_cast<std::uint32_t>(primitive_id(PrimitiveKind::glyph, index)));
  p.s0[0] = float(S(0, 0)), p.s0[1] = float(S(1, 1)), p.s0[2] = float(S(2, 2)), p.s0[3] = float(S(0, 1));
  p.s1[0] = float(S(1, 2)), p.s1[1] = float(S(0, 2)), p.s1[2] = float(size);
  // The shortest semi-axis: the glyph holds the ball of that radius (glyph_occluder.vert).
  if (g.kind != GlyphKind::cylinder) p.s1[3] = float(Eigen::JacobiSVD<Eigen::Matrix3d>(M).singularValues().minCoeff());
  return p;
}

std::string with_lib(std::string_view stage) { return std::string(shader_source("glyph_lib.glsl")) + "\n" + std::string(stage); }

}  // namespace

GlyphPass::GlyphPass()
    : software_(current_context_is_software()),
      program_("glyph", with_lib(shader_source("glyph.vert")), with_lib(shader_source("glyph.frag"))) {
  occluder_ = gl::Program("glyph occluders", with_lib(shader_source("glyph_occluder.vert")), shader_source("glyph_occluder.frag"));
  nearest_ = gl::Program("glyph nearest hits", with_lib(shader_source("glyph.vert")), with_lib(shader_source("glyph.frag")),
                         "#define GLYPH_NEAREST 1\n");
  resolve_ = gl::Program("glyph resolve", shader_source("fullscreen.vert"), with_lib(shader_source("glyph_resolve.frag")));
}

void GlyphPass::upload(std::span<const Glyph> glyphs) {
  if (glyphs.size() > kMaxPrimitiveIndex + 1)
    throw InvalidInput(
        fmt::format("{} glyphs: the GL renderer draws at most 2^{}", glyphs.size(), kPrimitiveIndexBits));
  Box3 box;
  for (const Glyph& g : glyphs) box.extend(g.centre);
  origin_ = FixedOrigin::of(box);
  std::vector<GpuGlyph> data;
  data.reserve(glyphs.size());
  cylinders_ = 0;
  for (const bool cylinders : {false, true})
    for (std::size_t i = 0; i < glyphs.size(); ++i)
      if ((glyphs[i].kind == GlyphKind::cylinder) == cylinders) {
        data.push_back(pack(glyphs[i], i, origin_));
        cylinders_ += cylinders;
      }
  glyphs_ = gl::make_buffer(static_cast<GLsizeiptr>(data.size() * sizeof(GpuGlyph)), data.data());
  count_ = data.size();
}

void GlyphPass::draw_proxies(const gl::Program& program, const Frame& f, bool count_statistics, bool rectangles) const {
  const RenderOptions& o = f.options;
  set_camera_uniforms(program, f.camera);
  set_origin_uniforms(program, origin_, f.camera);
  program.set("u_cull", o.cull ? 1 : 0);
  program.set("u_count_stats", count_statistics && o.statistics ? 1 : 0);
  program.set("u_proxy", o.glyph_proxies ? 1 : 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, glyphs_.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, f.stats_buffer);
  glBindVertexArray(f.empty_vao);
  // Octagons around ellipses leave 5.2 % of their area outside; the hull of a cylinder's two cap
  // ellipses gets 12 support lines (NoGlyphPixelLiesOutsideItsProxy prints the measured waste).
  const std::size_t ellipses = count_ - cylinders_;
  // Rectangles: a quarter of the octagon's triangles; on llvmpipe the cost per triangle outweighs
  // the fragments they add (RenderOptions::glyph_rectangles, by default on software rasterizers).
  const int ellipse_sides = rectangles ? 4 : 8, cylinder_sides = rectangles ? 4 : 12;
  for (const auto& [first, count, sides] :
       {std::tuple{std::size_t(0), ellipses, ellipse_sides}, std::tuple{ellipses, cylinders_, cylinder_sides}}) {
    if (count == 0) continue;
    program.set("u_first", static_cast<int>(first));
    program.set("u_sides", sides);
    program.use();
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, sides, static_cast<GLsizei>(count));
  }
}

void GlyphPass::run(const Frame& f) {
  begin_gbuffer_draw(f);
  if (f.options.glyph_early_depth.value_or(!software_) && !f.options.glyph_proxies) {
    run_early_depth(f);
    return;
  }
  draw_proxies(program_, f, true, f.options.glyph_rectangles.value_or(software_));
}

void GlyphPass::run_early_depth(const Frame& f) {
  const std::size_t pixels = static_cast<std::size_t>(f.targets.width) * f.targets.height;
  if (pixels > nearest_pixels_) {
    nearest_buffer_ = gl::make_buffer(static_cast<GLsizeiptr>(pixels * 2 * sizeof(GLuint)), nullptr);
    nearest_pixels_ = pixels;
  }
  const GLuint none[2] = {~0u, ~0u};
  // The previous frame's resolve reads this buffer (the light's view, then the camera's, share
  // it). llvmpipe cleared it while that resolve still ran: the shadow map lost glyph texels in 5
  // runs of 6 (ShadowsOutlines.DefaultMapSizeMatchesShadowRays with this path in the light's
  // view). The barrier makes the clear wait for the shaders before it.
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  glClearNamedBufferSubData(nearest_buffer_.id(), GL_RG32UI, 0, static_cast<GLsizeiptr>(pixels * 2 * sizeof(GLuint)),
                            GL_RG_INTEGER, GL_UNSIGNED_INT, none);
  // (1) Occluders: depth only, spheres and ellipsoids (stored first).
  for (GLuint i = 0; i < 3; ++i) glColorMaski(i, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  const std::size_t ellipses = count_ - cylinders_;
  if (ellipses > 0) {
    set_camera_uniforms(occluder_, f.camera);
    set_origin_uniforms(occluder_, origin_, f.camera);
    occluder_.use();
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, glyphs_.id());
    glBindVertexArray(f.empty_vao);
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(ellipses));
  }
  // (2) Proxies behind the occluders fail the depth test before the shader; the rest keep the
  // nearest hit per pixel.
  glDepthMask(GL_FALSE);
  glDepthFunc(GL_LEQUAL);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, nearest_buffer_.id());
  nearest_.set("u_index_pass", 0);
  // Polygons around the outline where triangles are cheap (hardware), rectangles on a software
  // rasterizer, as the direct path (it took rectangles everywhere: 21.5 % of each sphere's proxy
  // outside it instead of 5.2 %).
  const bool rectangles = f.options.glyph_rectangles.value_or(software_);
  draw_proxies(nearest_, f, true, rectangles);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  nearest_.set("u_index_pass", 1);
  draw_proxies(nearest_, f, false, rectangles);  // the same fragments again: counted once
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  // (3) That glyph's ray per pixel: the G-buffer and the depth (depth-tested as the other passes).
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
  set_gbuffer_colour_writes(f);
  set_camera_uniforms(resolve_, f.camera);
  set_origin_uniforms(resolve_, origin_, f.camera);
  resolve_.set("u_cull", f.options.cull ? 1 : 0);
  resolve_.use();
  glBindVertexArray(f.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

}  // namespace quadrix::render
