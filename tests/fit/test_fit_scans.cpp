// Fits of the shared scans (slow label: about 60 s of two cores in all).
//
// The Stanford bunny fitted at 1e-4, far below its mesh's sampling (about 40 s): the fit must
// end with every face of the mesh inside the union of the balls. Its repairs open new spots
// round after round (a ball at fault is replaced by smaller ones), so the faces still holding
// spots in the last round that may change the model get face patches, and a face that keeps a
// spot after a point was added on it gets one at once (it used to end with 568 spots outside
// every ball: 1.67e-4 of the data's pixels seen as holes at 1024²).
#include <array>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "core/io/io.h"
#include "core/mesh_io.h"
#include "core/reference.h"
#include "core/slim.h"
#include "fit/data_surface.h"
#include "fit/slim_fit.h"
#include "fit/surface_error.h"

namespace quadrix {
namespace {

TEST(FitSlimScans, AtOneTenThousandthEndsWithEveryFaceInsideTheBalls) {
  const std::string file = std::string(QUADRIX_DATASETS) + "/meshes/bunny.ply";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
  const PolygonMesh mesh = read_mesh(file);
  const SlimFitResult r = fit_slim(points_from_mesh(mesh), mesh, {.max_error = 1e-4});
  const SlimFitStats& s = r.stats;
  std::cerr << "  " << s.patches << " patches, " << s.face_holes << " face spots left, " << s.hole_points
            << " hole points, " << s.hole_face_patches << " hole face patches, " << s.blend_failures << " points beyond E, "
            << s.surface_failures << " of " << s.surface_samples << " surface samples beyond 2E (max "
            << s.surface_max / s.max_error_abs << "E), " << s.time_total << " s\n";
  EXPECT_EQ(s.face_holes, 0u);
  EXPECT_EQ(s.blend_failures, 0u);
  // The surface side: a few samples past 2E remain at this E (21–28 of ~820,000, up to 3.7E).
  EXPECT_LE(double(s.surface_failures), 1e-4 * double(s.surface_samples));
  EXPECT_LE(s.surface_max, 4.0 * s.max_error_abs);
}

// The armadillo at 1e-3, seen as bench fit sees it (8 views at 1024²): no speck of the drawn
// surface far from the data. Two patches' sheets curled away within 2 % of their rims, between
// the verification's lattice lines, and showed 9–11E from the data where no other patch is hit;
// their rims are now sampled (core/slim.h sample_slim_rim) and seen through the blend.
TEST(FitSlimScans, ArmadilloAtOneThousandthShowsNoSpeckFarFromTheData) {
  const std::string file = std::string(QUADRIX_DATASETS) + "/meshes/armadillo.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
  const PolygonMesh mesh = read_mesh(file);
  const SlimFitResult r = fit_slim(points_from_mesh(mesh), mesh, {.max_error = 1e-3});
  Box3 box;
  for (const auto& v : mesh.vertices) box.extend(v);
  const double E = r.stats.max_error_abs;
  const SurfaceError se = measure_surface_error(r.model, *r.data, box, {.views = 8, .resolution = 1024, .bound = 2 * E});
  std::cerr << "  " << r.stats.patches << " patches; drawn surface max " << se.max / E << "E, p99.9 " << se.p999 / E
            << "E, " << se.beyond << " of " << se.pixels << " pixels beyond 2E, " << se.holes << " holes\n";
  EXPECT_EQ(r.stats.blend_failures, 0u);
  EXPECT_LE(se.p999, 2 * E);
  EXPECT_LE(se.max, 4 * E);
}

// A sparse scan: 5,000 points drawn from the bunny's faces (points only), fitted at 1e-3, where
// the points' spacing (about 18E) is more than E resolves: balls of about one spacing cover
// every point but not the cells between them. Measured against the mesh the points came from
// (8 views at 256²), holes left without fill_point_holes: 8.8 % of the mesh's pixels (1024²);
// with it, 0.9 %, and the drawn surface stays within 2E of the points' tangent discs.
TEST(FitSlimScans, SparseCloudsHolesBetweenThePointsAreFilled) {
  const std::string file = std::string(QUADRIX_DATASETS) + "/meshes/bunny.ply";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
  const PolygonMesh mesh = read_mesh(file);
  const PointCloud cloud = sample_faces_uniformly(mesh, 5000, 7);
  Box3 box;
  for (const auto& p : cloud.points) box.extend(p);
  const DataSurface truth = DataSurface::from_mesh(mesh);
  const auto run = [&](bool fill, SurfaceError& discs) {
    const SlimFitResult r = fit_slim(cloud, {.max_error = 1e-3, .cover_point_holes = fill});
    const double E = r.stats.max_error_abs;
    discs = measure_surface_error(r.model, *r.data, box, {.views = 8, .resolution = 256, .bound = 2 * E});
    const SurfaceError t = measure_surface_error(r.model, truth, box, {.views = 8, .resolution = 256, .bound = 2 * E});
    std::cerr << "  fill " << fill << ": " << r.stats.patches << " patches (" << r.stats.disc_patches << " disc patches), "
              << r.stats.blend_failures << " points beyond E, " << r.stats.point_holes << " points with a hole; holes "
              << t.hole_share << " of the mesh's pixels; against the tangent discs p99.9 " << discs.p999 / E << "E, "
              << discs.share_beyond << " beyond 2E\n";
    EXPECT_EQ(r.stats.blend_failures, 0u);
    return t.hole_share;
  };
  SurfaceError off_discs, on_discs;
  const double off = run(false, off_discs), on = run(true, on_discs);
  EXPECT_GT(off, 0.03);  // the case: E below what the sampling resolves
  EXPECT_LT(on, 0.25 * off);
  EXPECT_LT(on, 0.02);
  EXPECT_LE(on_discs.share_beyond, 1e-3);
}

// Fandisk's 6,475 vertices without normals (a CAD part's mesh, its flat faces sampled only at
// their triangles' corners), fitted at 3e-3 and measured against the mesh (8 views at 256²).
// Nearly every point with a coverage hole lies beside a crease's faces (329 of 330): discs tilted
// off the crease, not cells the balls are too small for, so they do not decide whether every hole
// is filled. When they did (330 of 6,475 crossed point_hole_least), the fills stood out as fins:
// 2.5 % of the pixels beyond 2E of the mesh, p99.9 6.5E; now 0.28 %, p99.9 3.2E. The holes
// between the vertices that the points' discs cannot vouch for go up (1.7e-4 to 6.4e-4 of the
// mesh's pixels; the fit counts 6.2e-4 and exits 7).
TEST(FitSlimScans, AMeshsVerticesWithoutNormalsFillNoCreaseHolesWithFins) {
  const std::string file = std::string(QUADRIX_DATASETS) + "/meshes/fandisk.off";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
  const PolygonMesh mesh = read_mesh(file);
  PointCloud cloud;
  cloud.points = mesh.vertices;
  Box3 box;
  for (const auto& p : cloud.points) box.extend(p);
  const SlimFitResult r = fit_slim(cloud, {.max_error = 3e-3});
  const double E = r.stats.max_error_abs;
  const DataSurface truth = DataSurface::from_mesh(mesh);
  const SurfaceError t = measure_surface_error(r.model, truth, box, {.views = 8, .resolution = 256, .bound = 2 * E});
  std::cerr << "  " << r.stats.patches << " patches (" << r.stats.disc_patches << " disc patches, " << r.stats.point_hole_balls
            << " hole balls), " << r.stats.crease_points << " crease points; against the mesh " << t.share_beyond
            << " beyond 2E, p99.9 " << t.p999 / E << "E, holes " << t.hole_share << "; the fit's hole share "
            << r.stats.hole_share << "\n";
  EXPECT_EQ(r.stats.blend_failures, 0u);
  EXPECT_GT(r.stats.crease_points, 500u);  // the case: crease points beside the holes
  EXPECT_LT(r.stats.disc_patches, 50u);    // filled everywhere: 431
  EXPECT_LT(t.share_beyond, 0.01);
  EXPECT_LT(t.p999, 4 * E);
  EXPECT_LT(t.hole_share, 2e-3);
}

// The kitten (points only) at 1e-3 showed the far side of its head through a slit along its
// mouth, 8E wide between its points: two patches clipped at their own estimates of the crease
// there (try_sharp), the planes parting, and no coverage disc reaching the gap. A clipped
// patch's cut edge that no other patch holds, where the blend shows nothing just past it, now
// moves across the slit along the patch's own zero set (crease_slits). Seen from 0.08 in front of
// the spot, a 9 × 9 grid of rays over a square 0.008 (6E) wide around it (the kitten is about
// 0.65 × 1.0 × 0.59) must all meet the surface there (within 10E of the spot's depth), not the
// far side. The holes a view sees between the points (see_point_holes) close it too, on their
// own. With both off the centre rays go through (the case this test is about: the first
// expectation fails when an unrelated change closes the slit too; then pick another).
// Picked again when fit_slim began to fit points in Morton order (the mouth's slit no longer
// opened): of the 65 hole pixels bench fit's measure counts at 512² with both off, the 5 that
// moving a plane closes lie along a slit at the back of the head, (0.315, 0.454, −0.014), seen
// along (−0.527, −0.442, −0.726): 14 of the 81 rays there meet nothing (the far side is seen
// from inside, culled). The mouth's spot was (0.1190, 0.0971, 0.2663), seen from 0.08 out along
// its offset from (0.0309, 0.0084, −0.0505).
// Moved again when a boundary point's disc distance became a distance (the 640-patch fit with
// both off): the slit lies a hair off, at (0.3186, 0.4433, −0.0160) (1024², 14 views: the one
// hole there that a moved plane closes). There 17 of 81 rays pass with both off, 6 with the moved
// plane alone (it narrows the slit, and the seen holes close the rest), 0 with the seen holes
// alone and with both.
// With bent discs (the default) the slit does not open at all (0 of 81 rays with both off, 623
// patches): the mechanisms are tested on flat discs, where it does.
TEST(FitSlimScans, KittenShowsNoSlitThroughToTheFarSide) {
  const std::string file = std::string(QUADRIX_DATASETS) + "/points/kitten.xyz";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
  const PointCloud cloud = read_points(file);
  const Eigen::Vector3d spot(0.3186, 0.4433, -0.0160), view(-0.523, -0.447, -0.726);
  const Eigen::Vector3d eye = spot - 0.08 * view.normalized();
  const auto through = [&](bool relax, bool see) {
    SlimFitOptions o{.max_error = 1e-3, .relax_clips = relax};
    o.see_point_holes = see;
    o.bent_discs = false;
    const SlimFitResult r = fit_slim(cloud, o);
    const double E = r.stats.max_error_abs;
    const ReferenceScene scene(r.model);
    TraceOptions trace;
    trace.slim = slim_blend_of(r.model);
    const Eigen::Vector3d d = (spot - eye).normalized(), a = d.unitOrthogonal(), b = d.cross(a);
    int far = 0;
    for (int i = -4; i <= 4; ++i)
      for (int j = -4; j <= 4; ++j) {
        const Eigen::Vector3d target = spot + 0.001 * (i * a + j * b);
        const Eigen::Vector3d dir = (target - eye).normalized();
        const auto hit = scene.trace(Ray{eye, dir}, 0.0, 1e9, trace);
        if (!hit || std::abs(hit->t - (target - eye).norm()) > 10 * E) ++far;
      }
    std::cerr << "  relax " << relax << ", see " << see << ": " << r.stats.patches << " patches, " << r.stats.clips_relaxed
              << " planes moved, " << r.stats.crease_gaps << " slit samples left; " << far << " of 81 rays past the surface; "
              << r.stats.blend_failures << " points beyond E, " << r.stats.surface_failures << " surface samples beyond 2E\n";
    EXPECT_EQ(r.stats.blend_failures, 0u);
    EXPECT_EQ(r.stats.surface_failures, 0u);
    if (relax && !see) EXPECT_GT(r.stats.clips_relaxed, 0u);  // closed by a moved plane, not by another round's repair
    return far;
  };
  const int none = through(false, false);
  EXPECT_GT(none, 0);  // the case
  EXPECT_LT(2 * through(true, false), none);
  EXPECT_EQ(through(false, true), 0);
  EXPECT_EQ(through(true, true), 0);
}

// happy_buddha_10k at 1e-3, data nobody tuned for: it must end within its bound both ways.
// - It holds vertices one ulp apart. A point whose fits fail at every radius gets a tangent-plane
//   ball reaching half-way to its nearest other point: that was the one-ulp neighbour, a ball of
//   radius 8.7e-19, which float32 cannot place, so the whole model was written in the double
//   encoding (2.74 MB instead of 1.42 MB). Points within E/1000 now count as the centre.
// - Its needle triangles' face patches reached up to 8E past their sharp corners (the prism's
//   walls meet far out), and the fit ended with 11 surface samples beyond 2E (max 3.8E) and
//   exit 7. The sharpest corner is now cut by a fourth plane, the others' margins shrink.
// - Seen as bench fit sees it (8 views at 512²), a patch's rim showed alone 2.5E from the data
//   from the side, where a patch over it hid it along its normal: rim points off the data are now
//   also seen from 12 slanted views (fit/slim_fit_checks.cpp rim_view).
TEST(FitSlimScans, BuddhaAtOneThousandthEndsWithinItsBoundWithNoBallTooSmallForFloat) {
  const std::string file = std::string(QUADRIX_DATASETS) + "/meshes/happy_buddha_10k.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
  const PolygonMesh mesh = read_mesh(file);
  const SlimFitResult r = fit_slim(points_from_mesh(mesh), mesh, {.max_error = 1e-3});
  const double E = r.stats.max_error_abs;
  double smallest = E;
  for (const auto& s : r.model.slims) smallest = std::min(smallest, s.radius);
  std::cerr << "  " << r.stats.patches << " patches; smallest ball " << smallest / E << "E; " << r.stats.surface_failures
            << " surface samples beyond 2E (max " << r.stats.surface_max / E << "E)\n";
  EXPECT_GE(smallest, 1e-4 * E);
  EXPECT_EQ(r.stats.blend_failures, 0u);
  EXPECT_EQ(r.stats.surface_failures, 0u);
  EXPECT_LE(r.stats.surface_max, 2 * E);
  Box3 box;
  for (const auto& v : mesh.vertices) box.extend(v);
  const SurfaceError se = measure_surface_error(r.model, *r.data, box, {.views = 8, .resolution = 512, .bound = 2 * E});
  std::cerr << "  drawn surface max " << se.max / E << "E, p99.9 " << se.p999 / E << "E, " << se.beyond << " of "
            << se.pixels << " pixels beyond 2E\n";
  EXPECT_EQ(se.beyond, 0u);
}

// Data from ../shared that no earlier session tuned the fit on, each of which ended outside its
// bound or never ended:
// - bun000_rawscan (a raw range scan, normals estimated) at 1e-4 kept the round with the fewest
//   failures counting points' holes, one with 16 surface samples beyond 2E, over a later round
//   with none (and 1,105 points' holes against about 1,100), and exited 7. A round within the
//   bound now beats one that is not (about 30 s).
// - happy_buddha_10k at 1e-4: face patches on slivers with two sharp corners ran up to 3.2E from
//   the data, were dropped and made again each round, 4 samples stayed beyond 2E.
// - Quad meshes whose quads are not planar, below their sampling: spot_quadrangulated at 1e-3
//   looped in the covering until memory ran out; inspired_mesh_quads_Smooth at 1e-4 too.
// - radar.xyz at 1e-3 (no normals: estimated): lone patch rims 2.2-4.5E from the points' tangent
//   discs; 6 repair rounds left 2 surface samples beyond 2E, 10 rounds none.
TEST(FitSlimScans, UntunedDataEndsWithinItsBound) {
  struct Case {
    const char* file;
    double rel;
    bool mesh;
  };
  for (const Case c : {Case{"/points/bun000_rawscan.ply", 1e-4, false}, Case{"/meshes/happy_buddha_10k.obj", 1e-4, true},
                       Case{"/quads/spot_quadrangulated.obj", 1e-3, true},
                       Case{"/quads/inspired_mesh_quads_Smooth.off", 1e-4, true},
                       Case{"/points/radar.xyz", 1e-3, false}}) {
    const std::string file = std::string(QUADRIX_DATASETS) + c.file;
    if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
    SlimFitResult r;
    if (c.mesh) {
      const PolygonMesh mesh = read_mesh(file);
      r = fit_slim(points_from_mesh(mesh), mesh, {.max_error = c.rel});
    } else {
      r = fit_slim(read_points(file), {.max_error = c.rel});
    }
    const SlimFitStats& s = r.stats;
    std::cerr << "  " << c.file << " at " << c.rel << ": " << s.patches << " patches, " << s.blend_failures
              << " points beyond E, " << s.surface_failures << " surface samples beyond 2E (max "
              << s.surface_max / s.max_error_abs << "E), kept round " << s.kept_round + 1 << " of "
              << s.round_failures.size() << ", " << s.time_total << " s\n";
    EXPECT_EQ(s.blend_failures, 0u) << c.file;
    EXPECT_EQ(s.surface_failures, 0u) << c.file;
    EXPECT_LE(s.surface_max, 2.0 * s.max_error_abs) << c.file;
  }
}

// The bunny's mesh sampled by 20,000 points (with its faces' normals, points only: a sparse
// scan), fitted at 3e-3 and measured against the mesh: its base has holes 6-20 spacings long and
// in places about two spacings wide, whose rims the centroid test missed (the neighbours wrap
// around a concave rim) and whose far rim passed for a density step's sparse side, so the data
// bridged them and the fit, within 2E of its data, drew up to 7E from the mesh there: 0.57 % and
// 0.49 % of the mesh's pixels beyond 2E (p99.9 4.3E and 4.2E) in two samplings. With the hole_rims
// rules (DataSurfaceOptions): 0.19 % and 0.27 % (p99.9 2.6E and 3.1E). Compared in the same run.
TEST(FitSlimScans, ASparselySampledBunnyStopsAtTheSlitsInItsBase) {
  const std::string file = std::string(QUADRIX_DATASETS) + "/meshes/bunny.ply";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
  const PolygonMesh mesh = read_mesh(file);
  const DataSurface truth = DataSurface::from_mesh(mesh);
  Box3 box;
  for (const auto& p : mesh.vertices) box.extend(p);
  for (const std::uint64_t seed : {7, 8}) {
    const PointCloud cloud = sample_faces_uniformly(mesh, 20000, seed);
    std::array<SurfaceError, 2> e;
    double E = 0;
    for (const bool rims : {false, true}) {
      const SlimFitResult r = fit_slim(cloud, {.max_error = 3e-3, .hole_rims = rims});
      E = r.stats.max_error_abs;
      e[rims] = measure_surface_error(r.model, truth, box, {.views = 8, .resolution = 256, .bound = 2 * E});
      std::cerr << "  seed " << seed << (rims ? ", hole rims: " : ", without: ") << r.stats.patches << " patches; the mesh's pixels beyond 2E "
                << e[rims].share_beyond << ", p99.9 " << e[rims].p999 / E << "E, max " << e[rims].max / E << "E, holes "
                << e[rims].hole_share << "\n";
      EXPECT_EQ(r.stats.blend_failures, 0u);
    }
    EXPECT_LT(e[1].share_beyond, 0.65 * e[0].share_beyond) << seed;
    EXPECT_LT(e[1].share_beyond, 4e-3) << seed;
    EXPECT_LT(e[1].p999, 3.5 * E) << seed;
    EXPECT_LE(e[1].hole_share, std::max(1e-4, e[0].hole_share)) << seed;
  }
}

// bun000_rawscan (a raw range scan, normals estimated) at the CLI's default 1e-3: at the sparse
// stretches where the scanner grazed the ears and the back, 5 points kept a hole a view sees
// (1.24e-4 of the points, over the 1e-4 the fit promises, so `fit` exited 7): each one's own disc
// patch, bent to the data, ran off its neighbours' tangent discs and was dropped. The disc of
// another of the spot's nearest points on the same sheet covers three of them now.
TEST(FitSlimScans, ARawScanAtTheDefaultBoundKeepsItsHolePromise) {
  const std::string file = std::string(QUADRIX_DATASETS) + "/points/bun000_rawscan.ply";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
  const SlimFitResult r = fit_slim(read_points(file), {.max_error = 1e-3});
  const SlimFitStats& s = r.stats;
  std::cerr << "  " << s.patches << " patches, " << s.seen_point_holes << " points with a hole seen, share "
            << s.hole_share << ", " << s.disc_patches << " disc patches, " << s.time_total << " s\n";
  EXPECT_EQ(s.blend_failures, 0u);
  EXPECT_EQ(s.surface_failures, 0u);
  EXPECT_FALSE(s.holes_exceeded);
  EXPECT_LE(s.hole_share, 1e-4);
}

// radar.xyz at 1e-4 (no normals: estimated; E far below its sampling): the repairs trade surface
// samples beyond 2E for points' holes (497, 300, 170, 77 … 1 beyond while the holes rose from
// 659 to 938). The fit used to stop three rounds after the least share of failures (holes
// counted) and keep round 3, 497 samples beyond 2E up to 23E; the kept model is now one within
// the bound if any round was (else the one that breaches it least), and the repairs go on while
// they lower the breaches. With bent discs (the default) radar's first round has 49 breaches,
// not 497, and the repairs end within the bound in 4 rounds without trading them for holes: the
// selection is tested on flat discs, where the case still arises, and whole discs at the rims
// (with the rim cuts, the repairs end within the bound in the round with the fewest failures:
// breaches 258, 126, 33, 19, 0).
TEST(FitSlimScans, KeepsTheRoundWithTheFewestBreachesOfTheBound) {
  const std::string file = std::string(QUADRIX_DATASETS) + "/points/radar.xyz";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "dataset missing: " << file;
  const SlimFitResult r = fit_slim(read_points(file), {.max_error = 1e-4, .bent_discs = false, .rim_cuts = false});
  const SlimFitStats& s = r.stats;
  ASSERT_EQ(s.hole_points, 0u);  // no faces: the same points in every round
  ASSERT_EQ(s.round_breaches.size(), s.round_failures.size());
  ASSERT_GE(s.round_breaches.size(), 4u);
  std::cerr << "  kept round " << s.kept_round + 1 << " of " << s.round_failures.size() << ", breaches:";
  for (const auto b : s.round_breaches) std::cerr << " " << b;
  std::cerr << "; surface max " << s.surface_max / s.max_error_abs << "E, " << s.time_total << " s\n";
  std::size_t best = 0;
  for (std::size_t i = 1; i < s.round_breaches.size(); ++i)
    if (std::pair(s.round_breaches[i], s.round_failures[i]) < std::pair(s.round_breaches[best], s.round_failures[best]))
      best = i;
  EXPECT_EQ(s.kept_round, int(best));
  EXPECT_EQ(s.blend_failures + s.surface_failures, s.round_breaches[best]);  // the figures are the kept model's
  // Repairs went on past the rounds whose share of failures (holes counted) stopped falling.
  EXPECT_LT(100 * s.round_breaches[best], s.round_breaches.front());
  const auto least_share = std::min_element(s.round_failures.begin(), s.round_failures.end()) - s.round_failures.begin();
  EXPECT_GT(s.kept_round, least_share) << "the case no longer trades breaches for holes";
  // With the repairs' balls checked on verification's lattice before they join, it ends within
  // (it ended with 1 sample beyond 2E, 8.3E, each re-covering taking a ball 2–8E off the data).
  EXPECT_EQ(s.blend_failures + s.surface_failures, 0u);
}

}  // namespace
}  // namespace quadrix
