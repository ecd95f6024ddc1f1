#pragma once
/// Deferred shading: a full-screen pass from the G-buffer into the output image, one program per
/// Shading mode (Phong, environment line map, NPR cel shading with outlines) and shadowing, built
/// when a frame first needs it. The output is cleared to the background and the pass is drawn on
/// the far plane with the depth test GL_GREATER against the G-buffer's depth, so only pixels a
/// G-buffer pass drew run the shader (every covered pixel has depth < 1: prelude.glsl
/// covered_window_depth); on llvmpipe the shader otherwise ran on the background too.
#include <array>
#include <optional>

#include "render/passes/frame.h"

namespace quadrix::render {

class ShadePass final : public Pass {
public:
  ShadePass() = default;
  bool needed(const RenderOptions&) const override { return true; }
  void run(const Frame& frame) override;

private:
  /// The program of a mode and shadowing, compiled on first use. \throws GlError.
  const gl::Program& program(Shading mode, bool shadows);
  std::array<std::optional<gl::Program>, 6> programs_;  // [2 · Shading + shadows]
};

}  // namespace quadrix::render
