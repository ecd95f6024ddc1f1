#pragma once
/// The .qxm model format (DESIGN §4): a PLY profile with elements `slim`, `tet` and `glyph`,
/// written as binary little-endian PLY; read from binary little/big-endian or ASCII PLY of the
/// same profile, and from Kanai et al.'s `.slim2t` SLIM files.
///
/// Profile (all coordinates double, world units unless noted):
///   element slim:  x y z radius k_xx k_yy k_zz k_xy k_yz k_zx k_x k_y k_z k_1
///                  [clip_nx clip_ny clip_nz clip_d] [red green blue]
///                  (coefficients of g(u), u = (x − centre)/radius; clip plane in u)
///   element tet:   x0 y0 z0 x1 y1 z1 x2 y2 z2 x3 y3 z3 k_xx … k_1 [red green blue]
///                  (coefficients relative to the centroid of the four corners: y = x − centroid)
///   element glyph: kind(uchar: 0 sphere, 1 ellipsoid, 2 cylinder) x y z radius
///                  a0x a0y a0z a1x a1y a1z a2x a2y a2z [red green blue]
///   header comments: `comment quadrix-format 1`, then `comment KEY VALUE` per metadata entry
///   (producer, units, bbox, max_error, …).
///
/// Writer conventions: only non-empty elements are written, except that an entirely empty model
/// declares all three with count 0. Optional columns appear when any primitive of that kind has
/// them; a slim patch without a clip plane then gets an all-zero plane (a zero normal reads back
/// as "no clip"), and a primitive without a colour is written black (0 0 0) and reads back black.
/// Metadata keys containing whitespace are skipped, values are made single-line; `bbox` is always
/// recomputed from the model (`bbox x0 y0 z0 x1 y1 z1`, omitted for an empty model).
/// Reader: every comment `KEY VALUE` except `quadrix-format` becomes a metadata entry (so `bbox`
/// is in the metadata read back). Columns may be of any PLY numeric type; unknown extra
/// properties and elements are ignored (but still validated).
#include <filesystem>

#include "core/model.h"

namespace quadrix {

inline constexpr int kQxmFormatVersion = 1;

/// Reads a .qxm (any PLY encoding of the profile) or, by extension or magic, a .slim2t file.
/// Validates before it trusts: element counts against the file size before any allocation,
/// NaN/Inf, radii ≤ 0, degenerate tetrahedra, missing required properties, bad magic/format.
/// \throws FormatError naming the file, element, index and byte offset of the fault.
/// \throws IoError when the file cannot be opened.
Model read_model(const std::filesystem::path& path);

/// Kanai's .slim2t: int32 {±degree, #balls, #user values}, then per ball float32 centre(3),
/// coefficients(10, order xx yy zz xy yz zx x y z 1, local to the centre, unscaled),
/// support R, parent id (1-based, −1 root), user values. Only leaf balls are kept.
/// All little-endian; we read the parent id as int32 and user values as float32 (ignored);
/// |degree| ∈ {1, 2} (the sign is a flag), 0 ≤ #user values < 1024, parent ids in [−1, #balls]
/// (0 and −1 mean no parent); R must be finite and > 0.
/// \throws FormatError, IoError as read_model.
Model read_slim2t(const std::filesystem::path& path);

/// Writes binary little-endian .qxm through a temporary file renamed at the end.
/// The bounding box is written as the `bbox` metadata entry. Round trip is exact.
/// \throws InvalidInput when the model holds non-finite values; IoError on write failure.
void write_model(const Model& model, const std::filesystem::path& path);

}  // namespace quadrix
