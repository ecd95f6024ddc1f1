#include "fit/slim_fit.h"
#include "fit/slim_fitter.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <array>
#include <numbers>
#include <numeric>
#include <optional>
#include <span>
#include <queue>
#include <mutex>
#include <random>
#include <memory>
#include <thread>
#include <tuple>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "core/error.h"
#include "core/io/io.h"
#include "core/log.h"
#include "core/morton.h"
#include "core/reference.h"
#include "core/slim.h"
#include "fit/data_surface.h"
#include "fit/evaluate.h"
#include "fit/local_fit.h"
#include "fit/normals.h"
#include "fit/outliers.h"
#include "fit/patch_colour.h"
#include "fit/point_index.h"

namespace quadrix {
namespace {

using Clock = std::chrono::steady_clock;
// A cloud's own normals are replaced by estimated ones when more than this share lies more than
// 60° off their neighbours' plane, and turned by an estimated orientation when more than this
// share points against their neighbours (check_given_normals).
constexpr double kGivenNormalsOffPlane = 0.25, kGivenNormalsAgainst = 0.10;
// E below this many times the cloud's noise (SlimFitStats::noise) is warned about.
constexpr double kNoiseDeviations = 3.0;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void validate(const PointCloud& cloud, const SlimFitOptions& o) {
  const std::size_t n = cloud.points.size();
  if (n < 10) throw InvalidInput(fmt::format("fit_slim: {} point{}; at least 10 are needed", n, n == 1 ? "" : "s"));
  if (cloud.has_normals() && cloud.normals.size() != n)
    throw InvalidInput(fmt::format("fit_slim: {} normals for {} points", cloud.normals.size(), n));
  for (std::size_t i = 0; i < n; ++i) {
    if (!cloud.points[i].allFinite())
      throw InvalidInput(fmt::format("fit_slim: point {} is not finite ({}, {}, {})", i, cloud.points[i].x(),
                                     cloud.points[i].y(), cloud.points[i].z()));
    if (cloud.has_normals() && !(cloud.normals[i].allFinite() && cloud.normals[i].norm() > 1e-12))
      throw InvalidInput(fmt::format("fit_slim: normal {} is zero or not finite ({}, {}, {})", i,
                                     cloud.normals[i].x(), cloud.normals[i].y(), cloud.normals[i].z()));
  }
  if (!(o.max_error > 0) || !std::isfinite(o.max_error))
    throw InvalidInput(fmt::format("fit_slim: max_error must be positive and finite, got {}", o.max_error));
  if (!(o.normal_weight > 0)) throw InvalidInput(fmt::format("fit_slim: normal_weight must be > 0, got {}", o.normal_weight));
  if (!(o.radius_growth > 1)) throw InvalidInput(fmt::format("fit_slim: radius_growth must be > 1, got {}", o.radius_growth));
  if (o.cover_fraction && !(*o.cover_fraction > 0 && *o.cover_fraction <= 1))
    throw InvalidInput(fmt::format("fit_slim: cover_fraction must lie in (0, 1], got {}", *o.cover_fraction));
  if (!(o.weight_floor >= 0)) throw InvalidInput(fmt::format("fit_slim: weight_floor must be ≥ 0, got {}", o.weight_floor));
  if ((o.sharp || o.sharp_at_creases) && !(o.sharp_angle_deg > 0 && o.sharp_angle_deg < 180))
    throw InvalidInput(fmt::format("fit_slim: sharp_angle_deg must lie in (0, 180), got {}", o.sharp_angle_deg));
  if (o.min_points < 3) throw InvalidInput(fmt::format("fit_slim: min_points must be ≥ 3, got {}", o.min_points));
  if (o.max_fit_points < 10) throw InvalidInput(fmt::format("fit_slim: max_fit_points must be ≥ 10, got {}", o.max_fit_points));
  // Degenerate point sets: coincident, or all on one plane (no surface to enclose).
  Box3 box;
  for (const auto& p : cloud.points) box.extend(p);
  const double diag = box.diagonal();
  if (!(diag > 0)) throw InvalidInput(fmt::format("fit_slim: all {} points coincide", n));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : cloud.points) mean += p;
  mean /= double(n);
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& p : cloud.points) C += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
  // Off their line first (the largest axis), then off their plane: points on a line are called
  // collinear, not coplanar.
  const Eigen::Vector3d along = eig.eigenvectors().col(2), axis = eig.eigenvectors().col(0);
  double off_line = 0, off = 0;
  for (const auto& p : cloud.points) {
    const Eigen::Vector3d d = p - mean;
    off_line = std::max(off_line, (d - along.dot(d) * along).norm());
    off = std::max(off, std::abs(axis.dot(d)));
  }
  if (off_line <= 1e-9 * diag)
    throw InvalidInput(fmt::format("fit_slim: the {} points are collinear (largest distance from their line {:.3g}, "
                                   "diagonal {:.6g}); a SLIM surface needs a 3-D point set",
                                   n, off_line, diag));
  if (off <= 1e-9 * diag)
    throw InvalidInput(fmt::format("fit_slim: the {} points are coplanar (largest distance from their plane {:.3g}, "
                                   "diagonal {:.6g}); a SLIM surface needs a 3-D point set",
                                   n, off, diag));
}

}  // namespace

