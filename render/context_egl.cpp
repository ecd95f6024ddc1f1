// EGL without a window: a device display (NVIDIA and Mesa's EGL_EXT_platform_device) first, then
// Mesa's surfaceless platform. Quadrix renders into FBOs, so no surface is needed where the display
// has EGL_KHR_surfaceless_context; elsewhere a 16x16 pbuffer is made current. Configs are asked for
// with EGL_PBUFFER_BIT: EGL_SURFACE_TYPE defaults to window surfaces, which device and surfaceless
// displays do not offer. For tests and diagnosis, QUADRIX_EGL_PLATFORM=device|surfaceless tries
// one platform only and QUADRIX_EGL_PBUFFER=1 makes a pbuffer current even where surfaceless works.
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <glad/gl.h>

#include <fmt/format.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "core/error.h"
#include "core/log.h"
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
    const char* only = std::getenv("QUADRIX_EGL_PLATFORM");
    const std::string platform = only ? only : "";
    if (!platform.empty() && platform != "device" && platform != "surfaceless")
      throw GlError(fmt::format("QUADRIX_EGL_PLATFORM='{}': expected device or surfaceless", platform));
    const char* pbuffer = std::getenv("QUADRIX_EGL_PBUFFER");
    force_pbuffer_ = pbuffer && std::string(pbuffer) == "1";
    std::string tried;
    // 1. A device display: the GPU path on machines with a GPU and no X.
    if (platform != "surfaceless" && get_platform_display && has_extension(client_ext, "EGL_EXT_platform_device")) {
      auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
      EGLDeviceEXT devices[16];
      EGLint count = 0;
      if (query_devices && query_devices(16, devices, &count)) {
        for (EGLint i = 0; i < count && !display_; ++i) {
          if (try_display(get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr)))
            log::debug("egl: device {} of {}{}", i, count, surface_ ? ", pbuffer" : "");
          else
            tried += fmt::format(" device {}: {};", i, error_);
        }
      }
    }
    // 2. Mesa's surfaceless platform (llvmpipe on machines without a GPU).
    if (!display_ && platform != "device" && get_platform_display &&
        has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
      if (try_display(get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr)))
        log::debug("egl: Mesa surfaceless platform{}", surface_ ? ", pbuffer" : "");
      else
        tried += fmt::format(" surfaceless: {};", error_);
    }
    if (!display_) throw GlError(fmt::format("no EGL display with OpenGL 4.5 core:{}", tried.empty() ? " none found" : tried));
  }
  ~EglContext() override {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (surface_ != EGL_NO_SURFACE) eglDestroySurface(display_, surface_);
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
    const char* display_ext = eglQueryString(d, EGL_EXTENSIONS);
    const bool surfaceless = !force_pbuffer_ && has_extension(display_ext, "EGL_KHR_surfaceless_context");
    EGLConfig config = nullptr;
    EGLint n = 0;
    for (const EGLint surface_type : {EGLint(EGL_PBUFFER_BIT), EGLint(EGL_DONT_CARE)}) {
      if (surface_type == EGL_DONT_CARE && !surfaceless) break;
      const EGLint config_attribs[] = {EGL_SURFACE_TYPE, surface_type, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                       EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_ALPHA_SIZE, 8,
                                       EGL_NONE};
      if (eglChooseConfig(d, config_attribs, &config, 1, &n) && n >= 1) break;
      n = 0;
    }
    if (n < 1)
      return fail(surfaceless ? "no RGBA8 OpenGL config" : "no RGBA8 OpenGL pbuffer config", d);
    const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext ctx = eglCreateContext(d, config, EGL_NO_CONTEXT, ctx_attribs);
    if (ctx == EGL_NO_CONTEXT) return fail(fmt::format("eglCreateContext 4.5 core error 0x{:x}", eglGetError()), d);
    EGLSurface surface = EGL_NO_SURFACE;
    if (!surfaceless) {
      const EGLint pbuffer_attribs[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
      surface = eglCreatePbufferSurface(d, config, pbuffer_attribs);
      if (surface == EGL_NO_SURFACE) {
        eglDestroyContext(d, ctx);
        return fail(fmt::format("eglCreatePbufferSurface error 0x{:x}", eglGetError()), d);
      }
    }
    if (!eglMakeCurrent(d, surface, surface, ctx)) {
      const EGLint error = eglGetError();
      if (surface != EGL_NO_SURFACE) eglDestroySurface(d, surface);
      eglDestroyContext(d, ctx);
      return fail(fmt::format("eglMakeCurrent ({}) error 0x{:x}", surfaceless ? "surfaceless" : "pbuffer", error), d);
    }
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(eglGetProcAddress))) {
      eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      if (surface != EGL_NO_SURFACE) eglDestroySurface(d, surface);
      eglDestroyContext(d, ctx);
      return fail("glad could not load OpenGL", d);
    }
    try {
      check_gl_version("EGL");
    } catch (const std::exception& e) {
      eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      if (surface != EGL_NO_SURFACE) eglDestroySurface(d, surface);
      eglDestroyContext(d, ctx);
      return fail(e.what(), d);
    }
    display_ = d;
    context_ = ctx;
    surface_ = surface;
    return true;
  }
  bool fail(std::string why, EGLDisplay d = EGL_NO_DISPLAY) {
    if (d != EGL_NO_DISPLAY) eglTerminate(d);
    error_ = std::move(why);
    return false;
  }

  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
  EGLSurface surface_ = EGL_NO_SURFACE;
  bool force_pbuffer_ = false;
  std::string error_;
};

}  // namespace

std::unique_ptr<GlContext> create_egl(const ContextOptions& o) { return std::make_unique<EglContext>(o); }

}  // namespace quadrix::render::detail
