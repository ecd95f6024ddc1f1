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
  const ShadowMap none{.eye_to_light = Eigen::Matrix4f::Identity()};
  const ShadowMap& m = f.shadow ? *f.shadow : none;
  s.set("u_shadows", f.shadow ? 1 : 0);
  s.set("u_eye_to_light", m.eye_to_light);
  s.set("u_light_proj", Eigen::Vector2f(m.proj22, m.proj32));
  s.set("u_shadow_texel", m.texel_world);
  s.set("u_shadow_softness", f.options.shadow_softness);
  s.set("u_shadow_size", static_cast<float>(m.size));
  glBindTextureUnit(2, m.depth);
  s.use();
  glBindTextureUnit(0, f.targets.normal_depth.id());
  glBindTextureUnit(1, f.targets.albedo.id());
  glBindVertexArray(f.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

}  // namespace quadrix::render