namespace fit_detail {

SlimFitResult SlimFitter::run() {
  const auto t_start = Clock::now();
  validate(cloud_, opt_);
  setup();
  auto t0 = Clock::now();
  initial_candidates();
  st_.time_candidates = seconds_since(t0);
  t0 = Clock::now();
  cover(nullptr);
  st_.patches_before_pruning = chosen_.size();
  prune();
  st_.time_cover = seconds_since(t0);
  build_model();
  t0 = Clock::now();
  verify_and_repair();
  // The holes reported are the kept model's: where they are not filled they were counted in the
  // first round only, and the repairs since open and close some (kitten at 1e-3: 27 counted on
  // the first model, 52 on the one kept).
  // Holes between the points, seen through, are counted on the kept model wherever the rounds did
  // not track them to the end: where the points' holes were filled, the coverage discs came out
  // held while the patches' repairs left gaps between them (3,000 points of an exact sphere at
  // 1e-6: 0 holes said, 55 % of bench fit's pixels open).
  // So they are where the points' holes were left open (more than point_hole_share of the
  // points with one: the rounds count only coverage discs, and 800 points of an exact sphere at
  // 1e-6 ended with 99.9 % of bench fit's pixels open and exit 0): the hole share decides the
  // exit code.
  // Whether or not they were filled (`--no-fill-point-holes` left every hole open and counted
  // none: hole share 0 and exit 0 for a 400-point sphere at 1e-4 whose fit showed 382 holes).
  const bool count_seen = !surface_ && opt_.see_point_holes && !see_point_holes_;
  if (!surface_ && ((opt_.cover_point_holes && !point_holes_fresh_) || count_seen) && !result_.model.slims.empty()) {
    std::vector<Eigen::Vector3d> centres;
    for (const auto& s : result_.model.slims) centres.push_back(s.centre);
    const PointIndex centre_index{std::span<const Eigen::Vector3d>(centres)};
    const auto gaps = point_holes(centre_index, nullptr);
    st_.point_holes = gaps.size();
    point_holes_fresh_ = true;
    if (seen_counted_late_ || count_seen) {
      st_.seen_point_holes = seen_holes(gaps, centre_index, ReferenceScene(result_.model)).size();
      if (fill_point_holes_ && !seen_counted_late_ && double(st_.seen_point_holes) > opt_.seen_hole_share * double(P_.size()))
        warn_below_sampling(fmt::format("{} holes between {} points seen through", st_.seen_point_holes, P_.size()));
    }
  }
  st_.time_verify = seconds_since(t0);
  st_.time_total = seconds_since(t_start);
  finish();
  return std::move(result_);
}

void SlimFitter::setup() {
  const std::size_t n = P_.size();
  st_.points = n;
  Box3 box;
  for (const auto& p : P_) box.extend(p);
  st_.diagonal = box.diagonal();
  E_ = opt_.max_error_is_absolute ? opt_.max_error : opt_.max_error * st_.diagonal;
  st_.max_error_abs = E_;
  st_.cover_fraction = cover_fraction();
  const auto t0 = Clock::now();
  if (cloud_.has_normals()) {
    N_.resize(n);
    for (std::size_t i = 0; i < n; ++i) N_[i] = cloud_.normals[i].normalized();
    // A cloud's own normals are checked against its points (a mesh's come from its faces, turned
    // to agree when read): random normals fitted a sphere with 10,000 patches for 10,000 points
    // and left 47 % of its silhouette open; half of them flipped, 6,586 patches and pinholes;
    // both exited 0, the checks judging the surface by the same normals. Noisy normals (CGAL's
    // sphere_20k_normal: up to 30° off; 13.7 % off the plane, 1.8 % against) fit better than
    // estimated ones (7,177 patches at 1e-2 against 9,435) and are kept; so are the two sides of
    // a noisy thin plate (a share of their neighbours across the plate count as against).
    if (!surface_) {
      const GivenNormalsCheck c = check_given_normals(P_, N_);
      log::debug("fit_slim: given normals: {:.3g} % off their neighbours' plane, {:.3g} % against their neighbours",
                 100 * c.off_plane_share(), 100 * c.against_share());
      if (c.off_plane_share() > kGivenNormalsOffPlane) {
        N_ = estimate_normals(P_, {.neighbours = opt_.normal_neighbours}).normals;
        st_.normals_estimated = true;
        log::warn("fit_slim: {:.3g} % of the cloud's normals lie more than 60° from the plane of their neighbours; "
                  "estimated them instead (PCA over {} neighbours, MST orientation)",
                  100 * c.off_plane_share(), opt_.normal_neighbours);
      } else if (c.against_share() > kGivenNormalsAgainst) {
        const NormalEstimation est = estimate_normals(P_, {.neighbours = opt_.normal_neighbours});
        // Per part of the points (the estimate orients each away from its own centroid, wrong for
        // a shell's inner wall or an open sheet): the sign that turns fewer of its normals.
        std::vector<std::ptrdiff_t> votes(est.components, 0);
        for (std::size_t i = 0; i < n; ++i) votes[est.component[i]] += N_[i].dot(est.normals[i]) < 0 ? -1 : 1;
        std::size_t turned = 0;
        for (std::size_t i = 0; i < n; ++i) {
          const double sign = votes[est.component[i]] < 0 ? -1.0 : 1.0;
          if (N_[i].dot(sign * est.normals[i]) < 0) N_[i] = -N_[i], ++turned;
        }
        st_.normals_turned = turned;
        log::warn("fit_slim: {:.3g} % of the cloud's normals point against their neighbours'; {} of {} turned to "
                  "agree with an orientation propagated over the points (MST)",
                  100 * c.against_share(), turned, n);
      }
    }
  } else {
    const NormalEstimation est = estimate_normals(P_, {.neighbours = opt_.normal_neighbours});
    N_ = est.normals;
    st_.normals_estimated = true;
    log::info("fit_slim: the cloud has no normals; estimated them (PCA over {} neighbours, MST orientation{})",
              opt_.normal_neighbours,
              est.turned_by_parity ? fmt::format("; {} turned by ray parity at knife edges", est.turned_by_parity) : "");
  }
  st_.time_normals = seconds_since(t0);
  // The point indices and the data's surface are independent: built side by side.
  auto t1 = Clock::now();
  tbb::parallel_invoke(
      [&] {
        index_ = std::make_unique<PointIndex>(P_);
        subsamples_ = std::make_unique<Subsamples>(P_, 4 * opt_.max_check_points, opt_.seed);
      },
      [&] {
        data_ = std::make_shared<DataSurface>(surface_ ? DataSurface::from_mesh(*surface_) : DataSurface::from_points(P_, N_, {.bent_discs = opt_.bent_discs, .crease_cuts = opt_.crease_cuts, .crease_points = opt_.crease_points && st_.normals_estimated, .rim_cuts = opt_.rim_cuts, .hole_rims = opt_.hole_rims}));
      });
  log::debug("fit_slim: point indices and the data's surface ({}) in {:.2f} s", surface_ ? "mesh" : "tangent discs",
             seconds_since(t1));
  // Crease points (DataSurfaceOptions::crease_points, estimated normals): the fit takes their
  // faces' normals too, so its checks build each point's disc as the data does.
  if (!surface_ && data_->crease_points() > 0) {
    for (std::size_t i = 0; i < n; ++i) N_[i] = data_->normal(i);
    st_.crease_points = data_->crease_points();
    log::info("fit_slim: {} points lie where two or three planes meet (a sharp edge or corner) with a normal off "
              "them; each takes the plane of its face ({} on an edge also give the other face a disc there)",
              data_->crease_points(), data_->crease_copies());
  }
  if (!surface_) warn_below_noise();
  t1 = Clock::now();
  probe_height_ = probe_heights(P_, N_, opt_.probe_factor * E_, surface_ ? data_.get() : nullptr);
  log::debug("fit_slim: probe heights in {:.2f} s", seconds_since(t1));
  if (surface_ && opt_.face_patches && face_of_.size() == n)
    faces_ = std::make_unique<FaceSet>(*surface_, std::move(face_of_), P_, opt_.face_prisms);
  if (faces_)
    for (std::size_t k = 0; k < faces_->mesh->face_count(); ++k)
      if (faces_->centroid[k] != FaceSet::kNone) face_triangles_ += faces_->mesh->face(k).size() - 2;
  make_fitter();
  st_.subsample_levels = subsamples_->levels.size();
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0u);
  std::mt19937_64 rng(opt_.seed);
  std::shuffle(order_.begin(), order_.end(), rng);
  covered_.assign(n, 0);
  uncovered_ = n;
  cap_.assign(n, std::numeric_limits<double>::infinity());
}

// A user who asked for an E the cloud's sampling cannot resolve is told so at the default
// verbosity, with the figure that decides it: the holes are left (filling them bent the surface
// more than 2E off the points' tangent discs), and the fit otherwise looks complete (oni.ply from
// CGAL's demo data at 1e-3: 59 % of its points with a hole, 19 % of the pixels open, exit 0, and
// the reason only at -v).
void SlimFitter::warn_below_sampling(const std::string& what) const {
  std::vector<double> spacing;
  const std::size_t n = P_.size(), step = std::max<std::size_t>(1, n / 20000);
  for (std::size_t i = 0; i < n; i += step) spacing.push_back(data_->spacing(i));
  std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
  const double median = spacing[spacing.size() / 2];
  log::warn("fit_slim: {}: E = {:.3g} ({:.2g} of the diagonal) is below what the sampling resolves, so they are left "
            "open (a surface across them would bend more than 2E off the points' tangent discs); the points' median "
            "spacing is {:.3g} ({:.2g} of the diagonal): a larger --max-error closes them",
            what, E_, E_ / st_.diagonal, median, median / st_.diagonal);
}

// A user who asked for an E within the cloud's noise is told so, with the figure: every point
// within E of a surface through noise of about E takes a patch for every few points, and the
// surface side and its holes suffer with it (CGAL's blobby.xyz at 1e-2, noise 0.013 of the
// diagonal: 1,907 patches for 3,288 points; hippo1 at 1e-3, noise 6.3e-4: 1,423 for 6,104, where
// 3e-3 takes 198). Three deviations: uniform noise of ±E/2 (deviation 0.29E) fits within E.
void SlimFitter::warn_below_noise() {
  const auto t0 = Clock::now();
  st_.noise = estimate_noise(P_, N_, *index_);
  log::debug("fit_slim: the points scatter {:.3g} about their local surface ({:.2f} s)", st_.noise, seconds_since(t0));
  if (!(E_ < kNoiseDeviations * st_.noise)) return;
  log::warn("fit_slim: the points scatter {:.3g} ({:.2g} of the diagonal) about their local surface (the median RMS "
            "off a quadric through each point's 16 nearest): E = {:.3g} ({:.2g} of the diagonal) is less than {} times "
            "that, so the surface follows the noise, with a patch for every few points; a --max-error of {:.2g} or more "
            "fits a surface through it",
            st_.noise, st_.noise / st_.diagonal, E_, E_ / st_.diagonal, kNoiseDeviations,
            kNoiseDeviations * st_.noise / st_.diagonal);
}

