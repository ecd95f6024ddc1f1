#pragma once
/// Patch colours from a coloured point cloud (a scan with per-point RGB): every SLIM ball takes
/// the colour of the points in it, weighted as the blend weighs the ball at each point, so the
/// renderer's per-ray colour blend (Σ wᵢcᵢ / Σ wᵢ, core/reference.cpp and render/shaders/slim.frag)
/// reproduces the scan's colours at the resolution of the balls.
#include "core/io/point_cloud.h"
#include "core/model.h"

namespace quadrix {

/// Sets SlimPatch::colour of every drawn patch and every other ball of the hierarchy to
/// Σ w(‖p − c‖/R)·colour(p) / Σ w over the cloud's points p in the ball (core/slim.h slim_weight),
/// rounded; a ball with no point of positive weight takes its nearest point's colour. Nothing
/// when the cloud has no colours. TBB-parallel over balls.
/// \throws InvalidInput when the cloud's colours and points differ in number.
void set_patch_colours(Model& model, const PointCloud& cloud);

}  // namespace quadrix
