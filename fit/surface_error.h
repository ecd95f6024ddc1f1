#pragma once
/// What a viewer sees, measured against the data (DESIGN §2, the surface side of a fit's
/// contract): a surface is ray-cast from several views, every covered pixel is back-projected
/// and its distance to the data's surface measured. Pixels where the data (a mesh, or a cloud's
/// tangent discs) shows its front away from its silhouette are holes where the surface leaves
/// them empty or shows something farther than the bound behind the data (the far side through a
/// slit). Models (per-ray SLIM blend of core/reference.h) and triangle meshes are measured the
/// same way.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "core/camera.h"
#include "core/mesh_io.h"
#include "core/model.h"
#include "core/ray.h"
#include "fit/data_surface.h"

namespace quadrix {

struct SurfaceErrorOptions {
  /// Views from the 8 corners of a cube around the data (and a 9th+ from the axes when more).
  int views = 8;
  int resolution = 256;  ///< pixels per side of each view
  /// Distances above this count as "beyond" (world units; typically 2E). 0: not counted.
  double bound = 0;
  /// Hole band: a data pixel counts only when every pixel within max(band_px, bound in pixels)
  /// of it is covered by the data too (away from the silhouette).
  double band_px = 1.0;
  /// The same band along the data's open boundary (DataSurface::boundary_near: a mesh's open
  /// edges, a cloud's boundary points): data pixels that near the edge of a sheet do not count,
  /// as near its silhouette, whatever lies behind it in view (a scan's open base seen from
  /// below, the inside of the far wall past its rim): a fit's surface stops within the bound of
  /// an open boundary instead of extrapolating past it. false: they count.
  bool rim_band = true;
  /// Keep where the first this many holes are (the data's points there), e.g. to log them.
  std::size_t keep_hole_points = 0;
  /// Keep where the first this many pixels beyond bound are (the surface's points there).
  std::size_t keep_beyond_points = 0;
  /// Count the holes (the data ray-cast at every pixel); false: skip them.
  bool holes = true;
};

struct SurfaceError {
  std::size_t pixels = 0;          ///< covered pixels measured (all views)
  double max = 0, p999 = 0, p99 = 0, rms = 0;  ///< world units
  std::size_t beyond = 0;          ///< pixels farther than bound
  double share_beyond = 0;         ///< beyond / pixels
  std::size_t data_pixels = 0;     ///< data pixels away from the silhouette
  std::size_t holes = 0;           ///< of those, pixels the surface left empty or showed behind the data
  std::size_t see_through = 0;     ///< of the holes, those where the surface showed something behind
  double hole_share = 0;           ///< holes / data_pixels
  bool has_holes_measure = false;  ///< holes were counted (options.holes)
  std::vector<Eigen::Vector3d> hole_points;  ///< up to keep_hole_points, world units
  std::vector<Eigen::Vector3d> hole_dirs;    ///< the view ray's direction at each of hole_points
  struct Beyond {
    Eigen::Vector3d point;  ///< on the surface, world units
    double distance;        ///< to the data, > bound
  };
  std::vector<Beyond> beyond_points;  ///< up to keep_beyond_points
};

/// What one ray shows of the data and of a surface, the way measure_surface_error judges each
/// pixel. data_t: the data's first front-facing sheet along the ray (a cloud's: the tangent disc
/// there nearest its own point), −1: none; reach: a cloud's disc radius there (it may stand that
/// far past a silhouette), else 0. counts: the data there is sure enough to ask for a surface (not
/// a cloud's disc far from its point, not a ridge the ray only grazes within the bound, not a ray
/// along more than 64 of a cloud's overlapping discs); hole:
/// the surface shows nothing (t_surface < 0), or through: something more than the bound behind
/// the data, nearer its next sheet (for a cloud: where the ray leaves the solid) than its first.
struct RayVerdict {
  double data_t = -1, reach = 0;
  bool counts = false, hole = false, through = false;
};
RayVerdict judge_ray(const DataSurface& data, const Ray& ray, double t_surface, double bound);

/// A ray caster: the distance t along the ray (unit dir) to the first visible surface.
using TraceFn = std::function<std::optional<double>(const Ray&)>;

/// What a surface shows from the views framing a box (options.views, options.resolution), kept
/// to be measured against several data surfaces in turn without ray-casting the surface again.
struct SurfaceViews {
  std::vector<Camera> cameras;
  std::vector<std::vector<double>> t;  ///< per view, per pixel (row-major): the hit's ray distance, −1: none
};
SurfaceViews render_surface_views(const TraceFn& trace, const Box3& data_box, const SurfaceErrorOptions& options = {});

/// Measures what trace shows against data, from views framing data_box.
SurfaceError measure_surface_error(const TraceFn& trace, const DataSurface& data, const Box3& data_box,
                                   const SurfaceErrorOptions& options = {});
/// The same from views rendered before (options.views and options.resolution are theirs).
SurfaceError measure_surface_error(const SurfaceViews& views, const DataSurface& data,
                                   const SurfaceErrorOptions& options = {});
/// The same for a model (CPU reference, the model's own SLIM blend offset).
SurfaceError measure_surface_error(const Model& model, const DataSurface& data, const Box3& data_box,
                                   const SurfaceErrorOptions& options = {});

}  // namespace quadrix
