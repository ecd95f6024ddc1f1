#include "core/limits.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix {

std::string world_fault(double v) {
  if (!std::isfinite(v)) return "is not finite";
  return fmt::format("is beyond ±{:g}, the largest world coordinate Quadrix handles", kMaxWorldCoordinate);
}

std::string world_fault(const Eigen::Vector3d& p) {
  return world_fault(p.allFinite() ? p.cwiseAbs().maxCoeff() : NAN);
}

void check_world_point(const Eigen::Vector3d& p, std::string_view what) {
  if (!is_world_point(p))
    throw InvalidInput(fmt::format("{} ({:g}, {:g}, {:g}) {}", what, p.x(), p.y(), p.z(), world_fault(p)));
}

void check_drawable_extent(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::string_view what) {
  if ((lo.array() > hi.array()).any()) return;  // empty
  const double extent = (hi - lo).maxCoeff();  // no squares: tiny extents must not underflow
  const double reach = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
  if (extent < kMinWorldSize)
    throw InvalidInput(fmt::format("{}: its extent {:g} is below {:g}, the smallest size Quadrix draws (scale it up)",
                                   what, extent, kMinWorldSize));
  if (extent < kMinRelativeExtent * reach)
    throw InvalidInput(fmt::format("{}: its extent {:g} is below {:g} of its largest coordinate {:g}, where double "
                                   "precision cannot place its surfaces (move it towards the origin)",
                                   what, extent, kMinRelativeExtent, reach));
}

}  // namespace quadrix
