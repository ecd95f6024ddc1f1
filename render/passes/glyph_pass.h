#pragma once
/// Glyphs ([Sigg06] §3, DESIGN §6 glyphs): spheres, ellipsoids and capped cylinders, one
/// instanced polygon each around the exact projected outline (octagons around ellipses,
/// 12-gons around cylinders), ray-cast in the glyph's parameter space into the G-buffer.
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
  gl::Buffer glyphs_;      // spheres and ellipsoids first, then cylinders (ids keep the model's order)
  std::size_t count_ = 0;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();  // the centres are stored relative to it
  std::size_t cylinders_ = 0;
};

}  // namespace quadrix::render
