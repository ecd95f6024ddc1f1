#pragma once
/// What the passes of one frame share: the camera as the shaders see it (set on every program by
/// one function), the render targets, and the Pass interface the renderer runs in sequence.
#include <cstdint>

#include "core/camera.h"
#include "render/gl/objects.h"
#include "render/renderer.h"

namespace quadrix::render {

/// A double-precision point as float hi + lo; the shaders add the halves back.
struct Split {
  Eigen::Vector3f hi, lo;
};
Split split(const Eigen::Vector3d& p);
/// The float whose bits are `u` (ids and packed colours in float buffers).
float bits_float(std::uint32_t u);

/// The camera's uniforms, computed once per frame (differences taken in double).
struct CameraUniforms {
  explicit CameraUniforms(const Camera& camera);
  Eigen::Matrix4f proj;
  Eigen::Matrix3f view_rot;
  Split target;
  Eigen::Vector3f target_minus_eye;
  float target_distance;
  float near_plane;
  Eigen::Vector2f viewport;  ///< pixels
  Eigen::Vector3d target_world;
  Camera world;  ///< the camera itself (double), for work done on the CPU per frame
};

/// Sets every camera uniform (u_proj, u_view_rot, u_target_hi, u_target_lo, u_target_minus_eye,
/// u_target_distance, u_near, u_viewport) that the program declares.
void set_camera_uniforms(const gl::Program& program, const CameraUniforms& camera);

/// Positions relative to a pass's common origin, as an integer number of quanta plus a float rest,
/// so that a position relative to the view target is an exact integer sum in the shader: a hi + lo
/// float split relies on the shader adding hi to hi first, and llvmpipe's compiler reorders float
/// sums (`precise` or not), which left SLIM balls far from the common origin but near the target
/// off by an ulp of that distance (3e-3 of a ball's radius for balls 1e-4 of the scene).
struct FixedOrigin {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double quantum = 1;  ///< world units; the origin's box spans at most 2²⁸ quanta
  struct Offset {
    Eigen::Vector3i q = Eigen::Vector3i::Zero();     ///< quanta, |q| ≤ 2³⁰
    Eigen::Vector3f rest = Eigen::Vector3f::Zero();  ///< the rest, world units
  };
  /// An origin at the box's centre, the quantum fitted to its size.
  static FixedOrigin of(const Box3& box);
  /// d (a position − origin, or origin − target) as q·quantum + rest.
  Offset offset(const Eigen::Vector3d& d) const;
};
/// u_origin_q, u_origin_rest (the origin − the view target as FixedOrigin::Offset) and u_quantum:
/// the shader adds a primitive's offset to them (integers to integers, rests to rests).
void set_origin_uniforms(const gl::Program& program, const FixedOrigin& origin, const CameraUniforms& camera);

/// The G-buffer (normal + eye depth, albedo, primitive ids, depth) and the shaded output.
struct FrameTargets {
  int width = 0, height = 0;
  unsigned generation = 0;  ///< bumped on every re-allocation, so dependants re-attach
  gl::Texture normal_depth, albedo, ids, depth, colour;
  gl::Framebuffer gbuffer, output;

  /// Re-allocates at a new size (no-op at the same size). \throws GlError.
  void resize(int width, int height);
  /// Background everywhere: zero normal/depth and albedo, id −1, depth 1.
  void clear() const;
};

/// The key light's shadow map as the deferred pass reads it (core/lighting.h).
struct ShadowMap {
  GLuint depth = 0;                 ///< the light's window depth (GL_DEPTH_COMPONENT32F)
  Eigen::Matrix4f eye_to_light;     ///< view eye space → the light's clip space
  float proj22 = 0, proj32 = 0;     ///< the light's projection, to make its depth linear
  float texel_world = 0;            ///< a map texel's size at the scene, world units
  int size = 0;                     ///< pixels per side
};

/// One frame's shared inputs.
struct Frame {
  const CameraUniforms& camera;
  /// The caller's options, except that `cull` (back sides of tetrahedron patches and glyphs) is
  /// on only where it cannot change the image (core/culling.h).
  const RenderOptions& options;
  const FrameTargets& targets;
  GLuint stats_buffer;  ///< SSBO binding 1: culled, -, splat and hit, glyph proxy and hit fragment counts
  GLuint empty_vao;
  /// Per-quadric SLIM culling as the caller asked: always exact (SLIM patches are one-sided).
  bool slim_cull = true;
  /// The light's view for the shadow map: the passes write depth only (no colour targets).
  bool depth_only = false;
  /// The shadow map the deferred pass reads (RenderOptions::shadows), else null.
  const ShadowMap* shadow = nullptr;
  /// Bounding radius of the scene (outline thresholds).
  float scene_radius = 1.0f;
  /// Whether passes after the tetrahedron pass draw into the G-buffer (and so need its depth).
  bool depth_needed_after_tets = true;
  /// Whether the depth buffer is still clear when the SLIM pass (the last G-buffer pass) runs.
  bool is_depth_clear_before_slim = false;
};

/// The state every opaque pass draws into the G-buffer with: its framebuffer bound, depth test
/// GL_LESS with depth writes, no blending, no face culling (a pass that culls enables it after);
/// colour writes off for a depth-only frame.
void begin_gbuffer_draw(const Frame& frame);
/// Colour writes to the G-buffer's three targets: on, unless the frame is depth-only.
void set_gbuffer_colour_writes(const Frame& frame);

/// One step of a frame. Each pass owns its programs and the GPU data of its primitives, and
/// sets the GL state it draws with.
class Pass {
public:
  virtual ~Pass() = default;
  /// False when this frame has nothing for the pass (no such primitives, option off).
  virtual bool needed(const RenderOptions& options) const = 0;
  virtual void run(const Frame& frame) = 0;
};

}  // namespace quadrix::render
