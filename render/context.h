#pragma once
/// OpenGL 4.5 core contexts behind one interface, picked by name: `osmesa` (software,
/// headless), `egl` (surfaceless/device; the GPU path where there is one), `glfw` (a window), or
/// `auto` (the first that works, in the order egl, osmesa). Every context loads GL through glad.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace quadrix::render {

class GlContext {
public:
  virtual ~GlContext() = default;
  /// osmesa, egl or glfw.
  virtual std::string name() const = 0;
  /// GL_RENDERER and GL_VERSION strings.
  std::string description() const;
  /// Window contexts: show the default framebuffer; headless contexts: no-op.
  virtual void swap_buffers() {}
  /// Window contexts: true once the user closed the window.
  virtual bool should_close() const { return false; }
  /// Window contexts: the native window (GLFWwindow*), else nullptr.
  virtual void* native_window() const { return nullptr; }
};

struct ContextOptions {
  int width = 512;         ///< window/default framebuffer size (rendering uses its own FBOs)
  int height = 512;
  bool visible = false;    ///< glfw: show the window
  std::string title = "quadrix";
};

/// Creates and makes current a context by name (auto, osmesa, egl, glfw).
/// \throws GlError listing every context tried and why each failed.
std::unique_ptr<GlContext> create_context(std::string_view name, const ContextOptions& options = {});

/// Context names accepted by create_context.
std::vector<std::string> context_names();

/// The current context rasterizes on the CPU (Mesa's llvmpipe, softpipe, swrast), where a
/// triangle costs more than the fragments it covers: passes pick their proxies by it.
bool current_context_is_software();

namespace detail {
std::unique_ptr<GlContext> create_osmesa(const ContextOptions&);
std::unique_ptr<GlContext> create_egl(const ContextOptions&);
std::unique_ptr<GlContext> create_glfw(const ContextOptions&);
/// Checks the loaded GL version is ≥ 4.5; \throws GlError otherwise.
void check_gl_version(const char* context);
}  // namespace detail

}  // namespace quadrix::render
