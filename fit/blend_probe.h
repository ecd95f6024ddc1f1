#pragma once
/// The blended SLIM surface along short probe rays (the rule of core/slim.h's
/// blend_slim_samples: first front-facing in-ball hit per patch, t_cut = minᵢ(tᵢ + ½Rᵢ), weighted
/// mean of the samples in front of t_cut), with the patches found through a kd-tree over the
/// centres. Used by the fitter to verify and repair; fit/evaluate.h is the public measure.
#include <limits>
#include <vector>

#include "core/model.h"
#include "fit/point_index.h"

namespace quadrix {

class BlendProbe {
public:
  /// The model must outlive the probe. Clip planes are honoured.
  explicit BlendProbe(const Model& model);

  /// Distance |t − h| of the blended hit along the ray from p + h·n in direction −n (n unit),
  /// +inf when no patch is hit. With `culprits`, the patches whose own sample is farther than
  /// bound from p (or, on a miss, the patches whose ball holds p) are appended.
  double probe(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double h, double bound = 0,
               std::vector<int>* culprits = nullptr) const;

private:
  const Model* model_;
  std::vector<Eigen::Vector3d> centres_;
  double max_radius_ = 0;
  PointIndex index_;
};

}  // namespace quadrix
