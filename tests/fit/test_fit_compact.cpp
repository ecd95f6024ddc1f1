// A fit certified at E = 1e-4 of the diagonal keeps its certificate through the compact .qxm
// encoding (core/model_io.h): the points side (every point within E of the blended surface) and
// the surface side (the blended surface within 2E of the data) measured again on the model read
// back, with the change per point stated.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "core/model_io.h"
#include "core/points_io.h"
#include "fit/evaluate.h"
#include "fit/slim_fit.h"
#include "fit/surface_error.h"
#include "tests/core/malformed_corpus.h"

namespace quadrix {
namespace {

TEST(FitCompact, CertifiedBoundHoldsAfterTheCompactRoundTrip) {
  const std::filesystem::path file = std::filesystem::path(QUADRIX_DATASETS) / "points" / "kitten.xyz";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "no " << file << " (shared datasets absent)";
  const PointCloud cloud = read_points(file);
  const SlimFitResult fit = fit_slim(cloud, {.max_error = 1e-4});
  const SlimFitStats& s = fit.stats;
  ASSERT_EQ(s.blend_failures, 0u) << "the fit itself is outside its bound";
  const double E = s.max_error_abs;

  test::ScratchDir dir("fit-compact");
  const WriteModelResult w =
      write_model(fit.model, dir / "k.qxm", {.encoding = ModelEncoding::compact, .fallback_to_full = false});
  const WriteModelResult wd = write_model(fit.model, dir / "kd.qxm", {.encoding = ModelEncoding::full});
  const Model back = read_model(dir / "k.qxm");
  ASSERT_EQ(back.slims.size(), fit.model.slims.size());

  // Points side: the same probes (fit/evaluate.h) on both models.
  const SlimError e0 = evaluate_slim(fit.model, cloud, {.keep_per_point = true});
  const SlimError e1 = evaluate_slim(back, cloud, {.keep_per_point = true});
  ASSERT_EQ(e1.misses, e0.misses);
  double change = 0;
  for (std::size_t i = 0; i < cloud.points.size(); ++i)
    if (std::isfinite(e0.per_point[i])) change = std::max(change, std::abs(e1.per_point[i] - e0.per_point[i]));
  EXPECT_EQ(e1.count_above(E), 0u);
  EXPECT_LE(e1.max, E);
  EXPECT_LE(change, 1e-6 * s.diagonal);

  // Surface side: the blended surface within 2E of the data's surface (the points' discs).
  const DataSurface data = DataSurface::from_points(cloud.points, cloud.normals);
  Box3 box;
  for (const auto& p : cloud.points) box.extend(p);
  const SurfaceErrorOptions so{.views = 8, .resolution = 128, .bound = 2 * E};
  const SurfaceError s0 = measure_surface_error(fit.model, data, box, so);
  const SurfaceError s1 = measure_surface_error(back, data, box, so);
  EXPECT_LE(s1.beyond, s0.beyond);
  EXPECT_NEAR(s1.max, s0.max, 1e-6 * s.diagonal);

  std::printf("kitten, E = 1e-4 of the diagonal (%.4g): %zu patches; %zu bytes compact, %zu double (%.3f); "
              "points max %.6g -> %.6g (largest change per point %.3g = %.3g of the diagonal); "
              "surface max %.6g -> %.6g, beyond 2E %zu -> %zu of %zu pixels\n",
              E, fit.model.slims.size(), w.bytes, wd.bytes, double(w.bytes) / double(wd.bytes), e0.max, e1.max,
              change, change / s.diagonal, s0.max, s1.max, s0.beyond, s1.beyond, s1.pixels);
}

}  // namespace
}  // namespace quadrix
