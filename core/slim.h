#pragma once
/// SLIM surfaces (Ohtake, Belyaev, Alexa 2005; [Stoll06] §5.1.1): the per-ray blend of
/// sphere-bounded quadric patches, as the GPU's three passes compute it (DESIGN §2, §6).
#include <optional>
#include <span>

#include "core/model.h"
#include "core/ray.h"

namespace quadrix {

/// SLIM weight of r = ‖x − c‖/R: exp(−8r²) for r < ½, 16e⁻²(1 − r)⁴ for ½ ≤ r ≤ 1, 0 beyond.
/// Continuous at r = ½ (both 16e⁻²/16 = e⁻²).
double slim_weight(double r);

/// The first front-facing hit of one patch along a ray, inside its ball and clip plane.
bool intersect_slim_patch(const SlimPatch& patch, const Ray& ray, double tmin, double tmax, Hit& hit);

struct SlimBlendOptions {
  /// Pass 1 pushes each patch's first hit back by offset·R (R = that patch's radius); pass 2
  /// blends every patch hit in front of the nearest pushed-back depth.
  double offset = 0.5;
};

/// One patch's contribution to a ray: its hit and its weight.
struct SlimSample {
  Hit hit;
  double weight = 0;
  double radius = 0;
  int index = -1;
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
/// t_cut = minᵢ(tᵢ + offset·Rᵢ); blend all samples with tᵢ ≤ t_cut and weight > 0.
/// Returns nothing when no sample has positive weight.
std::optional<SlimBlend> blend_slim_samples(std::span<const SlimSample> samples, const SlimBlendOptions& options);

}  // namespace quadrix
