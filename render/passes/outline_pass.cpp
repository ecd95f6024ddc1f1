#include "render/passes/outline_pass.h"

#include <cmath>
#include <numbers>

#include "render/shaders.h"

namespace quadrix::render {

OutlinePass::OutlinePass() : program_("outline", shader_source("fullscreen.vert"), shader_source("outline.frag")) {}

void OutlinePass::run(const Frame& f) {
  const OutlineOptions& o = f.options.outline;
  glBindFramebuffer(GL_FRAMEBUFFER, f.targets.output.id());
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  set_camera_uniforms(program_, f.camera);
  program_.set("u_min_gap", static_cast<float>(o.depth_gap) * f.scene_radius);
  program_.set("u_depth_pixels", static_cast<float>(o.depth_pixels));
  program_.set("u_cos_crease", static_cast<float>(std::cos(o.crease_deg * std::numbers::pi / 180.0)));
  program_.use();
  glBindTextureUnit(0, f.targets.normal_depth.id());
  glBindVertexArray(f.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

}  // namespace quadrix::render
