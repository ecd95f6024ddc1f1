#pragma once
/// Glyphs ([Sigg06] §3, DESIGN §6 glyphs): spheres, ellipsoids and capped cylinders, one
/// instanced octagon each around the exact projected outline, ray-cast in the glyph's parameter
/// space into the G-buffer.
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
  gl::Program program_;
  gl::Buffer glyphs_;
  std::size_t count_ = 0;
};

}  // namespace quadrix::render
