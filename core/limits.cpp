#include "core/limits.h"

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

}  // namespace quadrix
