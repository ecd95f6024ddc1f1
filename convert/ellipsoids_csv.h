#pragma once
/// Ellipsoid glyphs from a CSV table ([Toledo04] tensor glyphs): one ellipsoid per row,
/// `cx,cy,cz, a1x,a1y,a1z, a2x,a2y,a2z, a3x,a3y,a3z[, r,g,b]` — the centre, three semi-axis
/// vectors (world units) and an optional 0..255 colour. A first row none of whose cells is a
/// number is a header; `#` starts a comment; commas or blanks separate the values.
#include <filesystem>

#include "core/model.h"

namespace quadrix {

/// \throws FormatError naming FILE:LINE:COL for a short row, an empty cell, a value that is not
///         a finite number, a colour outside 0..255 or singular axes (no volume); IoError when
///         unreadable.
Model read_ellipsoids_csv(const std::filesystem::path& path);

}  // namespace quadrix
