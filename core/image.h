#pragma once
/// Images: 8-bit RGBA for PNG (libpng) and float images for PFM (depth, normals).
#include <cstdint>
#include <filesystem>
#include <vector>

namespace quadrix {

/// 8-bit RGBA, row-major, row 0 at the top.
struct Image8 {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;  ///< width·height·4
  std::uint8_t* pixel(int x, int y) { return rgba.data() + 4 * (static_cast<std::size_t>(y) * width + x); }
  const std::uint8_t* pixel(int x, int y) const {
    return rgba.data() + 4 * (static_cast<std::size_t>(y) * width + x);
  }
};

/// Float image with 1 or 3 channels, row-major, row 0 at the top.
struct FloatImage {
  int width = 0, height = 0, channels = 1;
  std::vector<float> data;  ///< width·height·channels
};

/// Writes PNG (RGBA 8-bit) through a temporary file. \throws IoError.
void write_png(const Image8& image, const std::filesystem::path& path);
/// \throws FormatError naming the file for a corrupt or non-PNG file; IoError when unreadable.
Image8 read_png(const std::filesystem::path& path);

/// JPEG (libjpeg-turbo) settings.
struct JpegOptions {
  int quality = 92;  ///< 1..100
};
/// Writes baseline JPEG (RGB; alpha dropped, so callers refuse transparent images) through a
/// temporary file. \throws IoError; InvalidInput for an empty image or a quality outside 1..100.
void write_jpeg(const Image8& image, const std::filesystem::path& path, const JpegOptions& options = {});
/// Reads a JPEG as RGBA (alpha 255). \throws FormatError naming the file; IoError when unreadable.
Image8 read_jpeg(const std::filesystem::path& path);

/// Box filter: each output pixel the mean of a factor×factor block (alpha-weighted colour, so
/// transparent samples do not darken edges). Sizes must be multiples of factor.
/// \throws InvalidInput otherwise.
Image8 box_filter(const Image8& image, int factor);

/// Portable float map: "Pf" (1 channel) or "PF" (3), little-endian (scale −1), stored bottom row
/// first as the format requires; the in-memory image keeps row 0 at the top.
void write_pfm(const FloatImage& image, const std::filesystem::path& path);
/// \throws FormatError for a malformed header or truncated data.
FloatImage read_pfm(const std::filesystem::path& path);

}  // namespace quadrix
