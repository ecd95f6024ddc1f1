#pragma once
/// Levels of detail for a fitted SLIM surface (issue 12 item 4): coarser balls merged above the
/// fit, linked into Model::slim_hierarchy so a renderer can draw a cut by projected
/// error (core/model.h select_slim_cut).
#include <vector>

#include "core/mesh_io.h"
#include "core/points_io.h"
#include "fit/slim_fit.h"

namespace quadrix {

struct SlimHierarchyOptions {
  /// Coarser levels above the fit (fewer when merging stops reducing the count).
  int levels = 3;
  /// A group takes the balls whose centres lie within reach × max(its lead's radius, the level's
  /// median radius) of the lead's centre. Bunny mesh at 1e-3, balls per level: reach 1.0 (lead's
  /// radius only) 1,592/698/178/45/8; 1.2 1,592/456/81/10/2; 1.4 1,592/323/38/6/2; 2.0
  /// 1,592/129/6/1 (level-1 max error 84E, 84E, 98E, 123E).
  double reach = 1.2;
};

struct SlimLevelsStats {
  std::vector<std::size_t> patches;  ///< per level, finest (the fit itself) first
  std::vector<double> max_error;     ///< per level: the largest ball error, world units
  double seconds = 0;                ///< merging, fitting and measuring the coarse balls
};

/// Builds coarser levels above a finished fit by merging: per level, the largest ball not yet
/// taken takes every ball whose centre lies within its reach (options.reach), and the group
/// gets one ball that holds all of their balls (a cut that draws it instead of them leaves no hole), with a quadric fitted
/// to the points inside (fit/local_fit.h, the fit's μ). Each ball's error is a distance in world
/// units: for the fit's patches the larger of their points side (SlimPatch::measured_error,
/// computed here when missing) and surface side (SlimFitResult::surface_error_per_patch); for a
/// merged ball the larger of its points' Taubin and probe distances, its zero set's distance
/// from the data (fit/data_surface.h zero_set_excess, raised until it passes) and its children's
/// errors, so errors grow towards the roots. fine.model keeps its patches as the drawn leaves;
/// the merged balls go to slim_hierarchy.others. surface: the mesh the fit used, or null (then
/// the points' tangent discs); the fit's own SlimFitResult::data is used when it is there. Metadata: `slim_hierarchy_error distance`, `slim_levels`.
/// \throws InvalidInput without patches or without normals in cloud.
SlimLevelsStats add_slim_hierarchy(SlimFitResult& fine, const PointCloud& cloud, const PolygonMesh* surface,
                                   const SlimFitOptions& fit, const SlimHierarchyOptions& options = {});

}  // namespace quadrix
