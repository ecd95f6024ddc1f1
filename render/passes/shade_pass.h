#pragma once
/// Deferred shading: a full-screen pass from the G-buffer into the output image, one program per
/// Shading mode (Phong, environment line map, NPR cel shading with outlines).
#include <array>

#include "render/passes/frame.h"

namespace quadrix::render {

class ShadePass final : public Pass {
public:
  ShadePass();  ///< compiles a program per mode. \throws GlError.
  bool needed(const RenderOptions&) const override { return true; }
  void run(const Frame& frame) override;

private:
  std::array<gl::Program, 3> programs_;  // indexed by Shading
};

}  // namespace quadrix::render
