#pragma once
/// Curvature glyphs ([Toledo04] Fig. 1 and 9): one ellipsoid per mesh vertex, its axes along the
/// principal directions and the normal, from a local jet fit in Monge form (CGAL's
/// Monge_via_jet_fitting, in convert/curvature_glyphs_cgal.cpp only).
#include <cstddef>
#include <vector>

#include "core/mesh_io.h"
#include "core/model.h"

namespace quadrix {

struct CurvatureGlyphOptions {
  int jet_degree = 2;       ///< degree of the fitted jet (1 < d ≤ 4)
  int neighbours = 16;      ///< vertices per fit: the vertex and its nearest rings (≥ (d+1)(d+2)/2)
  double size = 0.45;       ///< largest in-plane semi-axis, in mean edge lengths
  double thickness = 0.15;  ///< semi-axis along the normal, in mean edge lengths
  double min_axis = 0.15;   ///< smallest in-plane semi-axis, as a fraction of `size`
};

struct CurvatureGlyphs {
  Model model;                  ///< ellipsoid glyphs, one per fitted vertex, coloured by shape
  std::vector<double> k_max;    ///< per glyph: principal curvatures (1/world units), k_max ≥ k_min,
  std::vector<double> k_min;    ///< signed so that a sphere seen from outside has k > 0
  std::vector<std::size_t> vertex;  ///< the mesh vertex of each glyph
  std::size_t skipped = 0;      ///< vertices with too few neighbours or an ill-conditioned fit
  double mean_edge = 0;         ///< world units
};

/// Fits the curvature tensor at every vertex of `mesh` (polygons; neighbours through its edges)
/// and makes an ellipsoid per vertex: semi-axes along the maximal and minimal principal directions
/// proportional to |k| (relative to the mesh's 95th percentile of |k|, clamped to
/// [min_axis, 1]·size), a thin one along the outward normal. Colour: shape index (blue concave,
/// green saddle, red convex). \throws InvalidInput for an empty mesh or bad options.
CurvatureGlyphs curvature_glyphs(const PolygonMesh& mesh, const CurvatureGlyphOptions& options = {});

}  // namespace quadrix
