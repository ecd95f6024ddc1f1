// OSMesa: Mesa's off-screen software context (llvmpipe). Debian 12 still ships it; upstream Mesa
// dropped it in 25.1, so EGL surfaceless is the long-term headless path.
#include <glad/gl.h>  // before osmesa.h, which would pull in the system GL/gl.h
#include <GL/osmesa.h>

#include <vector>

#include "core/error.h"
#include "render/context.h"

namespace quadrix::render::detail {
namespace {

class OsmesaContext final : public GlContext {
public:
  explicit OsmesaContext(const ContextOptions& o) : buffer_(4 * 16 * 16) {
    const int attribs[] = {OSMESA_FORMAT,     OSMESA_RGBA, OSMESA_DEPTH_BITS,          24,
                           OSMESA_PROFILE,    OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 4,
                           OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
    (void)o;
    ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!ctx_) throw GlError("OSMesaCreateContextAttribs failed for a 4.5 core profile");
    // The default framebuffer is a small dummy: Quadrix renders into its own FBOs.
    if (!OSMesaMakeCurrent(ctx_, buffer_.data(), GL_UNSIGNED_BYTE, 16, 16)) {
      OSMesaDestroyContext(ctx_);
      throw GlError("OSMesaMakeCurrent failed");
    }
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(OSMesaGetProcAddress))) {
      OSMesaDestroyContext(ctx_);
      throw GlError("glad could not load OpenGL through OSMesaGetProcAddress");
    }
    check_gl_version("OSMesa");
  }
  ~OsmesaContext() override { OSMesaDestroyContext(ctx_); }
  std::string name() const override { return "osmesa"; }

private:
  OSMesaContext ctx_ = nullptr;
  std::vector<unsigned char> buffer_;
};

}  // namespace

std::unique_ptr<GlContext> create_osmesa(const ContextOptions& o) { return std::make_unique<OsmesaContext>(o); }

}  // namespace quadrix::render::detail
