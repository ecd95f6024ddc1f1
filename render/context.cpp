#include "render/context.h"

#include <glad/gl.h>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix::render {

std::string GlContext::description() const {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return fmt::format("{} ({}, OpenGL {})", name(), r ? r : "?", v ? v : "?");
}

std::vector<std::string> context_names() { return {"auto", "osmesa", "egl", "glfw"}; }

bool current_context_is_software() {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  if (!r) return false;
  const std::string_view s(r);
  return s.find("llvmpipe") != s.npos || s.find("softpipe") != s.npos || s.find("swrast") != s.npos;
}

std::unique_ptr<GlContext> create_context(std::string_view name, const ContextOptions& options) {
  using Factory = std::unique_ptr<GlContext> (*)(const ContextOptions&);
  std::vector<std::pair<std::string, Factory>> order;
  if (name == "auto") order = {{"egl", detail::create_egl}, {"osmesa", detail::create_osmesa}};
  else if (name == "osmesa") order = {{"osmesa", detail::create_osmesa}};
  else if (name == "egl") order = {{"egl", detail::create_egl}};
  else if (name == "glfw") order = {{"glfw", detail::create_glfw}};
  else throw InvalidInput(fmt::format("unknown GL context '{}' (auto, osmesa, egl, glfw)", name));
  std::string failures;
  for (const auto& [n, factory] : order) {
    try {
      return factory(options);
    } catch (const std::exception& e) {
      failures += fmt::format("\n  {}: {}", n, e.what());
    }
  }
  throw GlError(fmt::format("no usable OpenGL 4.5 context; tried:{}", failures));
}

namespace detail {
void check_gl_version(const char* context) {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 45)
    throw GlError(fmt::format("{} gave OpenGL {}.{}, 4.5 core is required", context, major, minor));
}
}  // namespace detail

}  // namespace quadrix::render
