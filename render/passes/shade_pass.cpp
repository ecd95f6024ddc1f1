#include "render/passes/shade_pass.h"

#include <fmt/format.h>

#include "render/shaders.h"

namespace quadrix::render {

ShadePass::ShadePass() {
  constexpr const char* kNames[] = {"shade phong", "shade envmap", "shade npr"};
  for (int mode = 0; mode < 3; ++mode)
    programs_[mode] = gl::Program(kNames[mode], shader_source("fullscreen.vert"),
                                  shader_source("shade.frag"), fmt::format("#define SHADING_MODE {}\n", mode));
}

void ShadePass::run(const Frame& f) {
  glBindFramebuffer(GL_FRAMEBUFFER, f.targets.output.id());
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  const auto& s = programs_[static_cast<int>(f.options.shading)];
  const Rgb& bg = f.options.background;
  set_camera_uniforms(s, f.camera);
  s.set("u_background", Eigen::Vector3f(bg[0] / 255.f, bg[1] / 255.f, bg[2] / 255.f));
  s.use();
  glBindTextureUnit(0, f.targets.normal_depth.id());
  glBindTextureUnit(1, f.targets.albedo.id());
  glBindVertexArray(f.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

}  // namespace quadrix::render
