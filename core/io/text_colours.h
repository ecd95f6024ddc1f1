#pragma once
/// Vertex colours of the text mesh formats (OFF's COFF columns, OBJ's "v x y z r g b"): read as
/// written, then scaled to 8 bits by one rule for the whole file, so a colour column that is
/// damaged or written in an unusual range costs the colours, never the geometry.
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>

#include "core/io/text_reader.h"

namespace quadrix::io {

/// One vertex's colour as written: its first three values, whether any was written with a point
/// or an exponent, and whether every value read was a finite number.
struct TextColour {
  std::array<double, 3> value{};
  bool decimal = false;
  bool numbers = true;
};

/// The next tokens of the line as a colour: up to `most` values (r g b and an alpha, unused);
/// nullopt where fewer than three are left (OFF's colour-map index, OBJ's "v x y z w").
std::optional<TextColour> read_text_colour(TextReader& r, int most);

/// The colours as 8-bit sRGB, one per vertex, or none where not every vertex has one. Values are
/// 0-1 where every value of the file is at most 1 (a file printed with %g writes pure red as
/// "1 0 0"); else 0-255, except a vertex written with a point whose values are at most 1
/// (Geomview's rule for OFF). A value that is not a finite number, negative or above 255 drops
/// every colour of the file, with a warning naming `path` and the vertex (0-based).
std::vector<std::array<std::uint8_t, 3>> text_colours_rgb8(std::span<const std::optional<TextColour>> colours,
                                                           std::size_t vertices, const std::filesystem::path& path);

}  // namespace quadrix::io