void SlimFitter::make_fitter() {
  fitter_ = std::make_unique<BallFitter>(BallFitter{P_, N_, *index_, opt_, E_, opt_.probe_factor * E_});
  fitter_->subsamples = subsamples_.get();
  fitter_->data = data_.get();
  fitter_->faces = faces_.get();
  fitter_->diagonal = st_.diagonal;
  // Clouds whose points lie on faces meeting at sharp edges (DataSurface::faced where the fit
  // estimated the normals; with given normals the planar points, below): the points beside such
  // faces, and those beside an edge or corner
  // (beside_crease). Beside such faces a ball that fails tries its centre's sheet clipped at the
  // other faces' planes, as `--sharp` does everywhere: a box of 20,000 points without normals at
  // 1e-3 took 674 patches and left 2.9e-4 of the true box's pixels as holes, most within 15E of
  // a corner, where balls shrank until they held one or two faces; now 107 patches, 1.2e-4.
  // (Only beside an edge or corner, a 30° wedge, whose knife edge is no crease, took 1.6× the
  // patches and 4× the holes at 1e-3.) The holes beside an edge or corner do not decide whether
  // every hole is filled (below).
  near_crease_.clear();
  bool on_faces = false;
  if (!surface_ && data_)
    for (std::size_t i = 0; i < P_.size() && !on_faces; ++i) on_faces = data_->faced(i);
  // Given normals (each point its face's own, as a CAD model sampled gives them), no point is
  // faced: the points on a face are the planar ones. (Without this the same box with its exact
  // normals fitted worse than without them: 647 patches and 5.3e-4 of its pixels open, against
  // 96 and 3.3e-5; now 156 and 6.6e-5.)
  planar_faces_ = !on_faces && !surface_ && data_ && !st_.normals_estimated;
  if (on_faces || planar_faces_) {
    near_crease_.assign(P_.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P_.size(), 1024), [&](const auto& r) {
      std::vector<Neighbour> nb;
      // (Given normals: only a planar point, so a smooth scan's million points cost little.)
      for (std::size_t i = r.begin(); i != r.end(); ++i)
        near_crease_[i] = planar_faces_ && !data_->planar(i) ? 0 : beside_crease(i, nb);
    });
    if (opt_.sharp_at_creases && !opt_.sharp) fitter_->sharp_at = &near_crease_;
    log::debug("fit_slim: {} points lie beside faces found at creases, {} of them beside an edge or corner",
               std::count_if(near_crease_.begin(), near_crease_.end(), [](std::uint8_t f) { return f != 0; }),
               std::count_if(near_crease_.begin(), near_crease_.end(), [](std::uint8_t f) { return (f & kAtEdge) != 0; }));
  }
}

// Fits a ball around each centre (TBB-parallel) and records the points it covers. Radius
// search warm-starts from the nearest pilot candidate; caps bound the radius (repair).
void SlimFitter::evaluate(const std::vector<std::uint32_t>& centres, const std::vector<double>* caps) {
  const std::size_t first = balls_.size();
  balls_.resize(first + centres.size());
  covers_.resize(first + centres.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, centres.size(), 4), [&](const tbb::blocked_range<std::size_t>& r) {
    BallFitter::Scratch s;
    std::vector<Neighbour> pn;
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      double guess = 0;
      if (pilot_index_) {
        pilot_index_->nearest(P_[centres[k]], 1, pn);
        guess = pilot_R_[pn[0].first];
      }
      Ball b = fitter_->grow(centres[k], s, caps ? (*caps)[k] : std::numeric_limits<double>::infinity(), guess);
      if (!opt_.lazy_surface_check) b = fitter_->settle(std::move(b), s);
      balls_[first + k] = std::move(b);
      cover_of(first + k, s.nb);
    }
  });
}

// The points candidate b covers: those within cover_fraction·R of its centre (½R for a ball
// that never reached E) on its sheet.
void SlimFitter::cover_of(std::size_t b, std::vector<Neighbour>& nb) {
  const Ball& ball = balls_[b];
  const Eigen::Vector3d& c = P_[ball.centre];
  if (ball.face >= 0) {  // a face patch covers the points on its face
    index_->radius(c, ball.R, nb);
    auto& cov = covers_[b];
    cov.clear();
    for (const auto& [p, d2] : nb)
      if (faces_->distance(std::uint32_t(ball.face), P_[p]) <= 1e-3 * E_) cov.push_back(p);
    balls_[b].count = nb.size();
    return;
  }
  index_->radius(c, (ball.is_bounded ? cover_fraction() : 0.5) * ball.R, nb);
  auto& cov = covers_[b];
  cov.clear();
  for (const auto& [p, d2] : nb)
    if (ball.owns((P_[p] - c) / ball.R, N_[p])) cov.push_back(p);
}

void SlimFitter::grow_candidate_arrays() {
  const std::size_t n = balls_.size();
  covers_.resize(n);
  chosen_flag_.resize(n, 0);
  pinned_.resize(n, 0);
  // Not verified yet: the next round traces them whole.
  patch_excess_.resize(n, -1.0);
  patch_errors_.resize(n);
  patch_reach_.resize(n, kInf);
}

std::vector<std::uint32_t> SlimFitter::new_candidates(const std::vector<std::uint32_t>& centres, const std::vector<double>& caps) {
  const std::size_t first = balls_.size();
  evaluate(centres, &caps);
  std::vector<std::uint32_t> fresh(balls_.size() - first);
  std::iota(fresh.begin(), fresh.end(), std::uint32_t(first));
  settle(fresh);
  grow_candidate_arrays();
  return fresh;
}

// The surface side of candidates (BallFitter::settle), in parallel; their covers follow.
void SlimFitter::settle(const std::vector<std::uint32_t>& ids) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ids.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    BallFitter::Scratch s;
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const std::uint32_t b = ids[k];
      if (balls_[b].settled) continue;
      balls_[b] = fitter_->settle(std::move(balls_[b]), s);
      cover_of(b, s.nb);
    }
  });
}

// A random fraction of the points; the first pilot_candidates search their radius from scratch.
void SlimFitter::initial_candidates() {
  const std::size_t n = P_.size();
  const std::size_t m0 = std::min(
      {n, opt_.max_candidates, std::max(opt_.min_candidates, std::size_t(opt_.candidate_fraction * double(n)))});
  std::vector<std::uint32_t> centres(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(m0));
  if (const std::size_t pilot = opt_.pilot_candidates; pilot > 0 && pilot < centres.size()) {
    std::vector<std::uint32_t> first(centres.begin(), centres.begin() + static_cast<std::ptrdiff_t>(pilot)),
        rest(centres.begin() + static_cast<std::ptrdiff_t>(pilot), centres.end());
    evaluate(first, nullptr);
    for (const auto& b : balls_)
      if (b.is_bounded) pilot_centres_.push_back(P_[b.centre]), pilot_R_.push_back(b.R);
    if (!pilot_centres_.empty())
      pilot_index_ = std::make_unique<PointIndex>(std::span<const Eigen::Vector3d>(pilot_centres_));
    // As many candidates as the pilots say the covering needs (about n / their mean cover,
    // balls overlapping about twice), times candidates_per_patch for the greedy to choose from.
    double covered = 0;
    for (std::size_t k = 0; k < pilot; ++k) covered += double(covers_[k].size());
    const double mean_cover = std::max(1.0, covered / double(pilot));
    const auto wanted = std::size_t(opt_.candidates_per_patch * 2.0 * double(n) / mean_cover);
    const std::size_t keep = std::clamp(wanted, std::min(opt_.min_candidates, rest.size()), rest.size());
    rest.resize(keep - std::min(keep, pilot));
    evaluate(rest, nullptr);
  } else {
    evaluate(centres, nullptr);
  }
}

std::size_t SlimFitter::gain(std::uint32_t b) const {
  std::size_t g = 0;
  for (auto p : covers_[b]) g += !covered_[p];
  return g;
}

void SlimFitter::take(std::uint32_t b) {
  chosen_.push_back(b);
  chosen_flag_[b] = 1;
  for (auto p : covers_[b])
    if (!covered_[p]) covered_[p] = 1, --uncovered_;
}

// Greedy covering over candidates [from, end) (lazy: a candidate's gain only decreases).
// A candidate's surface side is checked when it reaches the top of the heap (lazy_surface_check),
// together with the next unchecked ones in gain order so the checks run in parallel; settling
// may shrink it, and it goes back into the heap with its new gain.
void SlimFitter::run_greedy(std::size_t from) {
  chosen_flag_.resize(balls_.size(), 0);
  for (std::size_t b = from; b < balls_.size(); ++b) heap_.push({gain(std::uint32_t(b)), std::uint32_t(b)});
  const std::size_t batch_size = std::max<std::size_t>(4, 4 * std::thread::hardware_concurrency());
  std::vector<std::uint32_t> batch;
  std::vector<std::pair<std::size_t, std::uint32_t>> aside;
  while (uncovered_ > 0 && !heap_.empty()) {
    auto [g, b] = heap_.top();
    heap_.pop();
    if (g == 0) break;
    const std::size_t now = gain(b);
    if (now < g) {
      if (now > 0) heap_.push({now, b});
      continue;
    }
    if (balls_[b].settled) {
      take(b);
      continue;
    }
    batch.assign(1, b);
    aside.clear();
    for (std::size_t looked = 0; batch.size() < batch_size && looked < 4 * batch_size && !heap_.empty(); ++looked) {
      const auto next = heap_.top();
      heap_.pop();
      // Only candidates whose gain is current join the batch (a stale one would rank lower).
      if (const std::size_t gn = gain(next.second); gn < next.first) {
        if (gn > 0) aside.push_back({gn, next.second});
      } else if (balls_[next.second].settled) {
        aside.push_back(next);
      } else {
        batch.push_back(next.second);
      }
    }
    settle(batch);
    for (const auto& a : aside) heap_.push(a);
    for (const auto c : batch)
      if (const std::size_t gc = gain(c); gc > 0) heap_.push({gc, c});
  }
}

