#pragma once
/// SLIM patches in three passes ([Stoll06] §5.1.1, DESIGN §6): visibility (pushed-back depth of
/// the first hit), accumulation (additive weighted normal, depth, colour), resolve (divide by Σw
/// into the G-buffer, shaded later with everything else). And the debug overlay of their splats.
///
/// In the camera's view the resolve is drawn on the far plane with the depth test GL_GREATER and
/// writes no depth, so only pixels with a depth below 1 run it (early depth test; pass 1 keeps
/// its depth-buffer value below 1 even past the far plane): the depth buffer keeps pass 1's
/// pushed depth there, and the G-buffer's eye depth is the blended one (what the shading, the
/// outlines and the read-back use). The light's view, whose depth buffer is the shadow map,
/// writes the blended depth.
///
/// Early-depth path (RenderOptions::slim_early_depth): llvmpipe runs the depth test before the
/// fragment shader only for shaders that write no depth. Pass 1 is unchanged but also keeps its
/// depth in a colour target; pass 2's splats lie in front of every hit they can make
/// (slim.vert) and write no depth, so fragments behind pass 1's depth fail the test before any
/// ray work, and the shader compares each hit with the colour target. The balls sit in spatial
/// chunks (render/passes/chunks.h): those outside the view frustum are not drawn, and the
/// clears and the resolve cover only the visible chunks' screen bound. The same G-buffer.
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "core/model.h"
#include "core/slim_lod.h"
#include "render/passes/chunks.h"
#include "render/passes/frame.h"

namespace quadrix::render {

class SlimPass final : public Pass {
public:
  SlimPass();  ///< compiles the three programs. \throws GlError.
  /// \throws InvalidInput past kMaxPrimitiveIndex patches, GlError (out of GPU memory).
  void upload(std::span<const SlimPatch> patches);
  /// A model's patches; with a hierarchy, every ball packed once and nothing drawn until
  /// select_cut uploads a cut. \throws as upload above, InvalidInput for an invalid hierarchy.
  void upload(const Model& model);
  /// Level of detail (core/slim_lod.h): the cut for this view, uploaded only when it differs
  /// from the one drawn. Returns true when it uploaded. Without a hierarchy: nothing, false.
  bool select_cut(const Camera& camera, const SlimLodOptions& options);
  /// The cut drawn (empty without a hierarchy).
  const SlimLodCut& cut() const { return cut_; }
  bool has_hierarchy() const { return lod_.has_value(); }
  std::size_t count() const { return count_; }
  /// The packed balls (SSBO, `Ball` in slim.vert).
  GLuint balls() const { return balls_.id(); }
  /// The balls' common origin: their centres are stored relative to it (set_origin_uniforms).
  const FixedOrigin& origin() const { return origin_; }
  bool needed(const RenderOptions&) const override { return count_ > 0; }
  void run(const Frame& frame) override;

private:
  void visibility(const Frame& frame);
  void accumulate(const Frame& frame);
  void resolve(const Frame& frame);
  /// The three passes on the early-depth path, within the visible chunks' screen bound.
  void run_early_depth(const Frame& frame);
  void set_uniforms(const gl::Program& program, const Frame& frame, int count_stats) const;
  /// Vertices per splat: RenderOptions::slim_splat_sides, or this platform's default.
  GLsizei splat_sides(const RenderOptions& options) const;
  /// (Re)makes the accumulation targets; they share the G-buffer's depth texture.
  void ensure_accumulation(const FrameTargets& targets, bool half);
  /// Packs `balls` (kBallFloats each, the cut's or the model's) into the GPU buffer in chunk order.
  void upload_chunked(std::span<const float> balls, std::span<const Box3> boxes);

  gl::Program visibility_, accumulate_, resolve_, resolve_drawn_;
  gl::Program visibility_early_, accumulate_early_, from_depth_;
  gl::Buffer balls_;
  std::size_t count_ = 0;
  Chunks chunks_;  // GPU slots in chunk order
  bool software_ = false;  // render/context.h current_context_is_software, at construction
  /// Accumulation targets for one FrameTargets (the view's, and the light's for shadows).
  struct Accumulation {
    gl::Texture normal_weight, depth_colour;
    gl::Framebuffer fbo;
    // Early-depth path: pass 1's window depth (R32F) drawn with the G-buffer's depth, or alone.
    gl::Texture pass1_depth;
    gl::Framebuffer pass1_fbo, copy_fbo;
    bool half = false;
    const FrameTargets* targets = nullptr;
    unsigned generation = 0;  // the FrameTargets generation fbo was made for
  };
  std::array<Accumulation, 2> acc_;
  Accumulation* current_ = nullptr;  // the one this frame draws with
  FixedOrigin origin_;  // the centres are stored relative to it
  // Level of detail: every ball of the hierarchy packed (kBallFloats each), the cut drawn.
  std::optional<SlimLod> lod_;
  std::vector<float> packed_;
  std::vector<Box3> boxes_;  // per ball of the hierarchy
  SlimLodCut cut_;
  bool has_cut_ = false;
};

/// Debug overlay over the shaded image: the screen bound of every SLIM ball, red where the
/// per-quadric test culls it (RenderOptions::slim_outlines).
class SlimOutlinePass final : public Pass {
public:
  explicit SlimOutlinePass(const SlimPass& slim);
  bool needed(const RenderOptions& options) const override { return options.slim_outlines && slim_.count() > 0; }
  void run(const Frame& frame) override;

private:
  const SlimPass& slim_;
  gl::Program program_;
};

}  // namespace quadrix::render
