#pragma once
/// Glyphs ([Sigg06] §3, DESIGN §6 glyphs): spheres, ellipsoids and capped cylinders, one
/// instanced polygon each around the exact projected outline (octagons around ellipses,
/// 12-gons around cylinders), ray-cast in the glyph's parameter space into the G-buffer.
///
/// On a software rasterizer the default is the direct path with rectangles (RenderOptions::
/// glyph_rectangles: measured fastest there), elsewhere the early-depth path below with the
/// polygons (unmeasured on a GPU: none was lent).
///
/// Early-depth path (RenderOptions::glyph_early_depth): a fragment that writes its hit's depth
/// keeps llvmpipe from testing depth before the shader, so every proxy fragment of every glyph
/// behind the surface would be ray-cast. Instead: (1) depth-only occluders, a square inside each
/// sphere and ellipsoid at a depth no nearer than the glyph there (glyph_occluder.vert); (2) the
/// proxies (polygons, or rectangles where glyph_rectangles says), depth-tested before the shader against them and writing no depth, keep
/// the nearest hit's depth per pixel (atomic min), then, drawn again, the index of the glyph hit
/// at that depth; (3) one ray per pixel into that glyph writes the G-buffer and the depth
/// (glyph_resolve.frag). Exact: the occluders' depth bounds the nearest glyph's from behind, so
/// it is never culled.
#include <span>

#include "core/model.h"
#include "render/passes/frame.h"

namespace quadrix::render {

class GlyphPass final : public Pass {
public:
  GlyphPass();  ///< compiles the program. \throws GlError.
  /// \throws InvalidInput past kMaxPrimitiveIndex glyphs or for a glyph with singular axes,
  /// GlError (out of GPU memory).
  void upload(std::span<const Glyph> glyphs);
  std::size_t count() const { return count_; }
  bool needed(const RenderOptions&) const override { return count_ > 0; }
  void run(const Frame& frame) override;

private:
  void draw_proxies(const gl::Program& program, const Frame& frame, bool count_statistics, bool rectangles) const;
  void run_early_depth(const Frame& frame);

  bool software_ = false;  // render/context.h current_context_is_software, at construction
  gl::Program program_;
  gl::Program occluder_, nearest_, resolve_;  // the early-depth path
  gl::Buffer nearest_buffer_;  // per pixel: the nearest hit's window depth bits, its glyph's index
  std::size_t nearest_pixels_ = 0;
  gl::Buffer glyphs_;      // spheres and ellipsoids first, then cylinders (ids keep the model's order)
  std::size_t count_ = 0;
  FixedOrigin origin_;  // the centres are stored relative to it
  std::size_t cylinders_ = 0;
};

}  // namespace quadrix::render