// Greedy covering, adding uncovered points as new candidates until every point is covered (or
// has been tried as a centre once in this covering).
void SlimFitter::cover(const std::vector<double>* cap_of_point) {
  run_greedy(0);
  // Each uncovered point is tried as a centre at most once per covering, so the loop ends even
  // where a point's own candidate does not cover it; such points stay uncovered, and the
  // verification judges the blend there.
  std::vector<std::uint8_t> tried(P_.size(), 0);
  while (uncovered_ > 0) {
    const std::size_t limit = std::max<std::size_t>(64, uncovered_ / 16);
    std::vector<std::uint32_t> fresh;
    std::vector<double> caps;
    for (auto p : order_)
      if (!covered_[p] && !tried[p]) {
        tried[p] = 1;
        fresh.push_back(p);
        if (cap_of_point) caps.push_back((*cap_of_point)[p]);
        if (fresh.size() >= limit) break;
      }
    if (fresh.empty()) {
      log::debug("fit_slim: {} points left uncovered: no candidate centred on them covers them", uncovered_);
      break;
    }
    const std::size_t from = balls_.size();
    evaluate(fresh, cap_of_point ? &caps : nullptr);
    run_greedy(from);
  }
}

// Drops balls whose covered points are all covered by other chosen balls (smallest first).
void SlimFitter::prune() {
  std::vector<std::uint16_t> multiplicity(P_.size(), 0);
  for (auto b : chosen_)
    for (auto p : covers_[b]) multiplicity[p] = std::uint16_t(std::min<int>(multiplicity[p] + 1, 60000));
  std::sort(chosen_.begin(), chosen_.end(), [&](auto a, auto b) { return covers_[a].size() < covers_[b].size(); });
  std::vector<std::uint32_t> kept;
  for (auto b : chosen_) {
    const bool redundant = !(b < pinned_.size() && pinned_[b]) &&
                           std::all_of(covers_[b].begin(), covers_[b].end(), [&](auto p) { return multiplicity[p] >= 2; });
    if (redundant) {
      for (auto p : covers_[b]) --multiplicity[p];
      chosen_flag_[b] = 0;
    } else {
      kept.push_back(b);
    }
  }
  chosen_.swap(kept);
}

void SlimFitter::build_model() {
  auto& slims = result_.model.slims;
  slims.clear();
  for (auto b : chosen_) slims.push_back(SlimPatch{P_[balls_[b].centre], balls_[b].R, balls_[b].g, balls_[b].clips, std::nullopt, std::nullopt});
  result_.model.metadata["slim_offset"] = fmt::format("{:.6g}", opt_.blend_offset);
  if (const SlimBlendOptions b = blend(); std::isfinite(b.max_push))
    result_.model.metadata["slim_max_push"] = fmt::format("{:.9g}", b.max_push);
  else
    result_.model.metadata.erase("slim_max_push");
}

// The blend the bound is certified for (written with the model, build_model).
SlimBlendOptions SlimFitter::blend() const {
  SlimBlendOptions b;
  b.offset = opt_.blend_offset;
  if (opt_.blend_max_push > 0) b.max_push = opt_.blend_max_push * E_;
  return b;
}

// How far the verified model is from its contract: the share of points beyond E, plus the share
// of surface samples beyond the surface bound, plus the share of the data's area outside every
// ball (face_holes: at most one spot per smallest piece of a fan triangle). No count alone: a
// fit below its data's noise trades a few points just past E for many fewer surface samples
// far off, or fewer holes for more of both.
double SlimFitter::failures() const {
  double f = double(st_.blend_failures) / double(std::max<std::size_t>(1, P_.size())) +
             double(st_.surface_failures) / double(std::max<std::size_t>(1, surface_error_.size()));
  if (faces_ && st_.face_holes > 0)
    f += double(st_.face_holes) / (double(std::max<std::size_t>(1, face_triangles_)) * double(1u << (2 * opt_.face_hole_depth)));
  // A fan triangle seen through from some view: counted as the whole triangle.
  if (faces_ && st_.view_holes > 0) f += double(st_.view_holes) / double(std::max<std::size_t>(1, face_triangles_));
  // A point whose coverage disc is not held: counted as its whole disc.
  if (fill_point_holes_ && fillable_holes_ > 0) f += double(fillable_holes_) / double(std::max<std::size_t>(1, P_.size()));
  // Below the fill band, a point's hole a view sees: counted as its whole disc.
  if (see_point_holes_) f += double(st_.seen_point_holes) / double(std::max<std::size_t>(1, P_.size()));
  // A slit sample at a crease (crease_slits): as a point's hole.
  f += double(st_.crease_gaps) / double(std::max<std::size_t>(1, P_.size()));
  return f;
}

// How far the model breaches its bound, all breaches summed: each point beyond E by its
// distance over E less one, each surface sample beyond the bound likewise (at most 100 each: a
// point no surface answers). One patch 4E off counts for more than two samples a hair past 2E.
double SlimFitter::breach_excess() const {
  const double bound = opt_.surface_factor * E_;
  const auto over = [](double d, double b) { return std::isfinite(d) ? std::min(100.0, d / b - 1.0) : 100.0; };
  double x = 0;
  for (const double e : point_error_)
    if (!(e <= E_)) x += over(e, E_);
  for (const double d : surface_error_)
    if (!(d <= bound)) x += over(d, bound);
  return x;
}

SlimFitter::Verified SlimFitter::snapshot(int round, double score, double excess) const {
  Verified v{chosen_, point_error_, {}, st_.blend_failures, st_.surface_failures, st_.face_holes, st_.view_holes, round, score, excess};
  v.point_holes = st_.point_holes;
  v.crease_gaps = st_.crease_gaps;
  v.seen_point_holes = st_.seen_point_holes;
  v.point_holes_fresh = point_holes_fresh_;
  v.patch_errors.reserve(chosen_.size());
  for (const auto b : chosen_) v.patch_errors.push_back(patch_errors_[b]);
  return v;
}

void SlimFitter::restore(Verified&& v) {
  for (const auto b : chosen_) chosen_flag_[b] = 0;
  chosen_ = std::move(v.chosen);
  for (std::size_t k = 0; k < chosen_.size(); ++k) {
    chosen_flag_[chosen_[k]] = 1;
    patch_errors_[chosen_[k]] = std::move(v.patch_errors[k]);
  }
  point_error_ = std::move(v.point_error);
  collect_surface_errors();
  st_.blend_failures = v.blend_failures;
  st_.surface_failures = v.surface_failures;
  st_.face_holes = v.face_holes;
  st_.view_holes = v.view_holes;
  st_.point_holes = v.point_holes;
  st_.crease_gaps = v.crease_gaps;
  st_.seen_point_holes = v.seen_point_holes;
  point_holes_fresh_ = v.point_holes_fresh;
  build_model();
}

