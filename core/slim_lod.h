#pragma once
/// Level of detail for SLIM hierarchies (Ohtake et al. 2005 §4): per view, the coarsest cut of
/// the hierarchy whose balls' errors project below a pixel bound at each ball's own distance
/// from the eye. The GL renderer and the CPU reference draw the same cut (slim_cut_model).
#include <cstdint>
#include <span>
#include <vector>

#include "core/camera.h"
#include "core/model.h"

namespace quadrix {

struct SlimLodOptions {
  /// Largest projected error, pixels: a ball stands in for the balls below it when its error,
  /// seen at the nearest point of its ball (eye-space depth), spans at most this many pixels.
  /// 0 (or less): the leaves, full detail.
  double pixel_error = 0.5;
  /// A ball whose subtree (every ball below it, and itself) lies outside the view frustum is
  /// taken as it is, not refined: nothing in it can show, so the image is the same.
  bool skip_outside_view = true;
};

/// A cut of the hierarchy: every leaf lies under exactly one of its balls.
struct SlimLodCut {
  std::vector<std::int32_t> balls;        ///< ball ids (SlimHierarchy), increasing
  /// Balls of the cut per level: [0] leaves, [k] balls k levels above their deepest leaf.
  std::vector<std::size_t> level_counts;
  std::size_t outside_view = 0;  ///< balls taken unrefined because their subtree is outside the view
  bool operator==(const SlimLodCut& o) const { return balls == o.balls; }
};

/// Each ball's error as a distance, world units. A fitted hierarchy (`fit --lod-levels`, metadata
/// `slim_hierarchy_error distance`) stores distances and they are returned as stored. Kanai's
/// .slim2t stores a fitting energy (metadata `source_format slim2t`, or a `slim_hierarchy_error`
/// other than `distance`), so there the distance is measured, two-sided, against the leaves, on
/// zero-set samples (core/slim.h sample_slim_patch, a 2×2 lattice per ball): the largest of
/// (1) the Taubin distance |g|/‖∇g‖ from the ball's quadric to its leaves' samples inside its
/// ball, and the distance to the ball of their samples outside it (a hole the ball leaves), and
/// (2) the distance from the ball's own samples to the nearest leaf sample (or, when nearer, to
/// the quadric of one of the 8 nearest leaves whose ball holds the sample). Leaves 0.
/// \throws InvalidInput for an invalid hierarchy (validate_slim_hierarchy).
std::vector<double> slim_lod_errors(const Model& model);

/// A hierarchy prepared for a cut per frame: the walk costs O(balls visited), no allocation of
/// the tree. Holds copies of what it needs; the model may go away.
class SlimLod {
public:
  /// \throws InvalidInput for an invalid hierarchy. A model without one gives the cut of all
  /// its patches for every view.
  explicit SlimLod(const Model& model);
  /// The coarsest cut whose every ball passes the projected test for this camera.
  SlimLodCut cut(const Camera& camera, const SlimLodOptions& options = {}) const;
  /// Balls in the hierarchy (Model::slims.size() without one).
  std::size_t size() const { return centre_.size(); }
  bool has_hierarchy() const { return !roots_.empty(); }
  /// Levels above the leaves, plus one (1 without a hierarchy).
  std::size_t levels() const { return levels_; }
  /// Per ball id: its error as a distance (slim_lod_errors).
  const std::vector<double>& errors() const { return error_; }

private:
  std::vector<Eigen::Vector3d> centre_;
  std::vector<double> radius_, error_;
  std::vector<double> reach_;                // radius about centre_ of the ball's subtree's balls
  std::vector<std::uint32_t> first_child_;  // CSR: children of b are child_[first_child_[b] .. first_child_[b+1])
  std::vector<std::int32_t> child_, roots_;
  std::vector<std::uint32_t> height_;       // 0 at the leaves
  std::size_t levels_ = 1;
};

/// One-off: SlimLod(model).cut(camera, options).
SlimLodCut select_slim_lod(const Model& model, const Camera& camera, const SlimLodOptions& options = {});

/// The model with its SLIM patches replaced by the cut's balls (in cut order) and no hierarchy:
/// what a renderer draws for that cut (primitive index i is the cut's i-th ball).
/// \throws InvalidInput for a ball id outside the hierarchy.
Model slim_cut_model(const Model& model, std::span<const std::int32_t> balls);

}  // namespace quadrix
