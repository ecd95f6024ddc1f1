#pragma once
/// Internal to fit/ (not an API): the SLIM fit as a class of named steps behind fit/slim_fit.h's
/// fit_slim — candidates, covering, pruning, then rounds of verification on both sides of the
/// contract and repair of the patches at fault. The steps are defined in fit/slim_fit.cpp; the
/// checks (points, drawn surface, face and view holes) and what they add in fit/slim_fit_checks.cpp.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <queue>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/reference.h"
#include "fit/ball_fitter.h"

namespace quadrix::fit_detail {

/// The spectral norm of a patch's quadratic part: |dᵀAd| for any unit d, local units.
double patch_bend(const SlimPatch& patch);
/// A patch seen from a spot x: x in local units, its distance from the centre, and (inside the
/// ball) g's gradient and |g| there.
struct PatchAtSpot {
  Eigen::Vector3d u, g = Eigen::Vector3d::Zero();
  double r = 0, g0 = 0;
  bool inside = false;
};
PatchAtSpot patch_at_spot(const SlimPatch& patch, const Eigen::Vector3d& x);
/// Whether every ray through the spot along a direction d with −∇g·d ≥ A1 (local units) meets
/// the patch's zero set front-facing, inside its ball and clip planes, within `reach` (world
/// units) of the spot — proven from g's exact quadratic along the ray (bend = patch_bend(patch)):
/// along u + σd, g = g0 + a1·σ + a2·σ² with −a1 ≥ A1 and |a2| ≤ bend, so with A1 > 0 g falls
/// strictly through zero within |σ| ≤ ρ, the smaller root of bend·ρ² − A1·ρ + |g0| (g' < 0
/// there): one front-facing crossing, if the ball and the planes hold ρ of room around the spot
/// and ρR ≤ reach.
bool meets_views(const SlimPatch& patch, double bend, const PatchAtSpot& at, double A1, double reach);
/// Whether every view of the spot within `widest` (radians) of −n meets the patch so
/// (view_holes' shortcut): meets_views with A1 = cos(widest)·(∇g·n) − sin(widest)·|∇g − (∇g·n)n|.
bool meets_every_view(const SlimPatch& patch, double bend, const PatchAtSpot& at, const Eigen::Vector3d& n, double widest,
                      double reach);
bool meets_every_view(const SlimPatch& patch, double bend, const Eigen::Vector3d& x, const Eigen::Vector3d& n, double widest,
                      double reach);

/// Orders spots by point (or face), then by position: parallel loops' results in an order that
/// does not depend on the threads' scheduling.
bool by_point_then_spot(const std::pair<std::uint32_t, Eigen::Vector3d>& x, const std::pair<std::uint32_t, Eigen::Vector3d>& y);

class SlimFitter {
public:
  SlimFitter(const PointCloud& cloud, const SlimFitOptions& options, const PolygonMesh* surface)
      : cloud_(cloud), opt_(options), P_(cloud.points), surface_(surface) {}
  // Owning its points, without a surface (fit_slim: the cloud in Morton order).
  SlimFitter(PointCloud&& cloud, const SlimFitOptions& options)
      : owned_(std::move(cloud)), cloud_(owned_), opt_(options), P_(owned_.points), surface_(nullptr) {}
  // Owning its points (a mesh's vertices and face samples), the fitter may add points where the
  // faces between them are left uncovered (SlimFitOptions::cover_face_holes).
  SlimFitter(PointCloud&& cloud, const SlimFitOptions& options, const PolygonMesh* surface, std::vector<std::uint32_t> face_of)
      : owned_(std::move(cloud)), cloud_(owned_), opt_(options), P_(owned_.points), surface_(surface),
        face_of_(std::move(face_of)), can_add_points_(true) {}

  /// The whole fit: set-up, candidates, covering, pruning, verification and repair, the model.
  SlimFitResult run();

private:
  struct Changed;  // below: the balls a repair changed

