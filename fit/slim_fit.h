#pragma once
/// SLIM fitting (Ohtake, Belyaev, Alexa 2005; DESIGN §2, issue 4): sphere-bounded local quadrics
/// fitted to an oriented point cloud so that every point lies within a bound E of the blended
/// surface the renderer shows.
///
/// Deviations from the letter of issue 4, with the measurements behind them (bunny vertices with
/// mesh normals, E = 1e-3 of the diagonal, every point within E of the blended surface each time):
/// - Covering within 0.9·R, not ½R (cover_fraction). Each ball's quadric is checked against every
///   point of its whole ball and the blend is a convex combination of the patches' hits, so a point
///   near the rim is as well served as one near the centre; the final verification against the
///   blended surface (and repair) is the safety net. With the fit as it was (floor 0.05, no
///   reweighting): ½R 5,497 patches · 0.7R 2,863 · 0.8R 2,146 · 0.9R 1,672 · 0.95R 1,521; at 1.0·R
///   a point on a ball's very rim got no usable sample and the bound broke (max 7.3e-2). With the
///   fit below: ½R 3,706, 0.9R 1,107. Balls that never reached E keep ½R.
/// - The fit weight is the SLIM weight w(r) plus a floor of 0.3 (was 0.05), and when a fit misses
///   E the weights are multiplied by (0.1 + (eᵢ/e_max)²) and the fit repeated up to twice (Lawson's
///   reweighting towards the minimax fit, as the bound is a maximum). At 0.9R: neither 1,582
///   patches, floor only 1,385, reweighting only 1,159, both 1,107 (+0.5 s of CPU for the refits).
///   Larger radii cost RMS: about 0.4·E instead of 0.18·E.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/mesh_io.h"
#include "core/model.h"
#include "core/points_io.h"

