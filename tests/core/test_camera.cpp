#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/camera.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {

// Where the points fall in the image (NDC).
struct Spread {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
};
Spread project(const Camera& c, const std::vector<Vector3d>& points) {
  const Eigen::Matrix4d m = c.projection() * c.view();
  Spread s;
  for (const auto& p : points) {
    const Eigen::Vector4d q = m * p.homogeneous();
    EXPECT_GT(q.w(), 0) << "a point behind the eye";
    s.x0 = std::min(s.x0, q.x() / q.w()), s.x1 = std::max(s.x1, q.x() / q.w());
    s.y0 = std::min(s.y0, q.y() / q.w()), s.y1 = std::max(s.y1, q.y() / q.w());
  }
  return s;
}

// Tight framing of points that lie far in front of the target and off the axis: a small cluster
// comes out centred, filling `fill` of the smaller side. The sideways move was taken at the
// target's depth, so the zoom's parallax pushed such a cluster off-centre and, for the four corners
// of one probe pixel (a model of sub-pixel specks), sent the camera 10 diagonals away.
TEST(CameraFraming, SmallClusterInFrontOfTheTargetIsCentredAndFilled) {
  const Camera start = frame_view(Box3{Vector3d(-1, -1, -1), Vector3d(1, 1, 1)},
                                  {.up = Vector3d::UnitY(), .azimuth_deg = 30, .elevation_deg = 20, .fov_y_deg = 40,
                                   .fit_fov_y_deg = 40, .zoom = 1.0, .margin = 1.05, .width = 640, .height = 480});
  for (const double size : {1e-3, 0.05, 0.4}) {
    SCOPED_TRACE(size);
    // A cube of the given size about a point 0.72 in front of the target and off the axis.
    const Vector3d c = start.target + 0.72 * (start.eye - start.target).normalized() + Vector3d(0.3, -0.2, 0.1);
    std::vector<Vector3d> points;
    for (int i = 0; i < 8; ++i)
      points.push_back(c + 0.5 * size * Vector3d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
    const Camera f = fit_points(start, points, 0.85);
    const Spread s = project(f, points);
    const double width = std::max(s.x1 - s.x0, s.y1 - s.y0);  // NDC spans 2 on each side
    EXPECT_NEAR(0.5 * (s.x0 + s.x1), 0.0, 0.02 * width);
    EXPECT_NEAR(0.5 * (s.y0 + s.y1), 0.0, 0.02 * width);
    EXPECT_NEAR(width / 2.0, 0.85, 0.02);
    EXPECT_LT((f.target - c).norm(), 2.0) << "the target left the scene";
  }
}

}  // namespace
