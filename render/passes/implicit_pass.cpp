#include "render/passes/implicit_pass.h"

#include <algorithm>
#include <chrono>

#include <fmt/format.h>

#include "core/error.h"
#include "core/implicit/surface.h"
#include "core/primitive.h"
#include "render/shaders.h"

namespace quadrix::render {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

AmpSettings amp_settings(const ImplicitSurface& surface, const AmpOptions& o) {
  const implicit::CompiledImplicit c = implicit::compile(surface);
  AmpSettings s;
  const double diag = surface.bounds.diagonal();
  s.step = o.step > 0 ? o.step : diag / std::max(o.step_divisions, 1.0);
  std::vector<double> values, slopes;
  constexpr int n = 16;
  const Eigen::Vector3d lo = surface.bounds.min, ext = surface.bounds.max - surface.bounds.min;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector3d p = lo + ext.cwiseProduct(Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5) / n);
        const implicit::ValueGradient vg = c.expression.value_gradient(p, c.parameters);
        if (std::isfinite(vg.value)) values.push_back(std::abs(vg.value));
        if (vg.gradient.allFinite()) slopes.push_back(vg.gradient.norm());
      }
  s.tau1 = o.tau1 > 0 ? o.tau1 : 0.05 * median(values);
  s.tau2 = o.tau2 > 0 ? o.tau2 : 2 * s.tau1;
  s.tau3 = o.tau3 > 0 ? o.tau3 : 0.1 * median(slopes);
  s.taylor = o.test == RootTest::taylor;
  s.newton_fraction = std::max(o.newton_fraction, 0.0);
  s.remainder = std::max(o.remainder, 0.0);
  s.min_step = s.step * o.min_step_fraction;
  s.bisections = o.bisections;
  s.max_steps = o.max_steps;
  return s;
}

void ImplicitPass::upload(std::span<const ImplicitSurface> surfaces, const AmpOptions& options) {
  if (surfaces.size() > kMaxPrimitiveIndex + 1)
    throw InvalidInput(fmt::format("{} implicit surfaces: the GL renderer draws at most 2^{}", surfaces.size(),
                                   kPrimitiveIndexBits));
  const auto start = std::chrono::steady_clock::now();
  std::vector<Surface> out;
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const ImplicitSurface& s = surfaces[i];
    const implicit::CompiledImplicit c = implicit::compile(s);
    Surface g;
    const Eigen::Vector3d centre = s.bounds.centre();
    g.far = centre.cwiseAbs().maxCoeff() > kImplicitFarFactor * s.bounds.diagonal();
    if (g.far) g.origin = centre;
    const std::string code =
        std::string(shader_source("implicit_lib.glsl")) +
        c.expression.glsl("S", g.far ? implicit::GlslPrecision::double_ : implicit::GlslPrecision::single);
    g.program = gl::Program(fmt::format("implicit {}", i), shader_source("fullscreen.vert"),
                            shader_source("implicit.frag"), code);
    g.parameter_names = c.expression.parameters();
    g.parameters = c.parameters;
    g.bounds = s.bounds;
    g.amp = amp_settings(s, options);
    const Rgb col = s.colour.value_or(Rgb{200, 200, 200});
    g.colour = col[0] | (col[1] << 8) | (col[2] << 16);
    out.push_back(std::move(g));
  }
  surfaces_ = std::move(out);
  options_ = options;
  compile_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void ImplicitPass::set_parameters(std::size_t i, const std::map<std::string, double>& values) {
  Surface& s = surfaces_.at(i);
  for (const auto& [name, v] : values) {
    const auto it = std::find(s.parameter_names.begin(), s.parameter_names.end(), name);
    if (it == s.parameter_names.end())
      throw InvalidInput(fmt::format("implicit surface {} has no parameter '{}'", i, name));
    s.parameters[it - s.parameter_names.begin()] = v;
  }
}

void ImplicitPass::run(const Frame& f) {
  begin_gbuffer_draw(f);
  const Eigen::Vector3d eye = f.camera.target_world - f.camera.target_minus_eye.cast<double>();
  glBindVertexArray(f.empty_vao);
  for (std::size_t i = 0; i < surfaces_.size(); ++i) {
    const Surface& s = surfaces_[i];
    const gl::Program& p = s.program;
    set_camera_uniforms(p, f.camera);
    // Relative to the surface's origin, in double before the cast.
    p.set("u_eye", Eigen::Vector3f((eye - s.origin).cast<float>()));
    p.set("u_box_min", Eigen::Vector3f((s.bounds.min - s.origin).cast<float>()));
    p.set("u_box_max", Eigen::Vector3f((s.bounds.max - s.origin).cast<float>()));
    if (s.far) {
      p.set("S_origin", s.origin);
      for (std::size_t k = 0; k < s.parameters.size(); ++k) p.set(fmt::format("S_p{}", k).c_str(), s.parameters[k]);
    } else {
      p.set("S_origin", Eigen::Vector3f::Zero().eval());
      for (std::size_t k = 0; k < s.parameters.size(); ++k)
        p.set(fmt::format("S_p{}", k).c_str(), static_cast<float>(s.parameters[k]));
    }
    p.set("u_step", static_cast<float>(s.amp.step));
    p.set("u_tau", Eigen::Vector3f(float(s.amp.tau1), float(s.amp.tau2), float(s.amp.tau3)));
    p.set("u_taylor", s.amp.taylor ? 1 : 0);
    p.set("u_newton", static_cast<float>(s.amp.newton_fraction));
    p.set("u_remainder", static_cast<float>(s.amp.remainder));
    p.set("u_min_step", static_cast<float>(s.amp.min_step));
    p.set("u_bisections", s.amp.bisections);
    p.set("u_max_steps", s.amp.max_steps);
    p.set("u_colour", s.colour);
    p.set("u_id", primitive_id(PrimitiveKind::implicit, i));
    p.use();
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
}

}  // namespace quadrix::render
