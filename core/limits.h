#pragma once
/// The range of world coordinates Quadrix handles, one limit for every reader, converter and
/// renderer. Geometry is computed in double and drawn in float relative to local origins; past
/// kMaxWorldCoordinate in magnitude, squared distances and products of three lengths (volumes, a
/// quadric's coefficients moved to another frame) leave float's range (3.4e38) on the GPU and
/// ray roots lose their precision in double, so such inputs are refused (InvalidInput or
/// FormatError, exit 3) instead of becoming empty models, blank images or an infinite diagonal.
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace quadrix {

/// The largest coordinate, radius, spacing or extent accepted, in world units (any unit).
inline constexpr double kMaxWorldCoordinate = 1e12;

/// |v| ≤ kMaxWorldCoordinate (false for NaN and infinities).
inline bool is_world_value(double v) { return v >= -kMaxWorldCoordinate && v <= kMaxWorldCoordinate; }
inline bool is_world_point(const Eigen::Vector3d& p) {
  return is_world_value(p.x()) && is_world_value(p.y()) && is_world_value(p.z());
}

/// The smallest size drawn, world units: a model's extent (the longest side of its bounding box)
/// and a glyph's longest semi-axis. Below it, inverse lengths (a glyph's M⁻¹, a quadric's
/// coefficients in a primitive's own units) leave float's range on the GPU.
inline constexpr double kMinWorldSize = 1e-30;

/// The smallest extent of a drawn model relative to its largest |coordinate|. Double resolves a
/// coordinate x to 2⁻⁵³|x|; at this ratio that is 1e-6 of the model's size (the accuracy goal
/// for depth is 1e-5 of the depth range), so neither the CPU reference nor GL can place surfaces
/// of a smaller model that far out.
inline constexpr double kMinRelativeExtent = 1e-10;

/// \throws InvalidInput "WHAT: its extent E …" when the box [lo, hi] is not empty and its longest
/// side is below kMinWorldSize or below kMinRelativeExtent times its largest |coordinate|.
void check_drawable_extent(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::string_view what);

/// "is not finite" or "is beyond ±1e+12, the largest world coordinate Quadrix handles", for
/// messages that have already named the value.
std::string world_fault(double v);
std::string world_fault(const Eigen::Vector3d& p);

/// \throws InvalidInput "WHAT (x, y, z) …world_fault" unless is_world_point(p).
void check_world_point(const Eigen::Vector3d& p, std::string_view what);

}  // namespace quadrix
