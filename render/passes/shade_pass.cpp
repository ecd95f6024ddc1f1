#include "render/passes/shade_pass.h"

#include <fmt/format.h>

#include "render/shaders.h"

namespace quadrix::render {

const gl::Program& ShadePass::program(Shading mode, bool shadows) {
  constexpr const char* kNames[] = {"phong", "envmap", "npr"};
  const int m = static_cast<int>(mode);
  std::optional<gl::Program>& p = programs_[2 * m + (shadows ? 1 : 0)];
  if (!p)
    p.emplace(fmt::format("shade {}{}", kNames[m], shadows ? " shadows" : ""), shader_source("fullscreen.vert"),
              shader_source("shade.frag"),
              fmt::format("#define SHADING_MODE {}\n#define SHADOWS {}\n#define FULLSCREEN_AT_FAR 1\n", m, shadows ? 1 : 0));
  return *p;
}

void ShadePass::run(const Frame& f) {
  glBindFramebuffer(GL_FRAMEBUFFER, f.targets.output.id());
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  const Rgb& bg = f.options.background;
  const Eigen::Vector3f background(bg[0] / 255.f, bg[1] / 255.f, bg[2] / 255.f);
  const GLfloat clear[4] = {background.x(), background.y(), background.z(), 1.f};
  glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glClearNamedFramebufferfv(f.targets.output.id(), GL_COLOR, 0, clear);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDepthMask(GL_FALSE);
  const gl::Program& s = program(f.options.shading, f.shadow != nullptr);
  set_camera_uniforms(s, f.camera);
  s.set("u_background", background);
  if (f.shadow) {
    const ShadowMap& m = *f.shadow;
    s.set("u_eye_to_light", m.eye_to_light);
    s.set("u_light_proj", Eigen::Vector2f(m.proj22, m.proj32));
    s.set("u_shadow_texel", m.texel_world);
    s.set("u_shadow_softness", f.options.shadow_softness);
    s.set("u_shadow_size", static_cast<float>(m.size));
    glBindTextureUnit(2, m.depth);
  }
  s.use();
  glBindTextureUnit(0, f.targets.normal_depth.id());
  glBindTextureUnit(1, f.targets.albedo.id());
  glBindVertexArray(f.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
  glDisable(GL_DEPTH_TEST);
}

}  // namespace quadrix::render
