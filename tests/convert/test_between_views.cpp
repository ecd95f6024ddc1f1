// Moves towards what grazing views see: a face under a drawn point beyond the bound comes within
// the bound of it, and no vertex moves farther than allowed off the surface it was on.
#include <gtest/gtest.h>

#include <algorithm>

#include "convert/between_views.h"
#include "fit/data_surface.h"

using namespace quadrix;

namespace {

/// The square [0, n]² of the plane z = 0 in 2n² triangles, normals +z.
PolygonMesh flat_grid(int n) {
  PolygonMesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) m.vertices.emplace_back(x, y, 0);
  const auto at = [n](int x, int y) { return y * (n + 1) + x; };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int a[3] = {at(x, y), at(x + 1, y), at(x + 1, y + 1)}, b[3] = {at(x, y), at(x + 1, y + 1), at(x, y + 1)};
      m.add_face(a);
      m.add_face(b);
    }
  return m;
}

double distance_to(const PolygonMesh& m, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto t = m.face(f);
    best = std::min(best, point_triangle_distance(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]));
  }
  return best;
}

}  // namespace

TEST(BetweenViews, FacesUnderPointsBeyondTheBoundComeWithinItAndMoveNoFartherThanAllowed) {
  const double bound = 0.1;
  const PolygonMesh before = flat_grid(10);
  PolygonMesh mesh = before;
  // Above the middle (1.6 bounds), below another spot (1.3 bounds), and beside the open edge
  // x = 10 (1.2 bounds past it, in the plane).
  const std::vector<SurfaceError::Beyond> beyond = {{{5.3, 5.6, 0.16}, 0.16}, {{2.4, 7.7, -0.13}, 0.13}, {{10.12, 3.5, 0}, 0.12}};
  const BetweenViewsOptions o{.bound = bound};
  std::vector<double> offset;
  const std::size_t moved = move_between_views(mesh, beyond, o, offset);
  EXPECT_GT(moved, 0u);
  for (const auto& b : beyond) {
    EXPECT_GT(distance_to(before, b.point), bound);
    EXPECT_LE(distance_to(mesh, b.point), bound) << "at (" << b.point.transpose() << ")";
  }
  ASSERT_EQ(offset.size(), mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const double d = (mesh.vertices[v] - before.vertices[v]).norm();
    EXPECT_LE(d, o.max_offset * bound + 1e-12) << "vertex " << v;
    EXPECT_NEAR(d, std::abs(offset[v]), 1e-12) << "vertex " << v;
    // Only the vertices of the faces nearest the points move (a face is one unit across).
    const Eigen::Vector3d& p = before.vertices[v];
    const bool near_one = std::any_of(beyond.begin(), beyond.end(), [&](const SurfaceError::Beyond& b) {
      return std::max(std::abs(p.x() - b.point.x()), std::abs(p.y() - b.point.y())) <= 1.5;
    });
    if (!near_one) {
      EXPECT_EQ(d, 0.0) << "vertex " << v;
    }
  }
  // Called again with the same points, the faces already within the bound stay.
  const PolygonMesh once = mesh;
  std::vector<SurfaceError::Beyond> still;
  for (const auto& b : beyond)
    if (const double d = distance_to(mesh, b.point); d > bound) still.push_back({b.point, d});
  EXPECT_EQ(move_between_views(mesh, still, o, offset), 0u);
  EXPECT_EQ(mesh.vertices, once.vertices);
}
