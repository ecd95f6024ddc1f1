// quadrix fit POINTS -o model.qxm: SLIM surfaces from point clouds (issue 4, DESIGN §2).
#include <algorithm>
#include <iostream>
#include <numeric>
#include <optional>
#include <random>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "core/error.h"
#include "core/limits.h"
#include "core/log.h"
#include "core/model_io.h"
#include "core/points_io.h"
#include "fit/data_surface.h"
#include "fit/evaluate.h"
#include "fit/outliers.h"
#include "fit/patch_error.h"
#include "fit/slim_fit.h"
#include "fit/slim_hierarchy.h"
#include "tools/cli.h"

namespace quadrix::cli {

void add_fit(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand("fit", "Fit a SLIM surface (sparse low-degree implicits) to a point cloud");
  struct Args {
    WriteModelOptions write;  // --encoding
    std::string points, out;
    double max_error = 1e-3;
    double max_error_abs = 0;
    double holdout = 0;
    bool allow_exceed = false;
    bool keep_outliers = false;
    int lod_levels = 0;
    SlimHierarchyOptions lod;
    std::string lod_rule = "fits";
    SlimFitOptions options;
  };
  auto a = std::make_shared<Args>();
  app->add_option("POINTS", a->points, "Point cloud (PLY, XYZ with 3 or 6 columns) or mesh (PLY, OFF, OBJ, STL: its faces give the normals)")->required();
  app->add_option("-o,--out", a->out, "Output .qxm")->required()->check(qxm_output());
  add_encoding_option(*app, a->write);
  app->add_option("--max-error", a->max_error, "Error bound relative to the bounding-box diagonal of the points fitted (stray points left out)")
      ->check(number({.lo = 1e-7, .hi = 0.5}));
  app->add_option("--max-error-abs", a->max_error_abs, "Error bound in world units (overrides --max-error; default: unset)")
      ->check(positive())->default_str("");
  app->add_option("--normal-weight", a->options.normal_weight, "μ: weight of the normal term")
      ->check(number({.lo = 1e-6, .hi = 10}));
  app->add_option("--holdout", a->holdout, "Fraction of points held out of the fit and measured after it")
      ->check(number({.lo = 0, .hi = 0.9}));
  app->add_flag("--allow-exceed", a->allow_exceed,
                "Exit 0 even when the fit finishes outside its bound (otherwise exit 7, the model still written)");
  app->add_option("--max-hole-share", a->options.max_hole_share,
                  "Share of the data a view may see through the model (holes the fit counts: faces seen through, "
                  "spots outside every ball, points with a hole a view sees) before the fit counts as outside its "
                  "bound (exit 7)")
      ->check(number({.lo = 0, .hi = 1}))
      ->capture_default_str();
  app->add_flag("--keep-outliers", a->keep_outliers,
                "Point clouds: fit every point, the stray ones too (by default a point alone off the surface - "
                "farther than 5 of the nearest surface points' spacings and off their planes, or over 2 spacings "
                "off its neighbours' plane - is left out of the fit and its bound, with a warning: each got a "
                "patch of its own, a speck beside the surface)");
  app->add_flag("!--no-surface-check", a->options.check_surface,
                "Skip the surface side of the bound (fins, specks: the blended surface within 2E of the data)");
  app->add_flag("!--no-face-prisms", a->options.face_prisms,
                "Clip a face patch (a mesh face's plane, where E is below the sampling) only at an open edge, "
                "not to its face's prism (for comparison: its plane then runs on into its neighbours)");
  app->add_flag_callback(
      "--no-view-holes", [a] { a->options.view_hole_rays = 0; },
      "Skip the check for faces seen through from some view although the balls cover them (a patch met edge-on, a hit "
      "just outside its ball; for comparison)");
  app->add_option("--repair-rounds", a->options.repair_rounds,
                  "Rounds of verification and repair of the patches at fault")
      ->check(number({.lo = 0, .hi = 100}))
      ->capture_default_str();
  app->add_flag("!--no-fill-point-holes", a->options.cover_point_holes,
                "Point clouds: leave the holes between the points that every ball misses (E below the points' spacing) "
                "open instead of closing them with the balls at those points or disc patches (their tangent planes)");
  app->add_option_function<double>(
         "--cover-fraction", [a](double f) { a->options.cover_fraction = f; },
         "A point counts as covered by a ball within this fraction of its radius: smaller, the balls overlap more, so "
         "neighbouring patches blend over wider bands (smoother shading, fewer facets) and leave fewer holes between "
         "the points of a cloud, for more patches (kitten at 1e-3: 0.9 435 patches, 0.75 640, 0.6 985)")
      ->check(number({.lo = 0.3, .hi = 1.0}))
      ->default_str("0.9 with a mesh, 0.75 for points alone");
  app->add_option("--seed", a->options.seed, "Random seed (candidates, hold-out split)")->check(non_negative());
  app->add_flag("--sharp", a->options.sharp,
                "Sharp features: a clip plane per patch whose normals split into two clusters");
  app->add_option("--sharp-angle", a->options.sharp_angle_deg,
                  "Smallest angle in degrees between the two normal clusters of a sharp patch")
      ->check(number({.lo = 1, .hi = 179}));
  app->add_option("--lod-levels", a->lod_levels,
                  "Coarser levels of detail above the fit, each with its balls' measured error (render --pixel-error "
                  "draws a cut); 0: none")
      ->check(number({.lo = 0, .hi = 16}))
      ->capture_default_str();
  app->add_option("--lod-rule", a->lod_rule,
                  "How a coarser level is made: fits (its own fit at E x --lod-factor^k, linked to the finer level "
                  "by which coarse ball holds each finer one) or merge (the finer balls merged into larger ones)")
      ->check(CLI::IsMember({"fits", "merge"}))
      ->capture_default_str();
  app->add_flag("!--lod-shared-push", a->lod.level_push,
                "--lod-rule fits: coarser levels blend with the fit's push bound instead of their own (for comparison)");
  app->add_option("--lod-factor", a->lod.level_factor, "--lod-rule fits: level k's bound is E x this^k")
      ->check(number({.lo = 1.1, .hi = 100}))
      ->capture_default_str();
  commands.push_back({app, [a](const CommonOptions& common, Report& report) {
                        // A mesh's faces give the normals and the surface the fit is bounded against.
                        std::optional<PolygonMesh> mesh;
                        PointCloud cloud;
                        if (detect_file_kind(a->points) == FileKind::mesh) {
                          mesh = read_mesh(a->points);
                          cloud = points_from_mesh(*mesh);
                        } else {
                          cloud = read_points(a->points);
                        }
                        // Stray points of a cloud (a mesh's vertices are its surface): each would get
                        // a patch of its own, a speck floating beside the surface.
                        std::vector<std::uint32_t> outliers;
                        // Copies of a point fitted once: estimated normals over copies degenerate (a
                        // 3,000-point sphere written 7 times fitted 2,994 patches instead of 4), and a
                        // copy is within E wherever its original is. file_index: each point's row.
                        std::vector<std::uint32_t> file_index(cloud.points.size());
                        std::iota(file_index.begin(), file_index.end(), 0u);
                        std::size_t copies = 0;
                        const std::size_t rows = cloud.points.size();
                        std::vector<std::uint32_t> position(rows);  // each row's point once copies are merged
                        std::iota(position.begin(), position.end(), 0u);
                        if (!mesh) {
                          file_index = distinct_positions(cloud.points, position);
                          copies = cloud.points.size() - file_index.size();
                          if (file_index.size() == 1 && cloud.points.size() > 1)
                            throw InvalidInput(fmt::format("{}: fit_slim: all {} points coincide", a->points, cloud.points.size()));
                          if (copies > 0 && file_index.size() < 10)
                            throw InvalidInput(fmt::format("{}: fit_slim: {} distinct positions among {} points; at least 10 are needed",
                                                           a->points, file_index.size(), cloud.points.size()));
                          if (copies > 0) {
                            PointCloud kept;
                            for (const auto i : file_index) kept.push_back_from(cloud, i);
                            log::warn("{}: {} of {} points repeat an earlier point's position exactly; each position is "
                                      "fitted once (with its first point's normal and colour)",
                                      a->points, copies, cloud.points.size());
                            cloud = std::move(kept);
                          }
                        }
                        if (!mesh && !a->keep_outliers) {
                          outliers = find_outliers(cloud.points);
                          // Over a quarter: not strays but a cloud this test misreads (a scatter).
                          if (4 * outliers.size() > cloud.points.size()) {
                            log::warn("{}: {} of {} points look like stray points off the surface, too many to be "
                                      "strays; all are fitted",
                                      a->points, outliers.size(), cloud.points.size());
                            outliers.clear();
                          }
                          if (!outliers.empty()) {
                            std::vector<std::uint8_t> drop(cloud.points.size(), 0);
                            for (const auto i : outliers) drop[i] = 1;
                            PointCloud kept;
                            for (std::size_t i = 0; i < cloud.points.size(); ++i)
                              if (!drop[i]) kept.push_back_from(cloud, i);
                            const auto& p = cloud.points[outliers.front()];
                            // Clumps of them may be a small separate object: say so.
                            const auto clumps = outlier_clumps(cloud.points, outliers);
                            if (!clumps.empty()) {
                              Eigen::Vector3d c = Eigen::Vector3d::Zero();
                              for (const auto i : clumps.front()) c += cloud.points[i];
                              c /= double(clumps.front().size());
                              std::size_t in = 0;
                              for (const auto& g : clumps) in += g.size();
                              log::warn("{}: {} of the outliers form {} clump{} of 5 or more, far nearer each other than "
                                        "the rest (the largest: {} points around ({:.6g}, {:.6g}, {:.6g})): a small separate "
                                        "object? --keep-outliers fits them",
                                        a->points, in, clumps.size(), clumps.size() == 1 ? "" : "s", clumps.front().size(),
                                        c.x(), c.y(), c.z());
                            }
                            // Rows of the file from here on: every copy of an outlier's position.
                            std::vector<std::uint8_t> stray(cloud.points.size(), 0);
                            for (const auto o : outliers) stray[o] = 1;
                            outliers.clear();
                            for (std::size_t r = 0; r < rows; ++r)
                              if (stray[position[r]]) outliers.push_back(std::uint32_t(r));
                            log::warn("{}: {} of {} points lie alone off the surface (outliers; the first is point {}, "
                                      "counted from 0 in file order, at ({:.6g}, {:.6g}, {:.6g})); left out of the fit "
                                      "and its bound (--keep-outliers fits them)",
                                      a->points, outliers.size(), rows, outliers.front(), p.x(), p.y(), p.z());
                            cloud = std::move(kept);
                          }
                        }
                        if (cloud.points.size() >= 10) {  // fewer: fit_slim refuses them, no warning first
                          // The fit holds far from the origin, but `render` cannot place what it makes.
                          Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
                          for (const auto& p : cloud.points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
                          try {
                            check_drawable_extent(lo, hi, a->points);
                          } catch (const InvalidInput& e) {
                            log::warn("{}; the model is fitted, but `render` will refuse it", e.what());
                          }
                        }
                        PointCloud held;
                        if (a->holdout > 0) {
                          // Fit on a random subset; measure the held-out rest afterwards.
                          std::mt19937_64 rng(a->options.seed);
                          std::bernoulli_distribution out(a->holdout);
                          PointCloud kept;
                          for (std::size_t i = 0; i < cloud.points.size(); ++i) (out(rng) ? held : kept).push_back_from(cloud, i);
                          cloud = std::move(kept);
                        }
                        SlimFitOptions o = a->options;
                        o.max_error = a->max_error_abs > 0 ? a->max_error_abs : a->max_error;
                        o.max_error_is_absolute = a->max_error_abs > 0;
                        SlimFitResult r;
                        try {
                          const Progress progress("fit", progress_allowed(common), Progress::Indeterminate{});
                          r = mesh ? fit_slim(cloud, *mesh, o) : fit_slim(cloud, o);
                        } catch (const InvalidInput& e) {  // unusable data: say which file held it
                          throw InvalidInput(fmt::format("{}: {}", a->points, e.what()));
                        }
                        r.model.metadata["producer"] = command_line();
                        const auto& s = r.stats;
                        nlohmann::json j = {{"points", s.points},
                                            {"copies_merged", copies},
                                            {"outliers", {{"checked", !mesh && !a->keep_outliers},
                                                          {"left_out", outliers.size()},
                                                          {"first", std::vector<std::uint32_t>(
                                                                        outliers.begin(),
                                                                        outliers.begin() + std::ptrdiff_t(std::min<std::size_t>(outliers.size(), 100)))}}},
                                            {"patches", s.patches},
                                            {"normals", s.normals_estimated ? "estimated" : "given"},
                                            {"normals_turned", s.normals_turned},
                                            {"crease_points", s.crease_points},
                                            {"noise_abs", s.noise},
                                            {"noise_rel", s.noise / s.diagonal},
                                            {"max_error_abs", s.max_error_abs},
                                            {"max_error_rel", s.max_error_abs / s.diagonal},
                                            {"diagonal", s.diagonal},
                                            {"measured_max_abs", s.max_blend},
                                            {"measured_rms_abs", s.rms_blend},
                                            {"measured_max_rel", s.max_blend / s.diagonal},
                                            {"measured_rms_rel", s.rms_blend / s.diagonal},
                                            {"points_beyond_bound", s.blend_failures},
                                            {"surface", {{"checked", a->options.check_surface},
                                                         {"bound_abs", a->options.surface_factor * s.max_error_abs},
                                                         {"samples", s.surface_samples},
                                                         {"max_abs", s.surface_max},
                                                         {"p999_abs", s.surface_p999},
                                                         {"max_rel", s.surface_max / s.diagonal},
                                                         {"p999_rel", s.surface_p999 / s.diagonal},
                                                         {"samples_beyond_bound", s.surface_failures}}},
                                            {"hole_share", s.hole_share},
                                            {"max_hole_share", a->options.max_hole_share},
                                            {"within_bound", s.blend_failures == 0 && s.surface_failures == 0 && !s.holes_exceeded},
                                            {"repair_rounds", s.repair_rounds},
                                            {"round_failures", s.round_failures},
                                            {"round_breaches", s.round_breaches},
                                            {"kept_round", s.kept_round},
                                            {"hole_points", s.hole_points},
                                            {"hole_face_patches", s.hole_face_patches},
                                            {"face_holes", s.face_holes},
                                            {"view_face_patches", s.view_face_patches},
                                            {"view_balls", s.view_balls},
                                            {"view_holes", s.view_holes},
                                            {"point_holes", s.point_holes},
                                            {"point_hole_balls", s.point_hole_balls},
                                            {"disc_patches", s.disc_patches},
                                            {"clips_relaxed", s.clips_relaxed},
                                            {"crease_gaps", s.crease_gaps},
                                            {"seen_point_holes", s.seen_point_holes},
                                            {"height_patches", s.height_patches},
                                            {"clipped_patches", s.clipped_patches},
                                            {"seconds", {{"normals", s.time_normals},
                                                         {"candidates", s.time_candidates},
                                                         {"cover", s.time_cover},
                                                         {"verify", s.time_verify},
                                                         {"total", s.time_total}}}};
                        if (s.normals_estimated && !cloud.has_normals())
                          log::warn("{}: no normals in the file; estimated them (PCA + MST orientation)", a->points);
                        std::string held_out;  // for the summary: the figure --holdout asks for
                        if (!held.points.empty()) {
                          const SlimError e = evaluate_slim(r.model, held, {.keep_per_point = true});
                          j["holdout"] = {{"points", e.points}, {"misses", e.misses}, {"max_abs", e.max},
                                          {"rms_abs", e.rms}, {"max_rel", e.max / s.diagonal},
                                          {"beyond_bound", e.count_above(s.max_error_abs)}};
                          held_out = fmt::format("; {} held-out points max {:.3g}, {} beyond E{}", e.points, e.max,
                                                 e.count_above(s.max_error_abs),
                                                 e.misses ? fmt::format(", {} met no surface", e.misses) : "");
                        }
                        {
                          // Each patch's measured error (the points side, per patch) for render --colour-by error.
                          const double t0 = report.elapsed();
                          const PatchErrors pe =
                              slim_patch_errors(r.model, cloud, {.surface = mesh ? r.data.get() : nullptr});
                          set_measured_errors(r.model, pe);
                          j["patch_errors"] = {
                              {"measured_patches", std::count_if(pe.per_patch.begin(), pe.per_patch.end(),
                                                                 [](const auto& e) { return e.has_value(); })},
                              {"max_abs", pe.max},
                              {"misses", pe.misses},
                              {"seconds", report.elapsed() - t0}};
                        }
                        if (a->lod_levels > 0) {
                          SlimHierarchyOptions lod = a->lod;
                          lod.levels = a->lod_levels;
                          lod.rule = a->lod_rule == "merge" ? SlimLevelRule::merge : SlimLevelRule::fits;
                          const SlimLevelsStats hs = add_slim_hierarchy(r, cloud, mesh ? &*mesh : nullptr, o, lod);
                          j["hierarchy"] = {{"levels", hs.patches.size()},
                                            {"rule", lod.rule == SlimLevelRule::fits ? "fits" : "merge"},
                                            {"patches", hs.patches},
                                            {"max_error_abs", hs.max_error},
                                            {"dropped", hs.dropped},
                                            {"seconds", hs.seconds}};
                          if (lod.rule == SlimLevelRule::fits) {
                            j["hierarchy"]["bound_abs"] = hs.bound;
                            j["hierarchy"]["fit_seconds"] = hs.fit_seconds;
                          }
                        }
                        write_model(r.model, a->out, a->write);
                        report.json["fit"] = j;
                        // Holes the fit counted and left, as the report has them.
                        std::vector<std::string> holes;
                        if (s.point_holes > 0) holes.push_back(fmt::format("{} points' coverage discs not held", s.point_holes));
                        if (s.face_holes > 0) holes.push_back(fmt::format("{} face spots outside every ball", s.face_holes));
                        if (s.view_holes > 0) holes.push_back(fmt::format("{} faces seen through", s.view_holes));
                        if (s.crease_gaps > 0) holes.push_back(fmt::format("{} slit samples at creases", s.crease_gaps));
                        if (s.seen_point_holes > 0) holes.push_back(fmt::format("{} holes between the points seen through", s.seen_point_holes));
                        report.summary = fmt::format(
                            "wrote {}: {} patches for {} points{}; points max {:.3g}, surface max {:.3g} p99.9 {:.3g}{} "
                            "(E = {:.3g}{})", a->out, s.patches, s.points,
                            outliers.empty() ? ""
                                              : fmt::format(" ({} outlier{} left out)", outliers.size(), outliers.size() == 1 ? "" : "s"),
                            s.max_blend,
                            s.surface_max, s.surface_p999, held_out, s.max_error_abs,
                            holes.empty() ? "" : fmt::format("; holes left: {}", fmt::join(holes, ", ")));
                        if (s.blend_failures == 0 && s.surface_failures == 0 && !s.holes_exceeded) return kOk;
                        // The holes the share counts (SlimFitStats::hole_share), not the coverage discs.
                        std::vector<std::string> counted;
                        if (mesh) {
                          if (s.view_holes > 0) counted.push_back(fmt::format("{} faces seen through", s.view_holes));
                          if (s.face_holes > 0) counted.push_back(fmt::format("{} face spots outside every ball", s.face_holes));
                        } else {
                          if (s.seen_point_holes > 0) counted.push_back(fmt::format("{} points with a hole seen through", s.seen_point_holes));
                          if (s.crease_gaps > 0) counted.push_back(fmt::format("{} slit samples at creases", s.crease_gaps));
                        }
                        const auto what = fmt::format(
                            "{}: finished outside the bound: {} of {} points beyond E = {:.3g} (max {:.3g}), {} of {} "
                            "surface samples beyond {:g}E (max {:.3g}), {:.3g} of the data seen through (at most {:g}: "
                            "{}); the model was written to {}",
                            a->points, s.blend_failures, s.points, s.max_error_abs, s.max_blend, s.surface_failures,
                            s.surface_samples, a->options.surface_factor, s.surface_max, s.hole_share,
                            a->options.max_hole_share, counted.empty() ? "no holes" : fmt::format("{}", fmt::join(counted, ", ")),
                            a->out);
                        if (a->allow_exceed) {
                          log::warn("{}", what);
                          return kOk;
                        }
                        std::cerr << "quadrix: " << what << " (--allow-exceed accepts it)\n";
                        report.exceeded = what;
                        return kExceeded;
                      }});
}

}  // namespace quadrix::cli
