#pragma once
/// SLIM surfaces (Ohtake, Belyaev, Alexa 2005; [Stoll06] §5.1.1): the per-ray blend of
/// sphere-bounded quadric patches, as the GPU's three passes compute it (DESIGN §2, §6).
#include <algorithm>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "core/model.h"
#include "core/ray.h"

namespace quadrix {

/// SLIM weight of r = ‖x − c‖/R: exp(−8r²) for r < ½, 16e⁻²(1 − r)⁴ for ½ ≤ r ≤ 1, 0 beyond.
/// Continuous at r = ½ (both 16e⁻²/16 = e⁻²).
double slim_weight(double r);

/// The first front-facing hit of one patch along a ray, inside its ball and clip plane.
bool intersect_slim_patch(const SlimPatch& patch, const Ray& ray, double tmin, double tmax, Hit& hit);

struct SlimBlendOptions {
  /// Pass 1 pushes each patch's first hit back by min(offset·R, max_push) (R = that patch's
  /// radius); pass 2 blends every patch hit in front of the nearest pushed-back depth.
  double offset = 0.5;
  /// World units. Hits of one sheet's patches, each within E of the data, lie about 2E apart;
  /// a push of half a large ball reaches the next sheet instead (a groove between two faces'
  /// planes, 10E apart along the ray, blended to 4E off both: dragon_10k at 1e-4).
  double max_push = std::numeric_limits<double>::infinity();
  /// own: the ball's own bound (SlimPatch::max_push), ≤ 0 for none (then max_push).
  double push(double radius, double own = -1) const { return std::min(offset * radius, own > 0 ? own : max_push); }
};

/// The blend offset a model's error bound was certified with: its `slim_offset` metadata (written
/// by the fitter), else SlimBlendOptions{}.offset. Renderers use it unless told otherwise.
double slim_offset_of(const Model& model);

/// The blend a model was certified with: slim_offset_of and its `slim_max_push` metadata (world
/// units; none: unbounded). offset ≥ 0 replaces the model's offset (a command's --slim-offset).
SlimBlendOptions slim_blend_of(const Model& model, double offset = -1);

/// A slab that holds a patch's zero set inside its ball, in local units (ball radius 1): every
/// u with g(u) = 0 and ‖u‖ ≤ 1 has s0 ≤ axisᵀu ≤ s1, and lies within r(s) of the axis, r linear
/// from r0 at s0 to r1 at s1: the piece lies in that frustum (the hull of two discs). With
/// axis = b/‖b‖ (the gradient's direction at the centre), per bin of s and distance r from the
/// axis, interval bounds of g over the bin tell where the zero set can be: a bowl's piece reaches
/// the rim only at its top, so its frustum narrows towards the centre. The splat of a tight slab
/// bounds the surface piece, not the ball ([Toledo04] waste); `tight` is false (the slab is the
/// whole ball, r0 = r1 = 1) when b = 0 or the slab is no thinner than max_thickness.
struct SlimSlab {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit, local (world-aligned) axes
  double s0 = -1, s1 = 1;                           ///< extent along axis, −1 ≤ s0 ≤ s1 ≤ 1
  double r0 = 1, r1 = 1;                            ///< the frustum's radii at s0 and s1, ≥ 0
  bool tight = false;
};
SlimSlab slim_patch_slab(const SlimPatch& patch, double max_thickness = 1.5);

/// A point of a patch's zero set inside its ball (and clip plane).
struct SlimSurfaceSample {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< world units
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< unit ∇g (outward)
  double r = 0;                                      ///< ‖point − centre‖ / R
};

/// Samples a patch's zero set: lines parallel to the three local axes through a grid × grid
/// lattice over the ball's cross-section, every root (either facing) inside the ball and clip
/// plane, appended to out; pieces wider than 2R/grid are always hit. The rim (r > 0.8), where a
/// sheet leaves the ball and extrapolates farthest, is sampled on a 3× finer lattice. Where the
/// lattice met fewer than 4 points, a zero set thinner than it is sought (for_thin_zero_set,
/// 16 lines per rim-lattice spacing): a wire's tube came out with no sample to check.
void sample_slim_patch(const SlimPatch& patch, int grid, std::vector<SlimSurfaceSample>& out);

/// Points of a patch's zero set thinner than a lattice's spacing (a tube or needle a lattice of
/// lines met nowhere): lines along each principal axis of its quadratic part, through the planes
/// of the other axes at the quadric's centre, `step` apart (ball units), each root inside the ball
/// and clip planes passed to f (ball units) until f returns false. Nothing for a plane or a
/// quadric whose centre lies outside the ball.
void for_thin_zero_set(const SlimPatch& patch, double step, const std::function<bool(const Eigen::Vector3d&)>& f);

/// Samples a patch's rim, where its zero set meets its sphere (r → 1; inside the clip planes):
/// meridians from the pole along the centre's gradient, one every `spacing` (world units) of the
/// equator, each crossing found by sign changes of the quadric along it (48 steps, then
/// bisection), appended to out. A sheet that curls away near its rim can pass between the
/// lattice lines of sample_slim_patch; drawn where no other patch is hit, it is a fin or a speck.
void sample_slim_rim(const SlimPatch& patch, double spacing, std::vector<SlimSurfaceSample>& out);
/// The rim beside where each principal axis of the patch's quadric (through its centre) leaves the
/// ball, found by bisection along the sphere: a loop there smaller than sample_slim_rim's steps
/// (an ellipsoid's tip just past the sphere) is found. Appended to out, as sample_slim_rim's.
void sample_slim_rim_at_axes(const SlimPatch& patch, std::vector<SlimSurfaceSample>& out);

/// One patch's contribution to a ray: its hit and its weight.
struct SlimSample {
  Hit hit;
  double weight = 0;
  double radius = 0;
  int index = -1;
  double max_push = -1;  ///< the patch's own push bound (SlimPatch::max_push), ≤ 0: none
};

/// The blended surface point along one ray.
struct SlimBlend {
  double t = 0;                                        ///< Σwᵢtᵢ / Σwᵢ
  Eigen::Vector3d point = Eigen::Vector3d::Zero();     ///< Σwᵢxᵢ / Σwᵢ
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();    ///< normalised Σwᵢnᵢ (unit nᵢ)
  double weight_sum = 0;
  int first_index = -1;                                ///< patch of the nearest hit
  int count = 0;                                       ///< patches blended
};

/// Blends the samples of one ray (any order) the way the three GPU passes do:
/// t_cut = minᵢ(tᵢ + pushᵢ) (SlimBlendOptions::push of each sample's radius and own bound); blend all samples with tᵢ ≤ t_cut and weight > 0.
/// Returns nothing when no sample has positive weight. With `used`, the samples blended are
/// stored there (cleared first).
std::optional<SlimBlend> blend_slim_samples(std::span<const SlimSample> samples, const SlimBlendOptions& options,
                                            std::vector<SlimSample>* used = nullptr);

}  // namespace quadrix
