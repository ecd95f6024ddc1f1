#include "core/culling.h"

namespace quadrix {

bool surfaces_are_closed(const Model& model) {
  if (model.tets.empty() && model.glyphs.empty()) return true;
  const auto it = model.metadata.find(kClosedKey);
  return it != model.metadata.end() && it->second == "1";
}

bool backface_culling_is_exact(const Box3& box, bool closed, const Camera& camera) {
  if (!closed) return false;
  if (box.empty()) return true;
  // Every corner of the box beyond the near plane: the whole box is, so the eye is outside it.
  const Eigen::Vector3d f = camera.forward();
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner((k & 1) ? box.max.x() : box.min.x(), (k & 2) ? box.max.y() : box.min.y(),
                                 (k & 4) ? box.max.z() : box.min.z());
    if (!((corner - camera.eye).dot(f) > camera.near_plane)) return false;
  }
  return true;
}

bool backface_culling_is_exact(const Model& model, const Camera& camera) {
  return backface_culling_is_exact(bounds(model), surfaces_are_closed(model), camera);
}

}  // namespace quadrix