  // Set-up and candidates (slim_fit.cpp).
  void setup();
  void warn_below_sampling(const std::string& what) const;
  void warn_below_noise();  // measures SlimFitStats::noise
  void make_fitter();
  void evaluate(const std::vector<std::uint32_t>& centres, const std::vector<double>* caps);
  void cover_of(std::size_t b, std::vector<Neighbour>& nb);
  void settle(const std::vector<std::uint32_t>& ids);
  // The per-candidate arrays grown to every ball (new ones: not chosen, not pinned, unverified).
  void grow_candidate_arrays();
  // Candidates evaluated at these centres (radius capped) and settled; their ids.
  std::vector<std::uint32_t> new_candidates(const std::vector<std::uint32_t>& centres, const std::vector<double>& caps);
  void initial_candidates();
  // Covering and pruning (slim_fit.cpp).
  std::size_t gain(std::uint32_t b) const;
  void take(std::uint32_t b);
  void run_greedy(std::size_t from);
  void cover(const std::vector<double>* cap_of_point);
  void prune();
  void build_model();
  SlimBlendOptions blend() const;
  // Verification rounds and repair (slim_fit.cpp).
  void verify_and_repair();
  void repair(const std::vector<std::uint8_t>& at_fault);
  void finish();

  // The checks and what fills what they find (slim_fit_checks.cpp).
  std::size_t verify_points(const ReferenceScene& scene, const PointIndex& centres, const std::vector<std::uint8_t>& stale,
                            std::vector<std::uint8_t>& at_fault);
  void collect_surface_errors();
  std::size_t verify_surface(const ReferenceScene& scene, const std::vector<std::uint8_t>& stale,
                             std::vector<std::uint8_t>& at_fault);
  // steep: also record the spots only a steep sheet holds (steep_spots_) for view_holes.
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> face_holes(const PointIndex& index, const Changed* changed,
                                                                    bool steep = false);
  // Whether chosen patch k holds x: inside its ball and clip planes, its zero set within band;
  // given the data's unit normal n at x, also no steeper there than 75 degrees to it (beside
  // a crease the other face's sheet passes within the band, and its planes keep the strip along
  // the edge, but a ray that meets this face there may pass beside that sheet: view_holes asks).
  bool holds(std::uint32_t k, const Eigen::Vector3d& x, double band, const Eigen::Vector3d* n = nullptr) const;
  // The triangle pqs against the patches `near`: covered when one holds its three corners (ball,
  // planes and band are convex), else split in four down to max_depth; a smallest piece no one
  // patch holds whole gives emit() its centroid or first corner that none holds. n: the
  // triangle's unit normal, for holds() (the angle test is not convex: a piece one patch holds at
  // its corners is taken as held, as for the band). budget: pieces left to look at (none: no limit).
  template <class Emit>
  void uncovered(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& s,
                 const std::vector<std::uint32_t>& near, double band, int depth, int max_depth, Emit&& emit,
                 const Eigen::Vector3d* n = nullptr, std::size_t* budget = nullptr) const;
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> point_holes(const PointIndex& index, const Changed* changed);
  // How deep in a ball a point counts as covered (SlimFitOptions::cover_fraction).
  double cover_fraction() const {
    return opt_.cover_fraction.value_or(surface_ ? SlimFitOptions::kCoverFractionMesh : SlimFitOptions::kCoverFractionPoints);
  }
  // Point i's coverage disc radius (point_hole_factor × its spacing) and its disc patch's.
  double coverage_radius(std::size_t i) const { return opt_.point_hole_factor * data_->spacing(i); }
  double disc_patch_radius(std::size_t i) const { return opt_.disc_patch_reach * opt_.point_hole_factor * data_->spacing(i); }
  std::size_t add_point_balls(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots,
                              std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& far);
  /// on_data: only where the plane stays within 2E of the data's surface across its ball (the
  /// holes below the fill band: planes off a curved cloud's surface, repaired round after round,
  /// kept radar.xyz at 1e-3 from ever ending within its bound).
  std::size_t add_disc_patches(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots, bool on_data = false);
  /// Of points' coverage holes, those a view along the point's normal sees (judge_ray).
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> seen_point_holes(
      const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots, const ReferenceScene& scene) const;
  /// Six spots rho out from point i in its tangent plane.
  std::array<Eigen::Vector3d, 6> tangent_ring(std::size_t i, double rho) const;
  /// Whether one patch holds p and the whole ring within band: the one that last did (`last`,
  /// updated), else the patches whose balls may reach the ring, nearest centres first (left in
  /// `near` when none does; `nb` is scratch).
  bool held_whole(const Eigen::Vector3d& p, const std::array<Eigen::Vector3d, 6>& ring, double rho, double band,
                  const PointIndex& centres, double max_radius, std::optional<std::uint32_t>& last,
                  std::vector<Neighbour>& nb, std::vector<std::uint32_t>& near) const;
  /// Among point i's crease_neighbours nearest: kOnFace where a point lies on a face (on_face: a
  /// face's plane found at a crease, DataSurface::faced, or with given normals a planar point),
  /// and kAtEdge too where points of two such faces do,
  /// their planes turned more than acos(crease_cos) from each other: an edge or corner is there
  /// (nb: scratch).
  static constexpr std::uint8_t kOnFace = 1, kAtEdge = 2;
  std::uint8_t beside_crease(std::size_t i, std::vector<Neighbour>& nb) const;
  Ray spot_ray(std::size_t i, const Eigen::Vector3d& x) const;
  std::optional<Eigen::Vector3d> seen_hole(const Ray& ray, const ReferenceScene& scene, const TraceOptions& trace) const;
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> seen_holes(
      const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots, const PointIndex& centres,
      const ReferenceScene& scene) const;
  /// Holes a view sees between a point and its neighbours (one spot per point, at most).
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> holes_between_points(const PointIndex& centres,
                                                                            const ReferenceScene& scene) const;
  // Slits at creases: a cut edge of a patch clipped at a crease (try_sharp, sheets within 120°,
  // not at fault) that no other patch holds, where the blend shows nothing within 2E just past
  // it along the sheet's normal, is followed across the plane along the patch's own zero set to
  // where another patch holds it (its zero set within E, inside its planes); the plane moves there
  // (E/2 past) if its new cut edge stays on the data or held. Per such patch (index in chosen_),
  // its moved plane; `open` gets the slit samples found (crease gaps).
  std::vector<std::pair<std::size_t, ClipPlanes>> crease_slits(const PointIndex& centres, const ReferenceScene& scene,
                                                               const std::vector<std::uint8_t>& at_fault, std::size_t& open) const;
  // Each such patch's ball replaced in chosen_ by a copy with the moved planes (pinned).
  void relax_clips(const std::vector<std::pair<std::size_t, ClipPlanes>>& relaxed);
  // Whether candidate b's centre lies within half the radius of a ball taken in this fill; b taken
  // (its centre's cap lowered to it, kept through pruning) and added to them.
  bool near_taken(std::uint32_t b, const std::vector<std::uint32_t>& taken) const;
  void take_pinned(std::uint32_t b, std::vector<std::uint32_t>& taken);
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> view_holes(const ReferenceScene& scene, const PointIndex& index,
                                                                    const Changed* changed);
  // Whether the view along d sees the data at x away from its silhouette: the main ray, then the six beside it.
  bool data_front(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double L) const;
  /// r: how far to the side the six rays run (≤ 0: surface_factor·E).
  bool data_around(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double L, double r = 0) const;
  void balls_near_triangle(const PointIndex& index, double max_radius, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c, std::vector<Neighbour>& nb, std::vector<std::uint32_t>& near) const;
  std::size_t add_face_patches(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots);
  std::size_t add_view_balls(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots,
                             std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& small);
  void add_points(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots);
  bool face_prisms() const { return faces_ && opt_.face_patches && opt_.face_prisms; }
  // The triangle pqs split at its edges' midpoints: visit(corner piece ×3, middle piece).
  template <class Visit>
  static void split_in_four(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& s, Visit&& visit) {
    const Eigen::Vector3d pq = 0.5 * (p + q), qs = 0.5 * (q + s), sp = 0.5 * (s + p);
    visit(p, pq, sp);
    visit(pq, q, qs);
    visit(sp, qs, s);
    visit(pq, qs, sp);
  }

