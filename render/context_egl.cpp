// EGL without a window: a device display (NVIDIA and Mesa's EGL_EXT_platform_device) first, then
// Mesa's surfaceless platform. Quadrix renders into FBOs, so no surface is needed.
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <glad/gl.h>

#include <fmt/format.h>

#include <cstring>
#include <string>

#include "core/error.h"
#include "render/context.h"

namespace quadrix::render::detail {
namespace {

bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)); p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

class EglContext final : public GlContext {
public:
  explicit EglContext(const ContextOptions&) {
    const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    auto get_platform_display =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    std::string tried;
    // 1. A device display: the GPU path on machines with a GPU and no X.
    if (get_platform_display && has_extension(client_ext, "EGL_EXT_platform_device")) {
      auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
      EGLDeviceEXT devices[16];
      EGLint count = 0;
      if (query_devices && query_devices(16, devices, &count)) {
        for (EGLint i = 0; i < count && !try_display(get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr)); ++i)
          tried += fmt::format(" device {}: {};", i, error_);
      }
    }
    // 2. Mesa's surfaceless platform (llvmpipe on machines without a GPU).
    if (!display_ && get_platform_display && has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
      if (!try_display(get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr)))
        tried += fmt::format(" surfaceless: {};", error_);
    }
    if (!display_) throw GlError(fmt::format("no EGL display with OpenGL 4.5 core:{}", tried.empty() ? " none found" : tried));
  }
  ~EglContext() override {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
  std::string name() const override { return "egl"; }

private:
  bool try_display(EGLDisplay d) {
    if (d == EGL_NO_DISPLAY) return fail("no display");
    EGLint major = 0, minor = 0;
    if (!eglInitialize(d, &major, &minor)) return fail(fmt::format("eglInitialize error 0x{:x}", eglGetError()));
    if (!eglBindAPI(EGL_OPENGL_API)) return fail("eglBindAPI(OpenGL) failed", d);
    const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8,
                                     EGL_BLUE_SIZE, 8, EGL_ALPHA_SIZE, 8, EGL_NONE};
    EGLConfig config;
    EGLint n = 0;
    if (!eglChooseConfig(d, config_attribs, &config, 1, &n) || n < 1) return fail("no RGBA8 OpenGL config", d);
    const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext ctx = eglCreateContext(d, config, EGL_NO_CONTEXT, ctx_attribs);
    if (ctx == EGL_NO_CONTEXT) return fail(fmt::format("eglCreateContext 4.5 core error 0x{:x}", eglGetError()), d);
    if (!eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
      eglDestroyContext(d, ctx);
      return fail("surfaceless eglMakeCurrent failed", d);
    }
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(eglGetProcAddress))) {
      eglDestroyContext(d, ctx);
      return fail("glad could not load OpenGL", d);
    }
    display_ = d;
    context_ = ctx;
    try {
      check_gl_version("EGL");
    } catch (const std::exception& e) {
      eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      eglDestroyContext(d, ctx);
      display_ = EGL_NO_DISPLAY;
      return fail(e.what(), d);
    }
    return true;
  }
  bool fail(std::string why, EGLDisplay d = EGL_NO_DISPLAY) {
    if (d != EGL_NO_DISPLAY) eglTerminate(d);
    error_ = std::move(why);
    return false;
  }

  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
  std::string error_;
};

}  // namespace

std::unique_ptr<GlContext> create_egl(const ContextOptions& o) { return std::make_unique<EglContext>(o); }

}  // namespace quadrix::render::detail
