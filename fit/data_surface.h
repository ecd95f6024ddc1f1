#pragma once
/// The data a SLIM fit is judged against, as a surface (DESIGN §2, the two-sided contract):
/// a triangle mesh (exact point–triangle distance, ray casting for hole counts), or oriented
/// points read as the union of their tangent discs, each disc as wide as the local sample
/// spacing and bent as its neighbours' heights bend it ("the local surface of the points").
#include <cstddef>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "core/mesh_io.h"
#include "core/model.h"
#include "core/ray.h"

namespace quadrix {

struct DataSurfaceOptions {
  /// Tangent-disc radius of a point: disc_factor × the distance to its spacing_neighbour-th
  /// nearest neighbour on the same sheet (6 neighbours of a regular sampling sit at about one
  /// spacing; random samplings leave gaps of up to about 1.5 spacings).
  std::size_t spacing_neighbour = 6;
  double disc_factor = 1.5;
  /// ... and at least sector_reach × the distance to the nearest same-sheet point in whichever
  /// 60° sector of its tangent plane has it farthest (of those that have one: not past a boundary)
  double sector_reach = 0.75;
  /// Open boundaries: a point whose boundary_neighbours nearest neighbours have their tangential
  /// centroid more than boundary_offset × their mean distance away lies on a boundary; its disc
  /// reaches only boundary_reach × its radius past the point, away from that centroid (so the
  /// data's surface stops near the boundary instead of extrapolating by a whole spacing).
  std::size_t boundary_neighbours = 24;
  double boundary_offset = 0.45;
  double boundary_reach = 0.25;
  /// Bent discs: each disc carries the second-order term of its neighbours' heights over its
  /// tangent plane (a flat disc's sag at its rim, about κρ²/2, read as error where E is below it),
  /// capped so its slope at the rim stays below max_disc_slope.
  bool bent_discs = true;
  double max_disc_slope = 0.5;
  /// ... only where the bend explains the heights: the residual sum of squares at most this
  /// share of the flat disc's
  double bend_residual = 0.25;
  /// Creases: a disc is cut short where it crosses the tangent plane of a point within its
  /// radius and a spacing whose normal turns more than acos(crease_cos) from its own (and less
  /// than its reverse), keeping its own side: at a sharp convex edge a face's discs otherwise
  /// reach a whole radius past the edge (a plate 1 × 1 × 0.04 fitted at 3e-3 drew fins 5.7E past
  /// its edges within 2E of the discs), and at a concave one through the other face.
  /// Only between planar points: those whose neighbours on their sheet within the disc (normals
  /// within acos(crease_cos)) lie at most crease_planarity × the spacing off its tangent plane
  /// (RMS): on a smooth surface sampled sparsely the normals turn as much between neighbours,
  /// and a neighbour's plane would cut the surface itself.
  bool crease_cuts = true;
  double crease_cos = 0.75;
  double crease_planarity = 0.005;
  /// Crease points (with crease_cuts): a point whose crease_neighbours nearest turn their normals
  /// and lie, all but two, within crease_planarity × 2 of the spacing of two or three planes (the
  /// first through the point) turned more than acos(crease_cos) from each other, while its own
  /// normal is off them, is a sample of those faces, not of a surface along its own normal:
  /// normals estimated from neighbours (PCA) round a sharp edge, and their discs, tilted up to half
  /// the dihedral, stood off both faces (a box without normals fitted at 1e-3 drew surface 4.5E
  /// off the true box at p99.9). Its disc takes the plane through it; where it lies on another
  /// plane too (on the edge), a second disc there takes that plane's normal, and the crease cuts
  /// stop each at the other. Off by default: for a mesh's vertex normals (averaged at the edges)
  /// it helps where both faces are flat and harms where one is a tessellated curve (fandisk's
  /// vertices at 3e-3: 2.6 % of the pixels beyond 2E against 0.15 %); fit_slim asks for it where
  /// it estimated the normals (SlimFitOptions::crease_points).
  bool crease_points = false;
  std::size_t crease_neighbours = 16;
  /// Knife edges: faces whose normals turn more than the reverse of acos(crease_cos) (139°), up to
  /// the reverse of acos(knife_cos) (166°), meet at a crease too, for the crease points and the
  /// crease cuts (a cut only where the planes cross within the disc: a thin plate's two sides,
  /// parallel, cut nothing). knife_cos = crease_cos: as before (no cut past 139°).
  double knife_cos = 0.97;
  /// Rim cuts: a disc near an open boundary is cut where the boundary points' discs end (the
  /// support lines of their ends: DataSurface::cut_at_rims), so the data stops near the rim
  /// instead of reaching up to two spacings past it; a boundary point beside a crease no longer
  /// leans away from it (from_points); past_boundary gives lines past the rim. False: as before
  /// the cuts.
  bool rim_cuts = true;
  /// Holes' rims (from_points, confirm_boundaries): a point is on an open boundary also where the
  /// widest angle between its consecutive neighbours about it is 100° or more (at a concave rim
  /// the centroid test passes it); a point across a gap is evidence of a density step only within
  /// 2.5 of its spacings (3 before) and when it is no boundary point facing away with a spacing
  /// within 2× of this point's (the far rim of the same hole, slot or bay); a disc is widened towards the sectors' nearest points only as far
  /// as the nearer of two opposite sectors' (not beside another sheet). A boundary point only these
  /// rules made stays one only in a run of boundary points at least 6 spacings long: a slit is
  /// long, a random sampling's chance void round. The data then reaches about a third less far into
  /// holes and bays, and the bunny's base sampled by 20,000 points is no longer bridged where its
  /// holes are slits. False: as before.
  bool hole_rims = true;
};

class DataSurface {
public:
  /// points: N×3 world units; normals: N unit vectors. Both spans are copied.
  static DataSurface from_points(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                                 const DataSurfaceOptions& options = {});
  /// Faces are fanned into triangles. \throws InvalidInput for a mesh without faces.
  static DataSurface from_mesh(const PolygonMesh& mesh);