// Rounds of verification (both sides); the patches at fault are removed, their centres come
// back no larger than shrink_step·R, and the points they covered are covered again.
void SlimFitter::verify_and_repair() {
  // Where E is far below the data's sampling, the first cover leaves most faces partly outside
  // every ball (bunny at 1e-4: 296,374 spots on 22,882 faces), and their face patches (below:
  // more than one spot per 8 faces) would change most of the model after its first verification,
  // so the whole model would be traced again. They join before it instead.
  if (can_add_points_ && opt_.cover_face_holes && face_prisms() && !result_.model.slims.empty()) {
    std::vector<Eigen::Vector3d> centres;
    for (const auto& s : result_.model.slims) centres.push_back(s.centre);
    const PointIndex centre_index{std::span<const Eigen::Vector3d>(centres)};
    const auto holes = face_holes(centre_index, nullptr);
    if (holes.size() > std::max<std::size_t>(64, faces_->mesh->face_count() / 8)) {
      const std::size_t added = add_face_patches(holes);
      log::info("fit_slim: {} spots of the data's faces lie outside every ball of the first cover (balls smaller than the "
                "faces: E below the data's sampling); {} faces get patches of their own", holes.size(), added);
      st_.hole_face_patches += added;
      prune();
      build_model();
    }
  }
  // From here on the repairs' candidates pass settle's check of the patch alone on the lattice
  // verification checks it on (fine in world units: a large ball's zero set has room for a fin
  // between the coarser lattice's lines). The candidates not chosen are settled again before
  // they join: radar.xyz at 1e-4 ended with one sample beyond 2E after 17 rounds, each repair's
  // re-covering taking a ball whose zero set verification then found 2–8E off the data.
  fitter_->verify_lattice = true;
  {
    std::vector<std::uint8_t> is_chosen(balls_.size(), 0);
    for (const auto b : chosen_) is_chosen[b] = 1;
    for (std::size_t b = 0; b < balls_.size(); ++b) {
      Ball& ball = balls_[b];
      if (is_chosen[b] || !ball.settled || ball.face >= 0 || ball.disc || ball.on_data || !ball.is_bounded) continue;
      if (const auto [grid, depth] = fitter_->surface_lattice(ball.R); depth == 1 && grid > ball.surface_lattice) ball.settled = false;
    }
  }
  std::vector<std::uint32_t> before;  // the chosen balls of the last verified model
  int fill_rounds = 0;  // rounds that added points on face holes
  // The best model verified since the points last changed. A repair can make things worse where
  // E is far below the data's sampling (armadillo at 1e-4: 26 points beyond E after the first
  // round, 3,550 after six more, each changing most balls); the fit then returns the best one,
  // and stops after three rounds that did not improve on it.
  Verified best;
  // The lowest score seen since the points last changed, and the round that reached it: the fit
  // stops after three rounds that improved neither the kept model nor the score.
  double least_score = std::numeric_limits<double>::infinity();
  int least_score_round = -1;
  for (int round = 0;; ++round) {
    // Rounds that add points do not count against repair_rounds (up to face_hole_rounds of them).
    const int budget = opt_.repair_rounds + std::min(fill_rounds, std::max(0, opt_.face_hole_rounds));
    const ReferenceScene scene(result_.model);
    const auto& slims = result_.model.slims;
    std::vector<Eigen::Vector3d> centres;
    for (const auto& s : slims) centres.push_back(s.centre);
    const PointIndex centre_index{std::span<const Eigen::Vector3d>(centres)};
    std::vector<std::uint8_t> at_fault(slims.size(), 0);
    // Which probes to trace: all in the first round; afterwards those that failed, and those
    // whose blend may have changed (their ray meets a ball that left or joined the model).
    std::vector<std::uint8_t> stale_points(P_.size(), 1), stale_patches(slims.size(), 1);
    std::optional<Changed> changed_balls;
    if (round > 0) {
      changed_balls = changed_since(before);
      const Changed& changed = *changed_balls;
      const double bound = opt_.surface_factor * E_, h = opt_.surface_probe_factor * E_;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P_.size(), 1024), [&](const auto& r) {
        std::vector<Neighbour> near;
        for (std::size_t i = r.begin(); i != r.end(); ++i)
          stale_points[i] = !(point_error_[i] <= E_) || other_direction_[i] ||
                            changed.meets(P_[i] + probe_height_[i] * N_[i], -N_[i], point_reach_[i], near);
      });
      std::vector<std::uint8_t> was(balls_.size(), 0);
      for (const auto b : before) was[b] = 1;
      std::vector<Neighbour> near;
      for (std::size_t k = 0; k < slims.size(); ++k) {
        const auto b = chosen_[k];
        if (!was[b] || !std::isfinite(patch_reach_[b])) continue;
        bool failed = false;
        for (const double e : patch_errors_[b]) failed |= e > bound;
        if (failed) continue;
        // Every probe of this patch starts within R + h of its centre and looks patch_reach along.
        stale_patches[k] = changed.near_ball(slims[k].centre, slims[k].radius + h + patch_reach_[b], near);
      }
      std::size_t np = 0, nk = 0;
      for (const auto v : stale_points) np += v;
      for (const auto v : stale_patches) nk += v;
      log::debug("fit_slim: round {}: {} balls changed; tracing {} of {} point probes, {} of {} patches", round + 1,
                 changed.centres.size(), np, P_.size(), nk, slims.size());
    }
    auto t_check = Clock::now();
    st_.blend_failures = verify_points(scene, centre_index, stale_points, at_fault);
    const double t_points = seconds_since(t_check);
    t_check = Clock::now();
    shrink_.clear();
    st_.surface_failures = opt_.check_surface ? verify_surface(scene, stale_patches, at_fault) : 0;
    const double t_surface = seconds_since(t_check);
    t_check = Clock::now();
    std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> holes;
    if (can_add_points_ && opt_.cover_face_holes)
      holes = face_holes(centre_index, changed_balls ? &*changed_balls : nullptr, /*steep=*/true);
    log::debug("fit_slim: round {}: points {:.2f} s, surface {:.2f} s, face holes {:.2f} s", round + 1, t_points, t_surface,
               seconds_since(t_check));
    st_.face_holes = holes.size();
    std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> seen;
    if (can_add_points_ && opt_.cover_face_holes && face_prisms()) {
      const auto t0 = Clock::now();
      seen = view_holes(scene, centre_index, changed_balls ? &*changed_balls : nullptr);
      log::debug("fit_slim: round {}: {} fan triangles seen through from some view ({:.2f} s)", round + 1, seen.size(), seconds_since(t0));
    }
    st_.view_holes = seen.size();
    const bool view_fill = !seen.empty() && round + 2 < budget;
    // Points without faces: coverage discs no ball holds (point_holes). While two verifying
    // rounds remain, a point tried for the first time gets its candidate ball; later, or tried
    // before, a disc patch (its tangent plane: shrunk by the repair where it runs off the data).
    std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> gaps;
    // Outside the band where they are filled (decided in the first round), counted once: on 1M
    // points each check costs about a second.
    if (opt_.cover_point_holes && (round == 0 || fill_point_holes_ || see_point_holes_)) {
      const auto t0 = Clock::now();
      gaps = point_holes(centre_index, changed_balls ? &*changed_balls : nullptr);
      if (!surface_) log::debug("fit_slim: round {}: {} points' coverage discs not held by the balls ({:.2f} s)", round + 1, gaps.size(), seconds_since(t0));
    }
    point_holes_fresh_ = opt_.cover_point_holes && (round == 0 || fill_point_holes_ || see_point_holes_);
    if (point_holes_fresh_) st_.point_holes = fillable_holes_ = gaps.size();
    // Where more than point_hole_share of the points have a hole after the first cover, E is far
    // below what the sampling resolves (kitten at 1e-4: 3,974 of 5,210): what would fill the
    // cells between the points bends away from their tangent discs by more than 2E (filled, the
    // kitten ended with 2,396 surface samples beyond 2E), so the holes are counted and left.
    // Where fewer than point_hole_least have one, the balls are larger than the spacing nearly
    // everywhere and the discs not held sit at creases and corners, where an estimated normal
    // tilts the disc off the data (a box of 20,000 points without normals: 107; the balls and
    // disc patches that filled them stood out as fins 5–13E past its corners).
    // Holes beside an edge or corner of faces meeting at a crease (near_crease_, with estimated
    // or given normals) are discs cut or tilted there whatever the sampling, so only the other
    // points and their holes tell whether E is below what the sampling resolves: fandisk's 6,475
    // vertices without normals at 3e-3 had 330 holes, nearly all there, and filled as the band
    // fills, they stood out as fins (2.5 % of the pixels beyond 2E of the mesh, against 0.28 % left
    // to the holes seen); whether 323 or 330 crossed point_hole_least turned on the data's smallest
    // changes. (Counting every point of a face whose plane a crease point spread across as beside
    // the crease took a sparse box, 2,000 points at 1e-3, out of the band: no hole counted, exit 0,
    // 2.1 % of its pixels open.)
    const auto at_crease = [&](std::uint32_t i) { return !near_crease_.empty() && (near_crease_[i] & kAtEdge) != 0; };
    if (round == 0) {
      disc_shrunk_.assign(P_.size(), 0);
      std::size_t smooth = 0, smooth_points = P_.size();
      for (const auto& g : gaps) smooth += !at_crease(g.first);
      for (const std::uint8_t f : near_crease_) smooth_points -= (f & kAtEdge) != 0;
      if (smooth < gaps.size())
        log::debug("fit_slim: {} of the {} points with a hole lie beside an edge or corner", gaps.size() - smooth, gaps.size());
      const double share = double(smooth) / double(std::max<std::size_t>(1, smooth_points));
      // Beside edges and corners a few discs are cut or tilted off the balls whatever the
      // sampling (6-10 % of the points there on prisms of 20,000 points at 1e-3); three times
      // the band's threshold there means E is below the sampling there too (a box of 2,000
      // points: 28 %), and every hole is filled as in the band.
      const std::size_t edge_points = P_.size() - smooth_points;
      crease_band_ = edge_points > 0 && double(gaps.size() - smooth) >= 3.0 * opt_.point_hole_least * double(edge_points) &&
                     double(gaps.size()) <= opt_.point_hole_share * double(P_.size()) && share <= opt_.point_hole_share;
      fill_point_holes_ = (share >= opt_.point_hole_least && share <= opt_.point_hole_share) || crease_band_;
      see_point_holes_ = opt_.see_point_holes && opt_.cover_point_holes && !surface_ && share < opt_.point_hole_least && !crease_band_;
      if (share > opt_.point_hole_share) {
        if (surface_)
          log::info("fit_slim: {} of {} points have a hole in the surface around them (balls smaller than the points' "
                    "spacing: E below what the sampling resolves); left as they are", gaps.size(), P_.size());
        else
          warn_below_sampling(fmt::format("{} of {} points ({:.0f} %) have a hole in the surface around them", smooth,
                                          smooth_points, 100.0 * share) +
                              (smooth < gaps.size() ? fmt::format(" away from edges ({} in all)", gaps.size()) : std::string()));
      }
    }
    // Points only: slits at creases, closed by moving a clipped patch's plane (crease_slits) while
    // two verifying rounds remain; counted in every round.
    std::vector<std::pair<std::size_t, ClipPlanes>> relaxed;
    if (opt_.relax_clips && !surface_) {
      relaxed = crease_slits(centre_index, scene, at_fault, st_.crease_gaps);
      if (round + 2 >= budget) relaxed.clear();
    }
    // Below the band, the holes a view sees are filled; the others are left (a disc off a crease).
    if (see_point_holes_) {
      const auto t0 = Clock::now();
      gaps = seen_holes(gaps, centre_index, scene);
      st_.seen_point_holes = gaps.size();
      log::debug("fit_slim: round {}: {} holes seen through along the points' normals ({:.2f} s)", round + 1, gaps.size(), seconds_since(t0));
      // Seen through at more than seen_hole_share of the points at the first check: E is below
      // what the sampling resolves over whole regions (radar.xyz at 1e-3, 774 of 20,950 points:
      // the planes and balls that filled them ran off its sphere round after round, 818 patches
      // for 300, and still left 15 % of the pixels open against 22 %); counted and left.
      if (round == 0 && double(gaps.size()) > opt_.seen_hole_share * double(P_.size())) {
        warn_below_sampling(fmt::format("{} holes between {} points seen through", gaps.size(), P_.size()));
        see_point_holes_ = false;
        seen_counted_late_ = true;
        gaps.clear();
      }
    } else if (!fill_point_holes_) {
      gaps.clear();
    } else if (!gaps.empty() && !crease_band_) {
      // In the band, those beside an edge or corner are filled only where a view sees them, as
      // below it.
      std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> smooth, crease;
      for (const auto& g : gaps) (at_crease(g.first) ? crease : smooth).push_back(g);
      if (!crease.empty()) {
        gaps.swap(smooth);
        const auto seen = seen_point_holes(crease, scene);
        // (Those left are counted in the report, not among the failures a repair round can mend.)
        fillable_holes_ -= crease.size() - seen.size();
        gaps.insert(gaps.end(), seen.begin(), seen.end());
        std::sort(gaps.begin(), gaps.end(), by_point_then_spot);
      }
    }
    // A point whose disc patch was shrunk (its plane ran off the data) keeps that patch and its
    // hole: counted, not filled again.
    std::erase_if(gaps, [&](const auto& g) { return disc_shrunk_[g.first] != 0; });
    const bool gap_fill = !gaps.empty() && round < budget;
    // More than one spot per 8 faces: the balls are smaller than the faces nearly everywhere
    // (E far below the data's sampling: bunny at 1e-4 had 88,211 for 69,451 faces). Points
    // there more than doubled the fit's work (51 s instead of 29 s) and left 2,881 points beyond
    // E; such faces get face patches instead (add_face_patches, with face_prisms), else the
    // spots are counted (face_holes) and left.
    const bool few = holes.size() <= std::max<std::size_t>(64, faces_ ? faces_->mesh->face_count() / 8 : 0);
    // Not in the last two rounds: the balls that cover new points need verifying and repairing too.
    const bool fill = !holes.empty() && few && round + 2 < budget;
    // Too many: the faces with spots get face patches of their own (below). So do the faces
    // with spots in the last round that may still change the model (too late for points: the
    // balls that would cover them would go unverified), as face patches are the data itself.
    const bool late = round + 2 >= budget && round + 1 < budget;
    const bool face_fill = !holes.empty() && face_prisms() && ((!few && round + 2 < budget) || late);
    const std::size_t failing =
        st_.blend_failures + st_.surface_failures + (fill || face_fill ? holes.size() : 0) + (view_fill ? seen.size() : 0) +
        (gap_fill ? gaps.size() : 0) + relaxed.size();
    const double score = failures();
    st_.round_failures.push_back(score);
    st_.round_breaches.push_back(st_.blend_failures + st_.surface_failures);
    st_.kept_round = round;
    // The model kept is one within what the exit code promises (no point beyond E, no surface
    // sample beyond 2E) if any round was, whatever their holes; else the one that breaches it
    // least (breach_excess: how far, summed over the breaches); among equals the smaller share of
    // failures wins. (bun000_rawscan at 1e-4 kept a round with 16 surface samples beyond 2E over a
    // later one with none but more points' holes, and exited 7; radar.xyz at 1e-4 kept round 3's
    // 497 samples beyond 2E, max 23E, over later rounds' 77 … 1, whose repairs had opened more
    // points' holes. Counted by number, one patch 8E off would beat two samples a hair past 2E.)
    // While either the kept model or the score improves, the repairs go on.
    const std::size_t breaches = st_.round_breaches.back();
    const std::size_t best_breaches = best.blend_failures + best.surface_failures;
    const double excess = breaches > 0 ? breach_excess() : 0.0;
    bool improved = true;
    if (best.round >= 0) {
      if ((breaches == 0) != (best_breaches == 0)) improved = breaches == 0;
      else if (excess != best.excess) improved = excess < best.excess;
      else improved = score < best.score;
    }
    if (score < least_score) least_score = score, least_score_round = round;
    const bool stalled = !improved && round - best.round >= 3 && round - least_score_round >= 3;
    if (failing == 0 || round >= budget || stalled) {
      if (!improved) {
        log::info("fit_slim: the repairs after verification round {} made the fit worse ({} points beyond E, {} surface "
                  "samples beyond {}E, {} face spots outside every ball, {} faces seen through, {} points' holes and {} "
                  "crease gaps in round {}, against {}, {}, {}, {}, {} and {}); the model of round {} is kept",
                  best.round + 1, st_.blend_failures, st_.surface_failures, opt_.surface_factor, st_.face_holes, st_.view_holes,
                  st_.point_holes, st_.crease_gaps, round + 1, best.blend_failures, best.surface_failures, best.face_holes,
                  best.view_holes, best.point_holes, best.crease_gaps, best.round + 1);
        st_.kept_round = best.round;
        restore(std::move(best));
      }
      break;
    }
    const auto t_fill = Clock::now();
    if (improved) best = snapshot(round, score, excess);
    // The model just verified: what changes from here on (face patches below, the repair) is
    // traced again next round.
    before = chosen_;
    if (fill) {
      ++fill_rounds;
      log::debug("fit_slim: round {}: {} spots of the data's faces outside every ball join the points", round + 1, holes.size());
      // One spot per face (the first; spots come sorted by face): the ball that covers it
      // mostly covers the face's others too, which the next round finds if not. Every spot at
      // once cost the bunny 260 points and 220 patches at 1e-3; one per face 74 and 35.
      // A face that still holds a spot after a point was added on it (the balls that cover
      // the points there come out smaller than the face: E below the sampling in this region)
      // gets a face patch instead of another point (bunny at 1e-4: 568 spots were left after
      // the fill rounds, each round's repair opening new ones).
      std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> one, again;
      hole_tried_.resize(faces_->mesh->face_count(), 0);
      for (std::size_t k = 0; k < holes.size(); ++k)
        if (k == 0 || holes[k].first != holes[k - 1].first)
          (hole_tried_[holes[k].first] && face_prisms() ? again : one).push_back(holes[k]);
      for (const auto& h : one) hole_tried_[h.first] = 1;
      add_points(one);
      if (!again.empty()) {
        const std::size_t added = add_face_patches(again);
        log::debug("fit_slim: round {}: {} faces with spots left after a point joined them get patches of their own", round + 1, added);
        st_.hole_face_patches += added;
      }
      best = Verified{};  // other points: not comparable
      least_score = std::numeric_limits<double>::infinity();
    } else if (face_fill) {
      // Too many to join the points: each face with a spot gets its own face patch instead, its
      // plane clipped to its prism — the data itself, covering the whole face.
      const std::size_t added = add_face_patches(holes);
      if (few)
        log::debug("fit_slim: round {}: {} spots of the data's faces outside every ball; too late for points, {} faces get "
                   "patches of their own", round + 1, holes.size(), added);
      else
        log::info("fit_slim: round {}: {} spots of the data's faces lie outside every ball (balls smaller than the faces: "
                  "E below the data's sampling); {} faces get patches of their own", round + 1, holes.size(), added);
      st_.hole_face_patches += added;
    } else if (!few && round == 0) {
      log::info("fit_slim: {} spots of the data's faces lie outside every ball (balls smaller than the faces: E below "
                "the data's sampling); left as they are", holes.size());
    }
    if (view_fill) {
      // Faces inside the balls that a view still sees through: their own face patches (the
      // data there), as for the many spots above; with view_balls, a face seen through for the
      // first time gets a regular ball at its centroid instead, unless that ball would not
      // reach across the face.
      if (opt_.view_balls) {
        view_tried_.resize(faces_->mesh->face_count(), 0);
        std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> fresh, again;
        for (const auto& s : seen) (view_tried_[s.first] ? again : fresh).push_back(s);
        for (const auto& s : fresh) view_tried_[s.first] = 1;
        const std::size_t balls = add_view_balls(fresh, again);
        log::debug("fit_slim: round {}: {} faces seen through for the first time get {} balls at their centroids", round + 1,
                   fresh.size(), balls);
        st_.view_balls += balls;
        std::sort(again.begin(), again.end(), by_point_then_spot);
        seen.swap(again);
      }
      const std::size_t added = add_face_patches(seen);
      log::debug("fit_slim: round {}: {} faces seen through from some view get patches of their own", round + 1, added);
      st_.view_face_patches += added;
    }
    if (gap_fill) {
      point_tried_.resize(P_.size(), 0);
      std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> fresh, discs;
      for (const auto& g : gaps) (point_tried_[g.first] || round + 2 >= budget ? discs : fresh).push_back(g);
      for (const auto& g : fresh) point_tried_[g.first] = 1;
      const std::size_t balls = fresh.empty() ? 0 : add_point_balls(fresh, discs);
      const std::size_t patches = add_disc_patches(discs, see_point_holes_);
      log::debug("fit_slim: round {}: {} points with a hole get their balls, {} disc patches", round + 1, balls, patches);
      st_.point_hole_balls += balls;
      st_.disc_patches += patches;
      if (!fresh.empty()) ++fill_rounds;
    }
    if (!relaxed.empty()) {
      relax_clips(relaxed);
      log::debug("fit_slim: round {}: {} slit samples at creases; {} clipped patches' planes moved across them", round + 1,
                 st_.crease_gaps, relaxed.size());
    }
    ++st_.repair_rounds;
    log::debug("fit_slim: round {}: fills {:.2f} s", round + 1, seconds_since(t_fill));
    log::debug("fit_slim: repair round {}: {} points beyond E, {} surface samples beyond {}E, {} face spots outside every "
               "ball (failures {:.3g})", round + 1, st_.blend_failures, st_.surface_failures, opt_.surface_factor, st_.face_holes, score);
    // The late round's face patches are verified on the model as it is: a repair there opens
    // new spots that no later round may fill (bunny at 1e-4: 219 → 946).
    const auto t_repair = Clock::now();
    if (!(late && face_fill)) repair(at_fault);
    prune();
    build_model();
    log::debug("fit_slim: round {}: repair {:.2f} s", round + 1, seconds_since(t_repair));
  }
}

