#pragma once
/// The CPU reference ray caster (double, TBB-parallel): the truth every renderer test compares
/// with. Per pixel, the nearest hit over tetrahedron patches and glyphs, and the per-ray SLIM
/// blend ([Stoll06] §5.1.1, DESIGN §2, §6), through a BVH over all primitives.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "core/camera.h"
#include "core/model.h"
#include "core/primitive.h"
#include "core/slim.h"

namespace quadrix {

/// What a ray sees first.
struct SurfaceHit {
  double t = 0;                                      ///< distance along the ray (unit dir)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< unit, facing the viewer
  PrimitiveKind kind = PrimitiveKind::none;
  int index = -1;                                    ///< into the model's vector of that kind
  Rgb colour{200, 200, 200};
};

struct TraceOptions {
  /// Per-fragment culling: front-facing roots only ([Stoll06] eq. 14). render_reference applies
  /// it only where it cannot change the image (core/culling.h); trace() applies it as asked.
  bool cull_backfaces = true;
  SlimBlendOptions slim{};
};

/// A model prepared for ray queries (BVH built once; thread-safe const queries).
class ReferenceScene {
public:
  explicit ReferenceScene(const Model& model);
  ~ReferenceScene();
  ReferenceScene(ReferenceScene&&) noexcept;
  ReferenceScene& operator=(ReferenceScene&&) noexcept;

  /// Nearest surface along the ray within (tmin, tmax). The model must outlive the scene.
  /// With `blended`, the SLIM samples that made a blended hit are stored there (cleared first).
  std::optional<SurfaceHit> trace(const Ray& ray, double tmin, double tmax, const TraceOptions& options,
                                  std::vector<SlimSample>* blended = nullptr) const;
  const Model& model() const;
  std::size_t bvh_node_count() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Distance from p to the nearest of up to four surfaces the scene draws along the line p + s·d
/// (|s| ≤ reach, d unit), or −1 when it meets none. The line is traced both ways: a surface is as
/// near whichever way it faces. Every hit is a drawn point, so this bounds p's Euclidean distance
/// to the drawn surface from above.
double line_distance(const ReferenceScene& scene, const TraceOptions& trace, const Eigen::Vector3d& p,
                     const Eigen::Vector3d& d, double reach);

/// line_distance along n, and, while that is beyond `bound` or meets nothing, along the 13 lines
/// through p towards its 26 grid neighbours (stopping at the first within `bound`): the least,
/// still an upper bound of the Euclidean distance (−1: no line met a surface). Where the surface
/// lies at a slant to n (a crease, a folded face whose normal points along the surface) the
/// normal's line alone can be many times the distance.
double nearest_along_lines(const ReferenceScene& scene, const TraceOptions& trace, const Eigen::Vector3d& p,
                           const Eigen::Vector3d& n, double reach, double bound);

/// Per-pixel buffers, row-major, row 0 at the top.
struct ReferenceImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> coverage;  ///< 1 where a surface was hit
  std::vector<float> depth;            ///< eye-space depth (distance along the view axis); +inf background
  std::vector<float> distance;         ///< distance from the eye along the ray; +inf background
  std::vector<Eigen::Vector3f> normal;  ///< unit world-space normal facing the viewer; 0 background
  std::vector<std::int32_t> primitive; ///< primitive_id(kind, index); −1 background
  std::vector<Rgb> albedo;             ///< primitive colour
  /// Visibility of the key light (core/lighting.h) per pixel: 1 lit, 0 in shadow; empty unless
  /// ReferenceRenderOptions::shadows.
  std::vector<float> key_light;
  double scene_radius = 0;             ///< bounding radius of the model (outline thresholds)
};

struct ReferenceRenderOptions {
  TraceOptions trace{};
  /// A shadow ray per covered pixel towards the key light's point (core/lighting.h), filling
  /// ReferenceImage::key_light.
  bool shadows = false;
  /// Called with the fraction done (0..1) from worker threads at most every few rows.
  std::function<void(double)> progress{};
};

/// Renders every pixel of the camera (TBB-parallel over rows): each pixel's ray from the near plane on.
ReferenceImage render_reference(const ReferenceScene& scene, const Camera& camera,
                                const ReferenceRenderOptions& options = {});

}  // namespace quadrix