  DataSurface(DataSurface&&) noexcept;
  DataSurface& operator=(DataSurface&&) noexcept;
  ~DataSurface();

  /// Distance from x to the data's surface, world units (thread-safe). With a finite cap, any
  /// distance beyond the cap comes back as +inf (faster: a mesh walk prunes what lies farther).
  /// With good > 0, a mesh walk stops at the first triangle within good and returns its
  /// distance: an upper bound ≤ good, not the minimum (for "within good?" questions); for
  /// points likewise the first disc found within good. Either way the answer to "≤ good?" is the
  /// full query's. For points the distance is to the union of every point's disc (a BVH walk
  /// over the discs), so, like a mesh's, it never changes faster than lipschitz() × as x moves.
  double distance(const Eigen::Vector3d& x, double cap = std::numeric_limits<double>::infinity(),
                  double good = 0) const;
  /// Nearest intersection of the ray with the triangles (either side) in (tmin, tmax), or for
  /// points with their tangent discs (the union distance() measures to). front: whether that
  /// triangle faces the ray: counter-clockwise seen from the ray's origin, or clockwise when the
  /// mesh is wound inwards (core/io/io.h mesh_wound_inward); whether the disc's normal does.
  std::optional<double> intersect(const Ray& ray, double tmin = 0.0, bool* front = nullptr,
                                  double tmax = std::numeric_limits<double>::infinity()) const;
  /// The same hit with what the surface is there.
  struct RayHit {
    double t = 0;
    bool front = false;                                 ///< as intersect's
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();   ///< unit, outward (facing the ray when front)
    double reach = 0;                                   ///< points: the hit disc's radius; mesh: 0
    /// Points: how far the hit lies from the disc's own point, and that point's sample spacing
    /// (a disc stands off a curved surface, and past its contours, more the farther from its
    /// point); mesh: 0.
    double from_sample = 0, spacing = 0;
  };
  std::optional<RayHit> first_hit(const Ray& ray, double tmin = 0.0,
                                  double tmax = std::numeric_limits<double>::infinity()) const;
  bool has_faces() const;
  /// How fast distance() can change as its query moves: 1 for a mesh and flat discs; for bent
  /// discs √(1 + s²), s the steepest disc's slope at its rim (≤ max_disc_slope: the height over
  /// a bent disc is measured along its normal).
  double lipschitz() const;
  /// The normal of point i's disc (points only; the given points first, then the second discs of
  /// DataSurfaceOptions::crease_points): the point's own, or at a crease point its face's plane.
  const Eigen::Vector3d& normal(std::size_t i) const;
  /// Points whose disc's normal is a face's plane instead of their own, and the second discs
  /// on edges (DataSurfaceOptions::crease_points).
  std::size_t crease_points() const;
  std::size_t crease_copies() const;
  /// Whether point i's disc lies in a face's plane found at a crease (DataSurfaceOptions::
  /// crease_points: its own normal kept where it was that plane's within 1°, and the second
  /// discs): a point of a sharp edge's faces.
  bool faced(std::size_t i) const;
  /// Whether point i is planar for the crease cuts (points with crease_cuts): faced, or its own
  /// sheet's neighbours within its disc lie within crease_planarity × the spacing of its plane.
  bool planar(std::size_t i) const;
  /// Tangent-disc radius of point i (points only).
  double disc_radius(std::size_t i) const;
  /// Height of point i's bent disc over its tangent plane at the tangential offset t (points
  /// only; 0 for flat discs), t clamped to the disc's radius: the disc's point over p + t is
  /// p + t + height·n.
  double bend_height(std::size_t i, const Eigen::Vector3d& t) const;
  /// Point i's bend as a world-frame tensor K (tangential: Kn = 0): the bent disc's height over
  /// p + t is ½ tᵀKt (points only; zero for flat discs).
  Eigen::Matrix3d bend_tensor(std::size_t i) const;
  /// Point i's sample spacing (points only): the distance to its spacing_neighbour-th nearest
  /// neighbour on the same sheet, or, at a step in the sampling density, half the gap to the
  /// sparse side's nearest point where that is wider (not the sectors' reach of its disc).
  double spacing(std::size_t i) const;
  /// The data's open boundary near c: samples (position, unit tangent towards the data) within
  /// r of c — boundary points of a cloud, or the vertices and edge midpoints of a mesh's open
  /// edges (out is cleared first).
  struct BoundarySample {
    Eigen::Vector3d point, inward;
  };
  /// With crease_sides, also the points beside a sharp crease that have no neighbour of their
  /// own face past it, as a boundary's do (their tangent towards their face's points), though
  /// the crease cuts, not the boundary's star, stop their discs: where a patch may stop too.
  void boundary_near(const Eigen::Vector3d& c, double r, std::vector<BoundarySample>& out, bool crease_sides = false) const;
  /// Lines across the data's surface just past its open rim within r of c: for each of a cloud's
  /// boundary points that stands for an open rim (rim_cuts: no other sheet ahead of it, as beside
  /// a crease), along its normal through the points `offset` past where its disc ends, outward,
  /// for each offset, where that line passes within r of c (out is cleared first; none for a
  /// mesh, none without rim_cuts).
  void past_boundary(const Eigen::Vector3d& c, double r, std::span<const double> offsets, std::vector<Ray>& out) const;
  /// Whether x lies within r of the data's open boundary: a mesh's open edges (exactly), a
  /// cloud's boundary points.
  bool near_open_boundary(const Eigen::Vector3d& x, double r) const;

private:
  DataSurface();
  struct Impl;
  static void from_mesh_boundary(const PolygonMesh& mesh, Impl& m);  // open edges, winding
  static void confirm_boundaries(Impl& m, const std::vector<double>& reach, const std::vector<std::uint8_t>& rim_kind);  // points
  static void cut_at_creases(Impl& m, const std::vector<std::uint8_t>& planar);  // points
  static void split_at_creases(Impl& m);  // points
  static void cut_at_rims(Impl& m);  // points, after the boundary is final
  std::unique_ptr<Impl> impl_;
};

/// Whether a SLIM patch's zero set inside its ball (and clip plane) lies within bound of data.
/// Lines parallel to the three local axes on a grid × grid lattice find its points; as distance
/// to the data is L-Lipschitz (DataSurface::lipschitz), a sample at distance d vouches for its
/// lattice cell when d + L·(the cell's reach on the sheet) ≤ bound, and cells it cannot vouch for are split in four,
/// down to a reach of bound/16 or max_depth splits, whichever comes first (the cost of a full
/// guarantee grows with (R/bound)²; the blended verification samples the rest). A clipped patch
/// is also sampled every bound/2 along the curve where its zero set meets the clip plane, where
/// it reaches farthest past an open boundary.
/// Returns 0 when within, else the distance of the first sample found beyond bound.
double zero_set_excess(const SlimPatch& patch, const DataSurface& data, double bound, int grid, int max_depth);

/// Distance from x to triangle (a, b, c), any shape (degenerate ones as segments).
double point_triangle_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c);

}  // namespace quadrix
