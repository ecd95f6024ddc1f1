#pragma once
/// Colour maps shared by the CPU reference and the GL renderer (`render --colour-by`): one
/// scalar map, one categorical patch palette, the normal encoding, and the model recolouring
/// and per-pixel colouring that use them, so both backends draw the same colours.
#include <optional>
#include <span>
#include <string_view>

#include <Eigen/Core>

#include "core/image.h"
#include "core/model.h"

namespace quadrix {

/// What `render --colour-by` colours by. error, patch: per primitive (lit like any colour);
/// normal, depth: per pixel (unlit, the value itself).
enum class ColourMode { none, error, patch, normal, depth };

/// "none", "error", "patch", "normal", "depth". \throws InvalidInput naming the text.
ColourMode parse_colour_mode(std::string_view text);

/// A closed interval of values mapped onto the scalar map.
struct ValueRange {
  double lo = 0, hi = 1;
  /// (v − lo)/(hi − lo) clamped to [0, 1]; 0 when hi ≤ lo.
  double normalise(double v) const;
};

/// The scalar map (viridis: dark blue → green → yellow), t clamped to [0, 1]; its luminance
/// rises monotonically with t, so larger values read brighter under any fixed lighting.
Rgb scalar_colour(double t);
/// A categorical colour per id: hues spaced by the golden angle (neighbouring ids far apart).
Rgb patch_colour(std::size_t id);
/// A unit normal as a colour: (n + 1)/2 per channel (x red, y green, z blue).
Rgb normal_colour(const Eigen::Vector3f& n);

/// A copy of the model with every primitive coloured by its id (SLIM patches, then tetrahedron
/// patches, glyphs and implicit surfaces, numbered on across the kinds).
Model colour_by_patch(const Model& model);

/// A copy of the model with SLIM patch i coloured scalar_colour(range.normalise(values[i])), or
/// grey (128) where values[i] is empty. values: one per Model::slims.
/// \throws InvalidInput for a size mismatch.
Model colour_by_values(const Model& model, std::span<const std::optional<double>> values, const ValueRange& range);

/// Per-pixel colours (normal, depth) of the covered pixels, unlit, into image (others kept).
/// depth: eye depth per pixel; normal: world unit normal per pixel; range: depth range.
/// \throws InvalidInput for a mode other than normal or depth, or buffers of the wrong size.
void colour_pixels(Image8& image, ColourMode mode, std::span<const std::uint8_t> coverage, std::span<const float> depth,
                   std::span<const Eigen::Vector3f> normal, const ValueRange& range);

/// Range of the covered pixels' depths (lo = hi = 0 when none is covered).
ValueRange covered_depth_range(std::span<const std::uint8_t> coverage, std::span<const float> depth);

}  // namespace quadrix