void SlimFitter::repair(const std::vector<std::uint8_t>& at_fault) {
  std::vector<std::uint32_t> keep;
  for (std::size_t k = 0; k < chosen_.size(); ++k) {
    const auto b = chosen_[k];
    if (k >= at_fault.size() || !at_fault[k] || balls_[b].R <= 0) {  // new since verified (add_face_patches)
      keep.push_back(b);
      continue;
    }
    chosen_flag_[b] = 0;
    const double f = k < shrink_.size() ? shrink_[k] : opt_.shrink_step;
    if (balls_[b].disc) {
      // A disc patch whose sheet runs off the data (a tip more curved than its spacing):
      // shrunk by the culprit's factor, down to a fifth of the disc it was made for; its point
      // is remembered, so the hole it leaves gets no full disc patch back.
      disc_shrunk_[balls_[b].centre] = 1;
      if (const double R = f * balls_[b].R; R >= 0.2 * disc_patch_radius(balls_[b].centre)) {
        Ball s = balls_[b];
        s.g.A *= R / s.R;  // the bent disc's term is −½R·K in the ball's units: the same bend at the new R
        s.R = R;
        balls_.push_back(std::move(s));
        std::vector<std::uint32_t> cov = covers_[b];
        grow_candidate_arrays();
        covers_.back() = std::move(cov);
        chosen_flag_.back() = 1;
        pinned_.back() = 1;
        keep.push_back(std::uint32_t(balls_.size() - 1));
      }
      // No candidate any more: the greedy cover took the dropped disc back for its point, round
      // after round (bun000 at 1e-4 ended 3.8E off its data at a rim with it).
      covers_[b].clear();
      continue;
    }
    cap_[balls_[b].centre] = std::min(cap_[balls_[b].centre], f * balls_[b].R);
  }
  chosen_.swap(keep);
  std::fill(covered_.begin(), covered_.end(), 0);
  uncovered_ = P_.size();
  for (auto b : chosen_)
    for (auto p : covers_[b])
      if (!covered_[p]) covered_[p] = 1, --uncovered_;
  // Centres of culprits whose points are now uncovered come back first, capped.
  std::vector<std::uint32_t> again;
  std::vector<double> caps;
  for (std::size_t i = 0; i < P_.size(); ++i)
    if (std::isfinite(cap_[i]) && !covered_[i]) again.push_back(std::uint32_t(i)), caps.push_back(cap_[i]);
  const std::size_t from = balls_.size();
  evaluate(again, &caps);
  for (std::size_t b = from; b < balls_.size(); ++b) cap_[balls_[b].centre] = std::min(cap_[balls_[b].centre], balls_[b].R);
  // Candidates larger than their centre's cap retire, so re-covering cannot regrow them.
  chosen_flag_.resize(balls_.size(), 0);
  for (std::size_t b = 0; b < from; ++b)
    if (!chosen_flag_[b] && balls_[b].R > cap_[balls_[b].centre]) covers_[b].clear();
  while (!heap_.empty()) heap_.pop();
  cover(&cap_);
  // A point still beyond E although covered (a tip, a spike: it sits near the rims of the balls
  // that cover it, where their weights vanish and farther patches dominate the blend) gets a
  // ball of its own, centred on it and kept through pruning.
  std::vector<std::uint32_t> stubborn;
  std::vector<double> stubborn_caps;
  for (std::size_t i = 0; i < P_.size(); ++i)
    if (!(point_error_[i] <= E_) && covered_[i]) stubborn.push_back(std::uint32_t(i)), stubborn_caps.push_back(cap_[i]);
  if (stubborn.empty() || stubborn.size() > P_.size() / 100) return;
  const std::size_t first = balls_.size();
  // Centred on the point itself: a face patch would centre on its face's centroid instead.
  const FaceSet* faces = std::exchange(fitter_->faces, nullptr);
  new_candidates(stubborn, stubborn_caps);
  fitter_->faces = faces;
  for (std::size_t b = first; b < balls_.size(); ++b) {
    cap_[balls_[b].centre] = std::min(cap_[balls_[b].centre], balls_[b].R);
    pinned_[b] = 1;
    take(std::uint32_t(b));
  }
}

