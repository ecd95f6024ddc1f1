#include "core/model.h"

namespace quadrix {

Box3 bounds(const SlimPatch& s) {
  const Eigen::Vector3d r = Eigen::Vector3d::Constant(s.radius);
  return {s.centre - r, s.centre + r};
}

Box3 bounds(const TetPatch& t) {
  Box3 b;
  for (const auto& p : t.corners) b.extend(p);
  return b;
}

Box3 bounds(const Glyph& g) {
  Eigen::Vector3d half;
  switch (g.kind) {
    case GlyphKind::sphere: half.setConstant(g.radius); break;
    case GlyphKind::ellipsoid:
      // Extent of an ellipsoid x = centre + axes·u, ‖u‖ ≤ 1, along each world axis.
      half = g.axes.rowwise().norm();
      break;
    case GlyphKind::cylinder: {
      const Eigen::Vector3d a = g.axes.col(0);
      const double len2 = a.squaredNorm();
      // Disc of radius r perpendicular to a: extent r·sqrt(1 − (a_i/|a|)²) per axis.
      for (int i = 0; i < 3; ++i) {
        const double s = len2 > 0 ? std::sqrt(std::max(0.0, 1.0 - a[i] * a[i] / len2)) : 1.0;
        half[i] = std::abs(a[i]) + g.radius * s;
      }
      break;
    }
  }
  return {g.centre - half, g.centre + half};
}

Box3 bounds(const Model& m) {
  Box3 b;
  for (const auto& s : m.slims) b.extend(bounds(s));
  for (const auto& t : m.tets) b.extend(bounds(t));
  for (const auto& g : m.glyphs) b.extend(bounds(g));
  return b;
}

}  // namespace quadrix