  // What a repair changed: the balls that left the model and those that joined it. Only the
  // probes whose blend looked inside one of them need tracing again.
  struct Changed {
    std::vector<Eigen::Vector3d> centres;
    std::vector<double> radii;
    double max_radius = 0;
    std::unique_ptr<PointIndex> index;

    // Whether any changed ball meets the ball (c, r).
    bool near_ball(const Eigen::Vector3d& c, double r, std::vector<Neighbour>& near) const {
      if (centres.empty()) return false;
      index->radius(c, r + max_radius, near);
      for (const auto& [k, d2] : near)
        if (d2 <= (r + radii[k]) * (r + radii[k])) return true;
      return false;
    }

    // Whether any changed ball meets the segment o + t·d, t ∈ [0, length] (d unit).
    bool meets(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double length, std::vector<Neighbour>& near) const {
      if (centres.empty()) return false;
      if (!std::isfinite(length)) return true;
      index->radius(o + 0.5 * length * d, 0.5 * length + max_radius, near);
      for (const auto& [c, d2] : near) {
        const Eigen::Vector3d v = centres[c] - o;
        const double t = std::clamp(v.dot(d), 0.0, length);
        if ((v - t * d).squaredNorm() <= radii[c] * radii[c] * (1.0 + 1e-9)) return true;
      }
      return false;
    }
  };
  Changed changed_since(const std::vector<std::uint32_t>& before) const;