void SlimFitter::finish() {
  double sum_sq = 0;
  std::size_t finite = 0;
  st_.max_blend = 0;
  for (const double e : point_error_) {
    st_.max_blend = std::max(st_.max_blend, e);
    if (std::isfinite(e)) sum_sq += e * e, ++finite;
  }
  st_.rms_blend = finite ? std::sqrt(sum_sq / double(finite)) : 0;
  st_.surface_samples = surface_error_.size();
  if (!surface_error_.empty()) {
    std::vector<double> e = surface_error_;
    const std::size_t k = std::min(e.size() - 1, static_cast<std::size_t>(0.999 * double(e.size() - 1)));
    std::nth_element(e.begin(), e.begin() + static_cast<std::ptrdiff_t>(k), e.end());
    st_.surface_p999 = e[k];
    st_.surface_max = *std::max_element(e.begin(), e.end());
  }
  double sum_sq_taubin = 0;
  std::size_t in_balls = 0;
  for (auto b : chosen_) {
    st_.max_taubin = std::max(st_.max_taubin, balls_[b].max_taubin);
    sum_sq_taubin += balls_[b].sum_sq_taubin;
    in_balls += balls_[b].count;
    st_.height_patches += balls_[b].is_height;
    st_.unbounded_patches += !balls_[b].is_bounded;
    st_.clipped_patches += !balls_[b].clips.empty();
  }
  st_.rms_taubin = in_balls ? std::sqrt(sum_sq_taubin / double(in_balls)) : 0;
  if (faces_) {
    const double fans = double(std::max<std::size_t>(1, face_triangles_));
    st_.hole_share = double(st_.view_holes) / fans + double(st_.face_holes) / (fans * double(1u << (2 * opt_.face_hole_depth)));
  } else if (!surface_) {
    st_.hole_share = double(st_.seen_point_holes + st_.crease_gaps) / double(std::max<std::size_t>(1, P_.size()));
  }
  st_.holes_exceeded = st_.hole_share > opt_.max_hole_share;
  st_.candidates = balls_.size();
  result_.data = data_;
  result_.surface_error_per_patch.assign(chosen_.size(), 0.0);
  for (std::size_t k = 0; k < chosen_.size() && chosen_[k] < patch_errors_.size(); ++k)
    for (const double e : patch_errors_[chosen_[k]]) result_.surface_error_per_patch[k] = std::max(result_.surface_error_per_patch[k], e);
  st_.settled_candidates = std::size_t(std::count_if(balls_.begin(), balls_.end(), [](const Ball& b) { return b.settled; }));
  st_.patches = chosen_.size();
  st_.clips_relaxed = std::size_t(std::count_if(chosen_.begin(), chosen_.end(), [&](std::uint32_t b) { return balls_[b].relaxed; }));

  auto& md = result_.model.metadata;
  auto num = [](double v) { return fmt::format("{:.6g}", v); };
  md["producer"] = "quadrix fit";
  md["max_error"] = num(E_ / st_.diagonal);
  md["max_error_abs"] = num(E_);
  md["surface_bound_abs"] = num(opt_.surface_factor * E_);
  md["surface_reference"] = surface_ ? "mesh" : "points";
  md["diagonal"] = num(st_.diagonal);
  md["normals"] = st_.normals_estimated ? "estimated" : "given";
  md["points"] = std::to_string(st_.points);
  if (st_.hole_points > 0) md["hole_points"] = std::to_string(st_.hole_points);
  if (st_.hole_face_patches > 0) md["hole_face_patches"] = std::to_string(st_.hole_face_patches);
  if (st_.view_face_patches > 0) md["view_face_patches"] = std::to_string(st_.view_face_patches);
  if (st_.view_balls > 0) md["view_balls"] = std::to_string(st_.view_balls);
  if (can_add_points_ && opt_.cover_face_holes && face_prisms()) md["view_holes"] = std::to_string(st_.view_holes);
  if (can_add_points_ && opt_.cover_face_holes) md["face_holes"] = std::to_string(st_.face_holes);
  if (!surface_ && opt_.cover_point_holes) {
    md["point_holes"] = std::to_string(st_.point_holes);
    md["disc_patches"] = std::to_string(st_.disc_patches);
    md["clips_relaxed"] = std::to_string(st_.clips_relaxed);
    md["seen_point_holes"] = std::to_string(st_.seen_point_holes);
  }
  md["hole_share"] = num(st_.hole_share);
  md["patches"] = std::to_string(st_.patches);
  md["candidates"] = std::to_string(st_.candidates);
  md["subsample_levels"] = std::to_string(st_.subsample_levels);
  md["height_patches"] = std::to_string(st_.height_patches);
  if (opt_.sharp) md["clipped_patches"] = std::to_string(st_.clipped_patches);
  md["measured_max_error"] = num(st_.max_blend);
  md["measured_rms_error"] = num(st_.rms_blend);
  md["measured_failures"] = std::to_string(st_.blend_failures);
  md["measured_surface_max"] = num(st_.surface_max);
  md["measured_surface_p999"] = num(st_.surface_p999);
  md["measured_surface_failures"] = std::to_string(st_.surface_failures);
  md["taubin_max_error"] = num(st_.max_taubin);
  md["taubin_rms_error"] = num(st_.rms_taubin);
  md["time_normals_s"] = num(st_.time_normals);
  md["time_candidates_s"] = num(st_.time_candidates);
  md["time_cover_s"] = num(st_.time_cover);
  md["time_verify_s"] = num(st_.time_verify);
  md["time_total_s"] = num(st_.time_total);
  log::info("fit_slim: {} points, {} patches ({} candidates, {} checked on the surface side), E = {:.3g}: points max {:.3g} ({} beyond E), "
            "surface max {:.3g} p99.9 {:.3g} ({} samples beyond {}E), {:.2f} s",
            st_.points, st_.patches, st_.candidates, st_.settled_candidates, E_, st_.max_blend, st_.blend_failures, st_.surface_max,
            st_.surface_p999, st_.surface_failures, opt_.surface_factor, st_.time_total);
  if (st_.face_holes > 0)
    log::info("fit_slim: {} spots of the data's faces outside every ball (holes between covered points; {} points "
              "were added on such spots)", st_.face_holes, st_.hole_points);
}

}  // namespace fit_detail

