#pragma once
/// The per-ray SLIM blend is not one surface: a ray at a grazing angle blends other hits than a
/// ray along the normal, so a view can see the surface in front of (or behind) where a head-on
/// view sees it. A mesh on the head-on surface is then beyond the bound from the grazing view.
/// Where that gap is under twice the bound, the mesh can be within the bound of both: its
/// vertices are moved part of the way towards what the grazing views see, staying within the
/// bound of the head-on surface.
#include <cstddef>
#include <span>
#include <vector>

#include "core/mesh_io.h"
#include "fit/surface_error.h"

namespace quadrix {

struct BetweenViewsOptions {
  double bound = 0;           ///< the mesh's bound (world units)
  double keep = 0.7;          ///< × bound: the distance left to a grazing view's point after a move
  double max_offset = 0.85;   ///< × bound: the most a vertex moves in all, off the surface it was on
  std::size_t first_face = 0; ///< faces before it (other primitives' exact tessellations) stay
};

/// Moves the vertices of the face nearest each drawn point beyond the bound (surface → mesh) along
/// their normals towards it, to within options.keep × bound of it (a point beside the face, past
/// an open edge where the blend runs on a little: straight towards it), each vertex's total move
/// (`offset`, per vertex, grown to the mesh's size and kept across calls) at most
/// options.max_offset × bound; a vertex pulled both ways stays. Returns the vertices moved.
std::size_t move_between_views(PolygonMesh& mesh, std::span<const SurfaceError::Beyond> beyond,
                               const BetweenViewsOptions& options, std::vector<double>& offset);

}  // namespace quadrix