namespace quadrix {

struct SlimFitOptions {
  /// Error bound E, relative to the bounding-box diagonal of the points (absolute when
  /// max_error_is_absolute). Both the per-patch Taubin distance |g|/‖∇g‖ and the blended
  /// surface's distance along each point's normal are kept ≤ E.
  double max_error = 1e-3;
  bool max_error_is_absolute = false;
  /// μ: weight of the normal term ‖∇g(u) − n‖² against g(u)² in the local least squares
  /// (local coordinates u = (x − c)/R, so both terms are dimensionless).
  double normal_weight = 0.01;
  /// Fit weight of a point at r = ‖p − c‖/R: the SLIM weight w(r) plus this floor (rim points are
  /// checked against E too, so they must pull on the fit).
  double weight_floor = 0.3;
  /// When a ball's first fit misses E: up to this many refits with each fit point's weight
  /// multiplied by (0.1 + (eᵢ/e_max)²), eᵢ its Taubin distance (towards the minimax fit).
  int reweight_rounds = 2;
  /// Greedy covering: a point is covered by a ball when it lies within cover_fraction·R of the
  /// centre (issue 4 says ½R; see the file comment for why 0.9). The price of 0.9: neighbouring
  /// balls overlap only in their rims, so two patches crossing at a few degrees blend over a
  /// narrow band and the shading shows facets, and between the points of a cloud without faces
  /// the balls leave holes no check fills below a share of 5 % (point_hole_least). Unset: 0.9
  /// with a mesh (its faces' checks close the holes; the patch count is compared with its
  /// decimation), kCoverFractionPoints for points alone (kitten at 1e-3: 27 points' coverage discs
  /// not held instead of 141, the blended normals' p99 against the points' 10.0° instead of
  /// 13.9°, for 640 patches instead of 435; `fit --cover-fraction`).
  std::optional<double> cover_fraction;
  static constexpr double kCoverFractionMesh = 0.9, kCoverFractionPoints = 0.75;
  /// A ball needs at least this many points for a general quadric; sparser balls use the
  /// height-function fallback.
  std::size_t min_points = 12;
  /// Candidate centres: this fraction of the points (at least min_candidates, at most all),
  /// drawn at random; uncovered points become candidates later as needed.
  double candidate_fraction = 0.08;
  std::size_t min_candidates = 400;
  std::size_t max_candidates = 8000;
  /// Fewer when the pilots (below) cover many points each: candidates_per_patch times the number
  /// of balls the covering needs by their mean cover (a coarse E needs few large balls). Bunny
  /// mesh at E = 1e-2 (user CPU s, one run on a loaded machine): all 7,704 candidates 165 patches
  /// 12.2 s; ×16: 2,433 candidates 199 patches 4.9 s; ×8: 238 patches 3.3 s; ×4: 249 patches
  /// 2.1 s. At 1e-3 (task-clock s, one run each, lazy_surface_check on): ×12 8,192 candidates,
  /// 1,504 patches, 6.3 s; ×4 5,697, 1,574, 5.0 s; ×3 1,616 patches; ×2 3,660, 1,677, 4.9 s.
  /// The decimated mesh at that error has 5,086 triangles, so ×4 is 0.31× of it. Later (quiet,
  /// task-clock, verification's lone-patch lattice skipped where settle's was as fine): ×4 1,604
  /// patches 3.56–3.89 s, ×3 1,650 patches 3.06 s, ×2 1,695 patches 3.16 s (bunny 1e-3; the
  /// armadillo's 8,000-candidate cap binds at ×3 and ×4).
  double candidates_per_patch = 3.0;
  /// Support radius search: geometric growth by this factor from the min_points-th neighbour
  /// distance, then this many bisection steps (in log R).
  double radius_growth = 2.0;
  int bisection_steps = 3;
  /// The first pilot_candidates candidates search from scratch; every later one starts at the
  /// radius of the nearest pilot and grows or shrinks by warm_growth, then bisects
  /// warm_bisection_steps times (about a third fewer fits for the same precision).
  std::size_t pilot_candidates = 300;
  double warm_growth = 1.25;
  int warm_bisection_steps = 3;
  /// At most this many points of a ball enter its least squares (every point is still checked).
  std::size_t max_fit_points = 200;
  /// While searching R, at most this many points of a ball (evenly strided) are checked; the
  /// final verification against the blended surface checks every point and repairs. Clouds of
  /// more than 4 × 4 × max_check_points points also get nested random subsamples (n/4, n/16, …
  /// down to 4 × max_check_points), and a ball's points come from the coarsest one that holds
  /// max_check_points of them.
  std::size_t max_check_points = 3000;
  /// Probe height h for the blended-surface check, in units of E (rays start at p + h·n).
  double probe_factor = 4.0;
  /// Rounds of verification against the blended surface and repair of the patches at fault
  /// (the fit stops earlier when a round leaves nothing at fault, or after three rounds without
  /// improvement). 12: radar.xyz at 1e-3 (no normals) needs 7 to 10; with 6 it ended with 2
  /// surface samples beyond 2E. Fits that end within 6 rounds are the same.
  int repair_rounds = 12;
  /// The surface side of the contract: every point of the blended surface within
  /// surface_factor·E of the data (the points' tangent discs, fit/data_surface.h).
  bool check_surface = true;
  double surface_factor = 2.0;
  /// While fitting, each patch's own zero set inside its ball must stay within
  /// local_surface_factor·E of the data (sampled on a local_surface_grid² lattice per axis,
  /// core/slim.h sample_slim_patch); else its radius shrinks by shrink_step, up to shrink_steps times.
  double local_surface_factor = 1.5;
  int local_surface_grid = 6;
  int local_surface_depth = 2;  ///< refinement levels of that lattice (fit/data_surface.h)
  double shrink_step = 0.75;
  /// Open boundaries: when a ball's points have their tangential centroid farther than
  /// boundary_offset·R from its centre and its zero set runs past the data, the patch gets a
  /// clip plane across the sheet just beyond its outermost point.
  double boundary_offset = 0.15;
  int shrink_steps = 16;
  /// Check that surface side (and shrink) only for the candidates the greedy covering is about
  /// to take, in parallel batches, instead of for every candidate. Same rules, fewer checks:
  /// bunny mesh at 1e-3 checks 2,527 of 8,192 candidates, 6.3 s of task-clock instead of 7.8.
  bool lazy_surface_check = true;
  /// Verification: zero-set samples on a verify_surface_grid² lattice per axis and patch, each
  /// seen through the blend along its normal from surface_probe_factor·E above it.
  int verify_surface_grid = 4;
  /// Verification also checks each patch alone (as while fitting) on a lattice of about
  /// verify_spacing·E in world units, at most verify_max_grid lines per side.
  double verify_spacing = 2.0;
  int verify_max_grid = 64;
  double surface_probe_factor = 2.0;
  /// The SLIM blend offset the bound is certified for (core/slim.h SlimBlendOptions); stored in
  /// the model as `slim_offset`, and renderers use it.
  double blend_offset = 0.5;
  /// The blend's push-back is at most this × E (stored as `slim_max_push`, world units; ≤ 0: no
  /// limit). Patches of one sheet hit a ray within about 2E of each other; a push of half a
  /// large ball (a face patch's) reaches a second sheet and blends it in.
  double blend_max_push = 4.0;
  /// With a mesh (the fit_slim overload below): its faces' centroids, and a lattice on faces much
  /// larger than their neighbours (core/io/io.h face_samples), join the points, fitted and covered
  /// like them, so the surface has no holes between the vertices.
  bool cover_faces = true;
  /// With cover_faces: where no quadric through a point's neighbours stays within E (a scan
  /// whose vertices jitter by more than E, fitted below its noise), the point is covered by the
  /// plane of the face it lies on, in a ball of face_patch_reach × the face's largest
  /// centroid–vertex distance (1.1 × that with face_prisms, so no corner sits at r = 1 with
  /// weight 0) around the face's centroid. Faces sharing a vertex all pass
  /// through it, so the blend keeps the vertex and joins up between vertices (no holes).
  /// Only where E is below the sampling: the point's nearest sample (vertex or face sample)
  /// farther than face_patch_spacing·E.
  /// With face_prisms, each face patch is clipped to its face's prism (a wall through every edge,
  /// perpendicular to the face; ClipPlanes), face_patch_margin·E outside an inner edge and a hair
  /// outside an open one: its plane, the data itself inside, runs on no farther than that into
  /// its neighbours' territory, where the blend would mix it with their planes. A triangle's
  /// walls meet far past a sharp corner (m / sin(θ/2)): the margins there shrink until they meet
  /// within local_surface_factor·E of it (not below face_patch_margin/5); a needle sharper than
  /// that floor allows gets a fourth plane across that corner.
  /// Without face_prisms, only its longest open edge clips it.
  bool face_patches = true;
  double face_patch_reach = 1.0;
  double face_patch_spacing = 10.0;
  bool face_prisms = true;
  double face_patch_margin = 0.5;
  /// Holes between the points (a mesh given, with face samples): each round, every face of the
  /// data's mesh is checked to lie inside the union of the balls (a face no one ball holds is
  /// split in four, down to face_hole_depth levels); a spot of a smallest piece outside every
  /// ball joins the points with its face's normal, and the repair covers it. Without this, balls
  /// smaller than the faces (noisy or open regions, small E) cover every point but not the faces
  /// between them (bunny at 1e-3: 37 faces). Not where there is more than one spot per 8 faces
  /// (the balls smaller than the faces nearly everywhere, E far below the sampling: bunny at
  /// 1e-4, 0.33 % of its area outside every ball); those spots are only counted (face_holes).
  /// One spot per face joins per round; rounds that add points do not count against
  /// repair_rounds, up to face_hole_rounds of them. Where there are more (and face_prisms), each
  /// face with a spot gets a face patch of its own, kept through pruning: its plane clipped to
  /// its prism is the data there, so it closes the hole without a fin.
  bool cover_face_holes = true;
  int face_hole_depth = 3;
  int face_hole_rounds = 4;
  /// With cover_face_holes and face_prisms, holes a view sees where the balls cover the face (the
  /// lattice check above is view-independent: a patch met edge-on, or a hit just outside its
  /// ball's rim, leaves a slit it cannot see; dragon_10k at 1e-3: 249 hole pixels of 8 views at
  /// 1024², 103 with this). Each round, each fan triangle is split in four down to
  /// view_hole_depth levels until one patch provably meets every view of a piece (its zero set
  /// crosses every such ray, front-facing, inside its ball and planes: bounds of the quadric
  /// along the ray over the whole piece); a smallest piece left is seen through its centroid along
  /// the normal and 2 × view_hole_rays directions on two cones up to view_hole_angle_deg, each ray
  /// traced through the blend where the data is seen away from its silhouette. A face some ray
  /// sees through gets a face patch. 0 rays: off (`fit --no-view-holes`).
  int view_hole_rays = 6;
  double view_hole_angle_deg = 75.0;
  int view_hole_depth = 2;
  /// Holes between the points of a cloud without faces (no mesh to check them against): each
  /// round, every point's coverage disc — its tangent plane within point_hole_factor × its
  /// spacing (the distance to its 6th nearest neighbour; on a regular sampling the cells between
  /// points reach 0.58 of it), the side past an open boundary left out — must lie inside the
  /// union of the balls, within 2·surface_factor·E of some patch's zero set (as a face, above:
  /// fan triangles split point_hole_depth times). Balls limited to about one spacing by E (E
  /// below what the sampling resolves: 5,000 points drawn from the bunny fitted at 1e-3 left
  /// 8.8 % of the true surface's pixels as holes, the armadillo's 15 %) cover every point but not
  /// the surface between them. A point whose disc is not held gets the candidate ball centred on
  /// it, when that ball reaches the spot; else, or when its disc is still not held in a later
  /// round, a disc patch: its tangent plane in a ball of disc_patch_reach × the disc, shrunk by
  /// the repair where it runs off the data and then left with its hole. Only where between
  /// point_hole_least and point_hole_share of the points have a hole after the first cover (with
  /// crease points, of the points not beside an edge or corner: their holes are discs cut or
  /// tilted there, filled only where a view sees them, as below the band):
  /// above, E is far below the sampling and what fills the cells runs beyond 2E of the points'
  /// tangent discs (kitten at 1e-4: 3,974 of 5,210); below, the balls outgrow the spacing nearly
  /// everywhere and the discs not held sit at creases and corners, where a disc tilts off the
  /// data (kitten at 1e-3: 2.7 %; a box without normals: 0.5 %, its fills stood 5–13E past the
  /// corners). Outside that band they are only counted (point_holes); `fit --no-fill-point-holes`
  /// turns it off.
  bool cover_point_holes = true;
  /// Below point_hole_least, the coverage holes that a view along the point's normal sees (the
  /// data's tangent discs there, the blend showing nothing or the far side: judge_ray, as bench
  /// fit counts holes) are filled the same way; the others are only counted. The uneven sphere
  /// (15,000 points, 10× denser on one half) at 1e-3 left 5 points' holes, 50 of 33,775 pixels
  /// seen through at 160².
  bool see_point_holes = true;
  /// ... unless more than this share of the points see one at the first check (then counted).
  double seen_hole_share = 0.01;
  /// Points without faces: the data's surface is the points' discs bent by their neighbours'
  /// heights (DataSurfaceOptions::bent_discs); false: flat tangent discs
  bool bent_discs = true;
  /// ... cut at sharp creases between planar faces (DataSurfaceOptions::crease_cuts: no fins
  /// past a plate's or a box's edges); false: whole discs, reaching up to a radius past a crease
  bool crease_cuts = true;
  /// ... and where the fit estimated the normals (none given, or given ones it set aside), a point
  /// whose neighbours lie on two or three planes meeting at a sharp edge while its rounded normal
  /// is off them takes its face's plane, and an edge point gives each face a disc
  /// (DataSurfaceOptions::crease_points)
  bool crease_points = true;
  /// ... and cut where an open boundary's own discs end (DataSurfaceOptions::rim_cuts: the data,
  /// and so the fit, stops near an open rim); false: the discs just inside a rim reach up to two
  /// spacings past it
  bool rim_cuts = true;
  /// ... and find the rims of holes, slots and bays too, so the data stops there
  /// (DataSurfaceOptions::hole_rims); false: the discs at such a rim reach up to three spacings
  /// into it, and across a slit two spacings wide
  bool hole_rims = true;
  double point_hole_factor = 0.6;
  int point_hole_depth = 1;
  double disc_patch_reach = 1.25;
  double point_hole_share = 0.5;
  double point_hole_least = 0.05;
  /// Points only: slits at creases between two sheets' clipped patches (each clipped at its own
  /// estimate of the crease, the planes parting between the points, where the blend shows
  /// nothing) are closed by moving the plane of the patch whose zero set runs across the slit
  /// (kitten at 1e-3: the far side showed through its mouth). Verified as any repair.
  bool relax_clips = true;
  /// The share of the data a view may see through and the fit still keep its promise (its part
  /// (c), no holes): SlimFitStats::hole_share above it is a fit outside its bound (`fit` exits 7),
  /// as points beyond E or surface beyond 2E are. 1e-4 is issue 11's target for holes (there a
  /// share of bench fit's pixels; here of the points, or of the fan triangles, seen through).
  double max_hole_share = 1e-4;
  /// A face seen through for the first time gets a regular ball at its centroid (the radius
  /// search and surface side as for any candidate) instead of a face patch: one such ball mends
  /// the slits of the faces around it too, and lets pruning drop balls it makes redundant. A
  /// face its ball would not reach across (radius < view_ball_min_reach × the face's
  /// centroid–vertex distance), or seen through again, gets the face patch. Bunny, armadillo,
  /// dragon_10k at 1e-3 (bench fit, 1024² views): 1,827 → 1,764, 3,183 → 2,869, 4,915 → 4,399
  /// patches with no more holes; factor 2: 1,780, 2,901, 4,845; 0 (any ball): happy_buddha_10k
  /// +3.5 %, its balls smaller than its faces.
  bool view_balls = true;
  double view_ball_min_reach = 1.0;
  /// Sharp features (issue 4 item 2): where a ball's fit fails and the normals in it split into
  /// two clusters more than sharp_angle_deg apart, the patch fits the cluster of its centre
  /// only and gets a clip plane (SlimPatch::clips) between the two sheets.
  /// Where the normals split into three such clusters (a corner of three faces), the centre's
  /// sheet is clipped at a plane per other sheet (in every use of the clipped sheet: here, and
  /// for a ball whose points fit but whose surface fails).
  bool sharp = false;
  /// ... and without it, beside an edge or corner (points whose 16 nearest hold points of two
  /// faces' planes: found by crease_points where the fit estimated the normals, else planar
  /// points with given normals turned as a crease's, DataSurface::planar), where each sheet's
  /// points lie within E of its plane (all but 2 %)
  bool sharp_at_creases = true;
  double sharp_angle_deg = 30.0;
  /// Neighbours for normal estimation when the cloud has no normals (fit/normals.h).
  std::size_t normal_neighbours = 16;
  std::uint64_t seed = 1;
};

struct SlimFitStats {
  std::size_t points = 0;
  std::size_t candidates = 0;        ///< candidate balls evaluated
  std::size_t settled_candidates = 0;  ///< of those, surface side checked (lazy_surface_check)
  std::size_t patches = 0;           ///< balls in the model
  std::size_t patches_before_pruning = 0;
  std::size_t height_patches = 0;    ///< patches using the height-function fallback
  std::size_t unbounded_patches = 0; ///< patches whose smallest ball still exceeded E (noise)
  std::size_t clipped_patches = 0;   ///< patches with a clip plane (--sharp)
  bool normals_estimated = false;
  double max_error_abs = 0;          ///< E in world units
  double cover_fraction = 0;         ///< the cover depth used (SlimFitOptions::cover_fraction or its default)
  double diagonal = 0;               ///< bounding-box diagonal of the points
  double max_taubin = 0, rms_taubin = 0;  ///< per-patch Taubin error over each ball's points, world units
  double max_blend = 0, rms_blend = 0;    ///< blended surface vs every point (fit/evaluate.h), world units
  std::size_t blend_failures = 0;    ///< points still farther than E from the blended surface
  std::size_t surface_samples = 0;   ///< zero-set samples seen through the blend (surface side)
  std::size_t surface_failures = 0;  ///< of those, farther than surface_factor·E from the data
  double surface_max = 0, surface_p999 = 0;  ///< their distances to the data, world units
  std::size_t normals_turned = 0;  ///< the cloud's own normals turned to agree with their neighbours'
  /// Points without faces: how far they scatter about their local surface (fit/outliers.h
  /// estimate_noise, world units); 0 with faces.
  double noise = 0;
  int repair_rounds = 0;
  /// Per verification round, how far its model was from the contract: the share of points
  /// beyond E + the share of surface samples beyond surface_factor·E + the share of the data's
  /// area outside every ball (mesh data), and its breaches of the bound: points beyond E plus
  /// surface samples beyond surface_factor·E. Of the rounds since the points last changed the
  /// fit keeps the model with the fewest breaches, among those the least failures (kept_round,
  /// 0-based): a repair can make things worse where E is far below the data's sampling.
  std::vector<double> round_failures;
  std::vector<std::size_t> round_breaches;
  int kept_round = 0;
  std::size_t hole_points = 0;  ///< points added on faces outside every ball (cover_face_holes)
  /// Where such spots were too many to join the points (E far below the sampling): faces that
  /// got a face patch of their own instead (face_prisms).
  std::size_t hole_face_patches = 0;
  std::size_t face_holes = 0;   ///< such spots still outside every ball at the end
  std::size_t view_face_patches = 0;  ///< faces some view saw through that got a face patch
  std::size_t view_balls = 0;        ///< regular balls added where a view saw through (view_balls)
  std::size_t view_holes = 0;   ///< fan triangles still seen through from some view at the end
  std::size_t point_holes = 0;  ///< points whose coverage disc is not held by the model returned (cover_point_holes)
  /// Points with a hole a view sees at the end, of their coverage holes or between them and
  /// their neighbours (see_point_holes; where too many to fill, counted on the model returned)
  std::size_t seen_point_holes = 0;
  std::size_t point_hole_balls = 0;  ///< candidate balls added on points with a hole
  std::size_t disc_patches = 0;      ///< disc patches added on points with a hole
  std::size_t clips_relaxed = 0;     ///< patches of the model returned whose crease plane moved across a slit (relax_clips)
  std::size_t crease_gaps = 0;       ///< slit samples at creases left at the end (relax_clips)
  std::size_t crease_points = 0;     ///< points that took their face's normal (SlimFitOptions::crease_points)
  /// The share of the data the model returned leaves seen through, as the fit counts it: points
  /// alone, the points with a hole a view sees (seen_point_holes, counted on the model returned
  /// whatever the rounds did) and crease gaps, per point; with faces, the fan triangles seen
  /// through (view_holes) plus the area outside every ball (face_holes, each a smallest piece
  /// of a fan triangle), per fan triangle. Compared with SlimFitOptions::max_hole_share.
  double hole_share = 0;
  bool holes_exceeded = false;  ///< hole_share > max_hole_share
  std::size_t subsample_levels = 0;  ///< nested subsamples for large balls' radius queries
  // Wall-clock seconds per stage.
  double time_normals = 0, time_candidates = 0, time_cover = 0, time_verify = 0, time_total = 0;
};

class DataSurface;

struct SlimFitResult {
  Model model;  ///< slims + metadata (E, measured errors, counts, times)
  SlimFitStats stats;
  /// The data's surface the fit was bounded against (the mesh's triangles, else the points'
  /// tangent discs; fit/data_surface.h), for measurements after the fit without building it again.
  /// Points alone are fitted in Morton order: its per-point queries (spacing, disc_radius) are
  /// indexed in that order, not the caller's.
  std::shared_ptr<const DataSurface> data;
  /// Per model.slims: the largest distance from the data of the patch's surface samples as the
  /// blend shows them (the surface side per patch, world units; 0 when not checked).
  std::vector<double> surface_error_per_patch;
};

/// Fits a SLIM surface to cloud (points in world units; normals optional, outward, unit —
/// estimated with fit/normals.h when absent). kd-tree, candidate centres among the points, per
/// candidate the largest support radius whose local quadric keeps the error ≤ E, greedy
/// covering (a point is covered within cover_fraction·R of a chosen centre), pruning of redundant
/// balls, then verification against the blended surface and repair (TBB-parallel throughout).
/// A point that no ball around it fits within E (noise) gets its tangent plane in a ball holding
/// no other point. Both sides of the contract are verified on the blended surface with core's
/// blend (core/reference.h): points → surface ≤ E, and samples of every patch's zero set seen
/// through the blend → data ≤ surface_factor·E; patches at fault shrink and the points are
/// covered again, for up to repair_rounds rounds. The stats say what was reached.
/// \throws InvalidInput for fewer than 10 points, non-finite coordinates or normals, a normal
///         count that differs from the point count, zero normals, coincident or coplanar points,
///         or bad options.
SlimFitResult fit_slim(const PointCloud& cloud, const SlimFitOptions& options = {});

/// The same with the data's own surface given (the mesh the points come from): the surface side
/// is then bounded against the mesh's triangles instead of the points' tangent discs, so the
/// surface stops where the mesh does (open boundaries) rather than a sample spacing beyond.
/// Faces of more than three corners count as their fans of triangles (PolygonMesh::fanned).
SlimFitResult fit_slim(const PointCloud& cloud, const PolygonMesh& surface, const SlimFitOptions& options = {});

}  // namespace quadrix
