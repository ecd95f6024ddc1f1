#pragma once
/// The .qxm model format (DESIGN §4, docs/qxm-format.md): a PLY profile with elements `slim`,
/// `slim_node`, `tet` and `glyph`, written as binary little-endian PLY; read from binary
/// little/big-endian or ASCII PLY of the same profile, and from Kanai et al.'s `.slim2t` files.
///
/// Profile, revision 4 (world units unless noted):
///   element slim:      x y z radius k_xx k_yy k_zz k_xy k_yz k_zx k_x k_y k_z k_1
///                      [clip_nx clip_ny clip_nz clip_d [clip2_* [clip3_* [clip4_*]]]]
///                      [red green blue] [measured_error] [parent error]
///                      (coefficients of g(u), u = (x − centre)/radius; clip planes in u, the
///                      patch keeps what every one keeps; clip2_* to clip4_* new in revision 4)
///   element slim_node: as slim, parent and error required: the hierarchy's balls that are not
///                      drawn (Model::slim_hierarchy.others); only with slim's parent/error
///   element tet:       x0 y0 z0 x1 y1 z1 x2 y2 z2 x3 y3 z3 k_xx … k_1 [red green blue]
///                      (coefficients relative to the centroid of the four corners: y = x − centroid)
///   element glyph:     kind(uchar: 0 sphere, 1 ellipsoid, 2 cylinder) x y z radius
///                      a0x a0y a0z a1x a1y a1z a2x a2y a2z [red green blue]
///   parent (int32): ball id of the parent, −1 for a root; ids count the slim rows, then the
///   slim_node rows. error: the ball's fitting error, ≥ 0. The links form a forest.
///   header comments: `comment quadrix-format 4`, `comment quadrix-encoding compact|double`,
///   `comment quadrix-origin X Y Z` (positions — slim/slim_node x y z, tet corners, glyph
///   x y z — are stored relative to it; 0 0 0 when absent), then `comment KEY VALUE` per
///   metadata entry (producer, units, bbox, max_error, …). Revisions 1 to 3 are still read.
///
/// Encodings (both read; the types come from the PLY header):
///   double:  every coordinate and coefficient float64, origin 0 (lossless).
///   compact: float32 for every coordinate, coefficient, radius and error; positions relative
///            to a float64 origin (the bounding-box centre), so a model far from the world
///            origin keeps its accuracy. A slim row's required part is 56 bytes, a tet row's 88.
///
/// Writer conventions: only non-empty elements are written, except that an entirely empty model
/// declares slim, tet and glyph with count 0. Optional columns appear when any primitive of that
/// element has them; a slim patch without a clip plane then gets an all-zero plane (a zero normal
/// reads back as "no clip"), and a primitive without a colour is written black (0 0 0) and reads
/// back black. parent/error are written on slim and slim_node when the model has a hierarchy.
/// Metadata keys containing whitespace are skipped, values are made single-line; `bbox` is always
/// recomputed from the model (`bbox x0 y0 z0 x1 y1 z1`, omitted for an empty model).
/// Reader: every comment `KEY VALUE` except the `quadrix-*` ones becomes a metadata entry (so
/// `bbox` is in the metadata read back). Columns may be of any PLY numeric type (parent must hold
/// an integer); unknown extra properties and elements are ignored (but still validated).
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include "core/model.h"

namespace quadrix {

inline constexpr int kQxmFormatVersion = 4;

/// Reads a .qxm (any PLY encoding of the profile) or, by extension or magic, a .slim2t file.
/// Validates before it trusts: element counts against the file size before any allocation,
/// NaN/Inf, radii ≤ 0, degenerate tetrahedra, missing required properties, bad magic/format.
/// \throws FormatError naming the file, element, index and byte offset of the fault.
/// \throws IoError when the file cannot be opened.
Model read_model(const std::filesystem::path& path);

/// Kanai's .slim2t: int32 {±degree, #balls, #user values}, then per ball only float32:
/// centre(3), coefficients(10, order xx yy zz xy yz zx x y z 1, local to the centre, unscaled),
/// support R, parent id (an integer-valued float, 1-based, −1 for a root), user values (the first
/// is the ball's fitting error). All little-endian; |degree| ∈ {1, 2}, 0 ≤ #user values < 1024.
/// Refused: trailing bytes after the declared balls, R not finite or ≤ 0, a parent id that is not
/// an integer in {−1} ∪ [1, #balls] or is the ball itself, links that are not a forest, a
/// negative error. The leaves become Model::slims (in file order); the whole tree, interior
/// balls included, goes to Model::slim_hierarchy (leaves first, then interior balls in file
/// order; errors 0 when the file has no user values).
/// A negative degree marks an unoriented file: every ball is flipped when most leaf gradients
/// point towards the leaves' centroid, and each interior ball is flipped to agree with the
/// majority of the leaves below it inside its support; the account is in metadata
/// `slim2t_orientation`. Leaves keep their relative signs.
/// \throws FormatError, IoError as read_model.
Model read_slim2t(const std::filesystem::path& path);

/// How write_model stores numbers (see the profile above).
enum class ModelEncoding {
  compact,  ///< float32, positions relative to a float64 origin in the header
  full,     ///< float64 everywhere: lossless (`double` on the command line)
};

struct WriteModelOptions {
  ModelEncoding encoding = ModelEncoding::compact;
  /// Compact only: when a primitive would not survive float32 (a value out of float range, a
  /// quadric whose coefficients all underflow, a radius rounded to 0, a position moved by more
  /// than 1/1000 of its primitive's size, more than 1 in 1000 tetrahedra turning flat), write
  /// the full encoding instead (true), or throw (false).
  bool fallback_to_full = true;
};

struct WriteModelResult {
  ModelEncoding encoding = ModelEncoding::compact;  ///< the encoding written
  std::size_t bytes = 0;                            ///< the file's size
  std::string fallback;  ///< why compact fell back to full (the first primitive at fault), or empty
  /// Compact: tetrahedra left out because float32 turns them flat or inside out (slivers thinner
  /// than the rounding of their corners; more than 1 in 1000 of them makes it fall back instead).
  std::size_t dropped_tets = 0;
};

/// The name used on the command line and in the header: "compact" or "double".
std::string_view encoding_name(ModelEncoding encoding);

/// Writes binary little-endian .qxm (revision kQxmFormatVersion) through a temporary file renamed
/// at the end. The bounding box is written as the `bbox` metadata entry. The full encoding round
/// trips exactly; compact moves each position by at most 2⁻²⁴ of its distance from the origin per
/// axis and each coefficient, radius and error by at most 2⁻²⁴ relative (float32 rounding; a
/// tetrahedron's quadric is re-expressed about its rounded corners' centroid first).
/// \throws InvalidInput when the model holds non-finite values, or (compact without fallback)
///         a primitive does not survive float32, naming it; IoError on write failure.
WriteModelResult write_model(const Model& model, const std::filesystem::path& path,
                             const WriteModelOptions& options = {});

}  // namespace quadrix