  // A verified model: its balls and what verification measured on it.
  struct Verified {
    std::vector<std::uint32_t> chosen;
    std::vector<double> point_error;
    std::vector<std::vector<double>> patch_errors;  // per chosen ball
    std::size_t blend_failures = 0, surface_failures = 0, face_holes = 0, view_holes = 0;
    int round = -1;  // -1: none
    double score = 0;  // failures() of that model
    double excess = 0;  // breach_excess() of that model
    std::size_t point_holes = 0;
    std::size_t crease_gaps = 0;
    std::size_t seen_point_holes = 0;
    bool point_holes_fresh = false;  // point_holes was counted on this model
  };
  double failures() const;
  double breach_excess() const;
  Verified snapshot(int round, double score, double excess) const;
  void restore(Verified&& v);

  static constexpr double kInf = std::numeric_limits<double>::infinity();
  // holds(): the cosine of the steepest a patch may stand to the data's surface where it holds a
  // spot of it (75 degrees); face_holes: at most this many such spots a fan triangle.
  static constexpr double kHoldSteepestCos = 0.25881904510252074;
  static constexpr std::size_t kSteepSpots = 256, kSteepPieces = 4096;
  PointCloud owned_;  // the points, when the fitter owns them (may grow: add_points)
  const PointCloud& cloud_;
  const SlimFitOptions& opt_;
  const std::vector<Eigen::Vector3d>& P_;
  const PolygonMesh* surface_;
  std::vector<Eigen::Vector3d> N_;
  double E_ = 0;
  SlimFitResult result_;
  SlimFitStats& st_ = result_.stats;
  std::unique_ptr<PointIndex> index_;
  std::vector<std::uint8_t> near_crease_;  // per point: beside_crease's flags (empty: no point on a face)
  // Given normals: the points on a face are the planar ones (DataSurface::planar), not those
  // crease points gave a face's plane (DataSurface::faced, estimated normals only).
  bool planar_faces_ = false;
  bool on_face(std::size_t j) const { return planar_faces_ ? data_->planar(j) : data_->faced(j); }
  std::size_t fillable_holes_ = 0;         // of st_.point_holes, those the fill band fills (failures)
  bool crease_band_ = false;               // the holes beside edges and corners alone put the fit in the band
  std::unique_ptr<Subsamples> subsamples_;
  std::shared_ptr<DataSurface> data_;
  std::unique_ptr<BallFitter> fitter_;
  std::vector<std::uint32_t> order_;                 // the points in random order
  std::mutex debug_mutex_;                           // -vv: the first failing surface samples
  std::size_t debug_shown_ = 0;
  std::vector<Ball> balls_;                          // evaluated candidates
  std::vector<std::vector<std::uint32_t>> covers_;   // points each candidate covers
  std::vector<Eigen::Vector3d> pilot_centres_;
  std::vector<double> pilot_R_;
  std::unique_ptr<PointIndex> pilot_index_;
  std::vector<std::uint8_t> covered_, chosen_flag_;
  std::vector<std::uint8_t> pinned_;                 // per candidate: kept through pruning (repair)
  std::size_t uncovered_ = 0;
  std::vector<std::uint32_t> chosen_;
  std::priority_queue<std::pair<std::size_t, std::uint32_t>> heap_;  // gain, candidate
  std::vector<double> cap_;                           // radius cap per centre point (repair)
  std::vector<double> point_error_, surface_error_;
  std::vector<double> shrink_;                        // per chosen patch: radius factor on repair
  std::vector<double> patch_excess_;                 // per candidate: zero_set_excess, −1 unknown
  std::vector<std::vector<double>> patch_errors_;    // per candidate: its last surface samples' distances
  std::vector<double> patch_reach_;                  // per candidate: how far its probes' blends looked
  std::vector<std::vector<SlimSurfaceSample>> rim_off_;  // per candidate: its rim samples off the data (verify_surface)
  std::vector<std::uint8_t> rim_known_;               // per candidate: rim_off_ found
  std::vector<double> point_reach_;                  // per point: how far its probe's blend looked
  std::vector<std::uint8_t> other_direction_;         // per point: measured along its neighbourhood's normal
  std::vector<double> probe_height_;                  // per point (fit/evaluate.h probe_heights)
  std::vector<std::uint32_t> face_of_;                // per point: its face (face samples), until setup
  std::unique_ptr<FaceSet> faces_;                    // face patches
  bool can_add_points_ = false;                       // owned_ holds the points
  std::size_t face_triangles_ = 0;                    // fan triangles of the faces with a surface (face_holes' pieces / 4^depth)
  std::vector<std::uint8_t> face_covered_;            // per face: inside the union of the balls at the last check
  // Per face: spots no patch within 75 degrees of the face holds, though a steeper one does
  // (beside a crease: the other face's sheet), found by face_holes; view_holes asks its views of
  // them.
  std::vector<std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>> steep_spots_;  // (fan triangle, spot)
  std::vector<std::uint8_t> view_clear_;              // per face: every view ray met a patch at the last check
  std::vector<std::vector<std::uint8_t>> view_data_;  // per face: data_front/data_around's answers so far (view_holes)
  std::vector<std::uint8_t> point_covered_;           // per point: its coverage disc held at the last check (point_holes)
  std::vector<std::uint8_t> point_tried_;             // per point: a ball was added on its hole once
  std::vector<std::uint8_t> corner_mask_;             // per point: coverage-disc corners with its sheet beyond (point_holes)
  std::vector<std::uint8_t> corner_known_;            // per point: corner_mask_ computed
  std::vector<std::uint32_t> point_order_;            // the points in Morton order (point_holes)
  bool fill_point_holes_ = false;                     // point_holes are filled (not E far below the sampling)
  bool see_point_holes_ = false;                      // below the fill band: those a view sees are filled
  bool seen_counted_late_ = false;                    // too many to fill: counted on the model returned
  bool point_holes_fresh_ = false;                    // st_.point_holes was counted on the model just verified
  std::vector<std::uint8_t> disc_shrunk_;             // per point: the repair shrank its disc patch (its hole stays)
  std::vector<std::uint8_t> hole_tried_;              // per face: a spot on it joined the points (add_points)
  std::vector<std::uint8_t> view_tried_;              // per face: seen through before (view_balls)
  std::vector<std::uint8_t> face_patched_;            // per face: holds a face patch of add_face_patches
};

}  // namespace quadrix::fit_detail
