// GLFW: a window with a 4.5 core context (needs an X display; tests use xvfb-run).
#include <glad/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <fmt/format.h>

#include "core/error.h"
#include "render/context.h"

namespace quadrix::render::detail {
namespace {

std::string g_glfw_error;
void on_error(int code, const char* text) { g_glfw_error = fmt::format("GLFW error 0x{:x}: {}", code, text); }

class GlfwContext final : public GlContext {
public:
  explicit GlfwContext(const ContextOptions& o) {
    glfwSetErrorCallback(on_error);
    if (!glfwInit()) throw GlError(fmt::format("glfwInit failed ({})", g_glfw_error.empty() ? "no display?" : g_glfw_error));
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, o.visible ? GLFW_TRUE : GLFW_FALSE);
    window_ = glfwCreateWindow(o.width, o.height, o.title.c_str(), nullptr, nullptr);
    if (!window_) {
      glfwTerminate();
      throw GlError(fmt::format("glfwCreateWindow 4.5 core failed ({})", g_glfw_error));
    }
    glfwMakeContextCurrent(window_);
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(glfwGetProcAddress))) {
      glfwDestroyWindow(window_);
      glfwTerminate();
      throw GlError("glad could not load OpenGL through glfwGetProcAddress");
    }
    check_gl_version("GLFW");
  }
  ~GlfwContext() override {
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
  std::string name() const override { return "glfw"; }
  void swap_buffers() override { glfwSwapBuffers(window_); }
  bool should_close() const override { return glfwWindowShouldClose(window_); }
  void* native_window() const override { return window_; }

private:
  GLFWwindow* window_ = nullptr;
};

}  // namespace

std::unique_ptr<GlContext> create_glfw(const ContextOptions& o) { return std::make_unique<GlfwContext>(o); }

}  // namespace quadrix::render::detail