using fit_detail::FaceSet;
using fit_detail::SlimFitter;


SlimFitResult fit_slim(const PointCloud& cloud, const SlimFitOptions& options) {
  // Fitted in Morton order: the fit's loops over the points then query the indices and the
  // data's discs where the last query did (1M points sampled from the armadillo in random order,
  // fitted at 1e-3: 15.0 s unsorted and 11.5 s sorted here, both over a Morton-ordered kd-tree
  // since dropped; 11.9 s now, in bench fit). Validated first, so that errors name the
  // caller's indices. Of the result, only `data` (the points' tangent discs) is indexed by point,
  // in the sorted order; the model and the stats are not. Colours are not copied: the fitter
  // does not read them, and the patches take theirs from the caller's cloud.
  // Points sharing a Morton cell go by their coordinates (core/morton.h), not by their rows, so
  // the same points in any order give the same model (exact copies of a position aside).
  validate(cloud, options);
  const std::vector<std::uint32_t> order = morton_order(cloud.points);
  PointCloud sorted;
  sorted.points.reserve(order.size());
  for (const std::uint32_t i : order) {
    sorted.points.push_back(cloud.points[i]);
    if (cloud.has_normals()) sorted.normals.push_back(cloud.normals[i]);
  }
  SlimFitResult r = SlimFitter(std::move(sorted), options).run();
  set_patch_colours(r.model, cloud);
  return r;
}

SlimFitResult fit_slim(const PointCloud& cloud, const PolygonMesh& mesh, const SlimFitOptions& options) {
  // Faces of more than three corners are fitted as their fans of triangles, the surface the data
  // side measures against (fit/data_surface.h): a face patch is a plane, and a non-planar quad's
  // centroid lies off it (spot_quadrangulated at 1e-3 looped in the covering; at 1e-4, 540
  // points were left beyond E).
  std::optional<PolygonMesh> fanned;
  if (!mesh.is_triangles()) fanned = mesh.fanned();
  const PolygonMesh& surface = fanned ? *fanned : mesh;
  if (!options.cover_faces || !cloud.has_normals()) {
    SlimFitResult r = SlimFitter(cloud, options, &surface).run();
    set_patch_colours(r.model, cloud);
    return r;
  }
  // Each face's centroid (and a lattice on faces much larger than their neighbours, core/io/io.h
  // face_samples) joins the points with the face's normal, so coverage and the points side hold
  // between the vertices too.
  PointCloud all = cloud;
  all.colours.clear();  // the face samples have none; the patches take the cloud's at the end
  std::vector<std::uint32_t> face_of(cloud.points.size(), FaceSet::kNone);
  // The lattice on large faces only when E is finer than the mesh's spacing: coarser balls span
  // many faces, held by their vertices and centroids (bunny at 1e-2, where E is 1.7 median
  // edges: a lattice point on a filled scan hole stayed 14E off through every repair round).
  Box3 box;
  for (const auto& p : cloud.points) box.extend(p);
  const double E = options.max_error_is_absolute ? options.max_error : options.max_error * box.diagonal();
  const PointCloud faces = face_samples(surface, 2.0, &face_of, E);
  all.points.insert(all.points.end(), faces.points.begin(), faces.points.end());
  all.normals.insert(all.normals.end(), faces.normals.begin(), faces.normals.end());
  const std::size_t added = all.points.size() - cloud.points.size();
  SlimFitResult r = SlimFitter(std::move(all), options, &surface, std::move(face_of)).run();
  r.model.metadata["face_samples"] = std::to_string(added);
  set_patch_colours(r.model, cloud);
  return r;
}

}  // namespace quadrix
