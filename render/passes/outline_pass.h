#pragma once
/// Silhouette and crease lines over the shaded image ([Sigg06] §5), from depth and normal
/// discontinuities of the G-buffer: the detector of core/outlines.h, run per pixel on the GPU.
/// Drawn for RenderOptions::outlines and for NPR shading.
#include "render/passes/frame.h"

namespace quadrix::render {

class OutlinePass final : public Pass {
public:
  OutlinePass();  ///< compiles the program. \throws GlError.
  bool needed(const RenderOptions& options) const override {
    return options.outlines || options.shading == Shading::npr;
  }
  void run(const Frame& frame) override;

private:
  gl::Program program_;
};

}  // namespace quadrix::render
