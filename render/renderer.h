#pragma once
/// The OpenGL renderer: ray-casts every primitive per pixel into a G-buffer and shades it in a
/// deferred pass ([Stoll06] §5, DESIGN §6). A frame runs only the passes its scene needs.
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/mesh_io.h"
#include "core/model.h"
#include "core/slim.h"
#include "core/outlines.h"
#include "render/amp_options.h"

namespace quadrix::render {

class GlContext;

enum class Shading { phong, envmap, npr };

struct RenderOptions {
  /// Per-quadric (eq. 18, 19) and per-fragment (eq. 14) backface culling, where it cannot change
  /// the image (core/culling.h): SLIM always, tetrahedron patches and glyphs only when the model
  /// is closed and lies beyond the near plane. Off: the same image, slower.
  bool cull = true;
  Shading shading = Shading::phong;
  bool statistics = false;     ///< count culled/drawn primitives, fragments (costs a little)
  Rgb background{255, 255, 255};
  /// Clip-plane tolerance in local units (tetrahedron size ≈ 1): neighbours overlap by this much
  /// so no pixel falls between them.
  float clip_eps = 2e-5f;
  /// glFinish after each pass and time the passes on the CPU (llvmpipe's GL_TIME_ELAPSED only
  /// measures command submission). Costs the overlap between passes; for benchmarks.
  bool time_passes = false;
  /// SLIM pass 1 pushes each first hit back by min(slim_offset·R, slim_max_push) along the ray
  /// (world units; as the CPU reference, core/slim.h SlimBlendOptions).
  float slim_offset = 0.5f;
  float slim_max_push = std::numeric_limits<float>::infinity();
  void set_slim_blend(const SlimBlendOptions& b) {
    slim_offset = static_cast<float>(b.offset);
    slim_max_push = static_cast<float>(b.max_push);
  }
  /// SLIM accumulation targets: RGBA16F instead of RGBA32F (half the bandwidth; see the benchmark).
  bool slim_half_float = false;
  /// SLIM splats bound each patch's surface piece (a prism about the slab of its zero set,
  /// core/slim.h) instead of its whole ball; false: the ball's screen rectangle (the baseline).
  bool slim_tight_splats = true;
  /// Sides of the tight SLIM splat: the polygon of this many support lines around the projected
  /// slab: 4 (the oriented rectangle) or 8 (cutting its corners around a disc seen face-on);
  /// other values are rounded down to a multiple of 4 and clamped to 4–8 (12 and 16 sides left
  /// single pixels of a blend out in the tight-splat property test). Unset: 4 on a software rasterizer, 8 elsewhere. On llvmpipe the octagons'
  /// extra triangles cost more than the fragments they save (bunny fitted at 1e-3, 1024²: 11 %
  /// fewer SLIM shader runs but 17 % more fragment-shader invocations, as the blocks along each
  /// inner edge run once per triangle; `bench render`'s octagon row); unmeasured on a GPU.
  std::optional<int> slim_splat_sides;
  /// SLIM pass 2 runs the depth test before the ray–quadric code (render/passes/slim_pass.h):
  /// its splats lie in front of their hits and write no depth, each hit is compared with pass 1's
  /// depth in the shader; chunks outside the view frustum are skipped, and clears and the resolve
  /// cover only the visible balls' screen bound. The same G-buffer. false: every splat fragment
  /// of both passes ray-casts and writes its hit's depth (no early depth test on llvmpipe).
  bool slim_early_depth = true;
  /// SLIM level of detail, for models with a hierarchy (core/slim_lod.h): each frame draws the
  /// coarsest cut whose balls' errors project below this many pixels at their distance (the cut
  /// is uploaded only when it changes). 0: the leaves, full detail.
  double slim_pixel_error = 0.5;
  /// Debug overlay: the screen bound of every SLIM ball, red where the patch is culled.
  bool slim_outlines = false;
  /// Tetrahedra drawn nearest chunk first, testing and writing their entry faces' depth, so the
  /// depth test runs before the fragment shader on every driver. Exact for the tetrahedra of one
  /// tessellation (any two overlap in at most a face), so used only for models whose metadata says
  /// so (`comment tetrahedra tessellation`, written by `convert volume`). Otherwise, or false: each
  /// fragment writes its hit's depth (the depth test runs after the shader on llvmpipe).
  bool tet_early_depth = true;
  /// Tetrahedron chunks hidden behind what the frame has drawn are skipped: the chunks drawn last
  /// frame go first, the depth buffer is read back as tiles, and every other chunk whose box lies
  /// behind all its tiles is not drawn (exact: nothing skipped could show).
  bool tet_occlusion = true;
  /// Debug: glyphs write every fragment of their proxy polygon, flat, without ray casting.
  bool glyph_proxies = false;
  /// Glyphs drawn so the depth test runs before their fragment shader (occluders, then nearest
  /// hits, then one ray per pixel: render/passes/glyph_pass.h); false: each proxy fragment writes
  /// its hit's depth (no early test on llvmpipe). Unset: the platform's faster way (below).
  std::optional<bool> glyph_early_depth;
  /// The proxies of either way: rectangles (two triangles, 21.5 %
  /// of a sphere's square outside it) or polygons around the exact outline (octagons, 12-gons
  /// around cylinders: 5.2 %). Unset: the platform's faster way. On a software rasterizer
  /// (llvmpipe), whose cost is per triangle more than per fragment, the direct way with
  /// rectangles (1aon at 1024², one run each: spacefill 152 ms against 202 early and 221 with
  /// octagons; balls-and-sticks 130 against 284 and 259); elsewhere polygons, in the early-depth
  /// way (unmeasured on a GPU) and where the direct way is asked for (the light's view).
  std::optional<bool> glyph_rectangles;
  /// Shadows of the key light (core/lighting.h) from a shadow map of every primitive kind, with
  /// adaptive percentage-closer filtering ([Sigg06] §5: 8 samples, 64 in the penumbra).
  bool shadows = false;
  /// Pixels per side of the light's view; 0: kShadowTexelsPerPixel texels per view pixel at
  /// the scene's centre (core/lighting.h, matched_shadow_map_size).
  int shadow_map_size = 0;
  float shadow_softness = 1.5f;   ///< PCF kernel radius, shadow-map texels
  /// Black silhouette and crease lines (core/outlines.h, the CPU reference's detector); NPR
  /// shading draws them too.
  bool outlines = false;
  OutlineOptions outline{};
};

/// Measured figures of one frame.
struct FrameStats {
  std::uint64_t primitives = 0;        ///< tetrahedron patches, SLIM balls and glyphs submitted
  std::uint64_t culled = 0;            ///< removed by the per-quadric test (statistics only)
  std::uint64_t chunks = 0;            ///< spatial chunks of tetrahedron patches
  std::uint64_t chunks_culled = 0;     ///< of those, skipped whole (outside the view frustum)
  std::uint64_t culled_in_chunks = 0;  ///< patches in the skipped chunks (not in `culled`)
  std::uint64_t chunks_occluded = 0;   ///< tetrahedron chunks skipped as hidden (tet_occlusion)
  std::uint64_t occluded_in_chunks = 0;  ///< patches in those chunks
  std::uint64_t fragments = 0;         ///< fragment shader invocations (-1 when unsupported)
  std::uint64_t fragments_hit = 0;     ///< fragments that passed (not discarded, depth test)
  /// SLIM pass 1 fragments: the splats' area [Toledo04] A_RTA (with slim_early_depth, the part
  /// past the early depth test).
  std::uint64_t slim_splat_fragments = 0;
  std::uint64_t slim_hit_fragments = 0;    ///< of those, rays that met their patch: A_obj
  std::uint64_t slim_accumulate_fragments = 0;  ///< SLIM pass 2 fragments run
  std::uint64_t slim_cast_fragments = 0;   ///< SLIM fragments of passes 1 and 2 that ray-cast their patch
  /// [Toledo04] Waste = (A_RTA − A_obj)/A_RTA of the SLIM splats (statistics only).
  double slim_waste() const {
    return slim_splat_fragments ? double(slim_splat_fragments - slim_hit_fragments) / slim_splat_fragments : 0.0;
  }
  std::uint64_t glyph_proxy_fragments = 0;  ///< glyph fragments run (proxy area past early-Z)
  std::uint64_t glyph_hit_fragments = 0;    ///< of those, rays that met their glyph
  /// [Toledo04] Waste of the glyph proxies, (run − hit)/run (statistics only).
  double glyph_waste() const {
    return glyph_proxy_fragments ? double(glyph_proxy_fragments - glyph_hit_fragments) / glyph_proxy_fragments : 0.0;
  }
  std::uint64_t slim_balls = 0;        ///< SLIM balls drawn (with a hierarchy: the cut's)
  bool slim_cut_uploaded = false;      ///< this frame's view chose a new cut and uploaded it
  /// The cut's balls per level above the leaves (core/slim_lod.h); empty without a hierarchy.
  std::vector<std::size_t> slim_level_counts;
  double ms_clear = 0;                 ///< clearing the G-buffer (time_passes only)
  double ms_geometry = 0;              ///< G-buffer passes (time_passes only)
  double ms_slim = 0;                  ///< the three SLIM passes (time_passes only)
  double ms_shading = 0;               ///< deferred pass and outlines (time_passes only)
  double ms_shadows = 0;               ///< the light's view for the shadow map (time_passes only)
  double ms_total = 0;                 ///< CPU wall time of the frame incl. glFinish
};

/// Per-pixel results read back from the GPU (row 0 at the top, like the CPU reference).
struct GBuffer {
  int width = 0, height = 0;
  std::vector<std::uint8_t> coverage;
  std::vector<float> depth;            ///< eye-space depth, +inf background
  std::vector<Eigen::Vector3f> normal; ///< world normal facing the viewer
  std::vector<std::int32_t> primitive; ///< kind·2²⁸ + index, −1 background
};

class Renderer {
public:
  /// Compiles the programs in the current context. \throws GlError.
  explicit Renderer(GlContext& context);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Uploads a model's primitives (float, relative to each primitive's local origin).
  /// \throws GlError (e.g. out of GPU memory), InvalidInput for kinds not supported yet.
  void set_model(const Model& model);
  /// As set_model, with the adaptive-marching settings of its implicit surfaces.
  void set_model(const Model& model, const AmpOptions& amp);
  /// Milliseconds the last set_model spent generating and compiling implicit-surface programs.
  double implicit_compile_ms() const;
  /// Ordinary triangles drawn into the same G-buffer (polygons fanned).
  /// New parameter values (names as in its expression) for implicit surface i of the model, used
  /// from the next frame on: uniforms only, nothing recompiled or recomputed ([Singh10] dynamic
  /// surfaces). \throws InvalidInput for an unknown name, std::out_of_range for a bad index.
  void set_implicit_parameters(std::size_t i, const std::map<std::string, double>& values);
  void set_mesh(const PolygonMesh& mesh, Rgb colour = {180, 180, 190});

  /// Renders one frame at the camera's size. Allocates targets on size change.
  FrameStats draw(const Camera& camera, const RenderOptions& options);

  Image8 read_colour() const;
  GBuffer read_gbuffer() const;
  /// Blits the shaded image into the default framebuffer (window contexts).
  void present(int window_width, int window_height) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// True if GL_ARB_pipeline_statistics_query is available (fragment invocation counts).
bool has_pipeline_statistics();

}  // namespace quadrix::render
