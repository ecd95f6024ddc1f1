#pragma once
/// Levels of detail for a fitted SLIM surface: coarser levels above the fit, linked into
/// Model::slim_hierarchy so a renderer can draw a cut by projected error (core/slim_lod.h).
#include <vector>

#include "core/mesh_io.h"
#include "core/points_io.h"
#include "fit/slim_fit.h"

namespace quadrix {

/// How a coarser level is made.
enum class SlimLevelRule {
  /// Level k is its own SLIM fit of the same data (fit_slim) at the bound E·level_factor^k, with
  /// its own measured two-sided error; a ball's parent is the coarser ball that holds most of its
  /// zero set.
  fits,
  /// Level k merges the balls of level k − 1 into larger ones (reach below) that hold them.
  merge,
};

struct SlimHierarchyOptions {
  /// Coarser levels above the fit (fewer when a level stops reducing the count).
  int levels = 3;
  SlimLevelRule rule = SlimLevelRule::fits;
  /// fits: level k's bound is the fit's E × level_factor^k.
  double level_factor = 4.0;
  /// fits: each coarser ball keeps its own fit's blend push bound (SlimPatch::max_push, that
  /// fit's `slim_max_push`, blend_max_push × E_k), so a cut blends each level as its own fit does;
  /// false: every level blends with the finest fit's push (for comparison).
  bool level_push = true;
  /// A group takes the balls whose centres lie within reach × max(its lead's radius, the level's
  /// median radius) of the lead's centre. Bunny mesh at 1e-3, balls per level: reach 1.0 (lead's
  /// radius only) 1,592/698/178/45/8; 1.2 1,592/456/81/10/2; 1.4 1,592/323/38/6/2; 2.0
  /// 1,592/129/6/1 (level-1 max error 84E, 84E, 98E, 123E).
  double reach = 1.2;
};

struct SlimLevelsStats {
  std::vector<std::size_t> patches;  ///< per level, finest (the fit itself) first
  std::vector<double> max_error;     ///< per level: the largest ball error, world units
  /// fits: per level, the bound E_k it was fitted at (world units) and the seconds its fit took;
  /// and per level, coarse balls dropped because no finer ball chose them as its parent (they
  /// would be leaves, drawn at full detail).
  std::vector<double> bound;
  std::vector<double> fit_seconds;
  std::vector<std::size_t> dropped;
  double seconds = 0;                ///< building the coarse levels and measuring their balls
};

/// Builds coarser levels above a finished fit.
///
/// SlimLevelRule::fits: level k is fit_slim of the same data with max_error E·level_factor^k (the
/// other options as `fit`), stopping when a level has no fewer patches than the one below. Each
/// ball's error is its own two-sided measure against the data (as for the fit's patches, below),
/// raised to its children's. A ball of level k − 1 gets as parent the ball of level k holding the
/// most of its zero-set samples (core/slim.h sample_slim_patch; ties by the SLIM weight there); a
/// coarse ball no finer ball chose takes, if it can, the finer ball it holds best from a parent
/// with other children, else it is dropped. With level_push, each coarser ball carries its own
/// fit's push bound (SlimPatch::max_push).
///
/// SlimLevelRule::merge: per level, the largest ball not yet
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
