#include "core/image.h"

#include <png.h>

#include <fmt/format.h>

#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/io/file.h"
#include "core/log.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;

constexpr int max_dimension = 65536;

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  const std::string bytes = io::read_file(path);
  return {bytes.begin(), bytes.end()};
}

// ---------------------------------------------------------------------------------------------
// libpng. Its errors longjmp back to the setjmp in decode_png/encode_png. Those functions create
// no C++ object after their setjmp: everything with a destructor (the output vectors, the png
// struct guard) lives before it or in the caller, so the jump never skips a destructor, and the
// state that changes after setjmp lives behind pointers, never in the setjmp frame's locals.

struct PngContext {
  const std::uint8_t* data = nullptr;  ///< reading: the whole file in memory
  std::size_t size = 0, pos = 0;
  std::vector<std::uint8_t>* out = nullptr;  ///< writing: the encoded bytes
  char message[256] = "unknown libpng error";
};

[[noreturn]] void png_error_fn(png_structp png, png_const_charp msg) {
  auto* ctx = static_cast<PngContext*>(png_get_error_ptr(png));
  std::snprintf(ctx->message, sizeof ctx->message, "%s", msg ? msg : "libpng error");
  png_longjmp(png, 1);
}

void png_warning_fn(png_structp, png_const_charp msg) { log::debug("libpng: {}", msg ? msg : ""); }

void png_read_fn(png_structp png, png_bytep dst, png_size_t n) {
  auto* ctx = static_cast<PngContext*>(png_get_io_ptr(png));
  if (n > ctx->size - ctx->pos) png_error(png, "unexpected end of file (truncated PNG)");
  std::memcpy(dst, ctx->data + ctx->pos, n);
  ctx->pos += n;
}

void png_write_fn(png_structp png, png_bytep src, png_size_t n) {
  auto* ctx = static_cast<PngContext*>(png_get_io_ptr(png));
  bool failed = false;
  try {
    ctx->out->insert(ctx->out->end(), src, src + n);
  } catch (...) {  // never let an exception unwind through libpng's C frames
    failed = true;
  }
  if (failed) png_error(png, "out of memory while encoding");
}

void png_flush_fn(png_structp) {}

struct PngReadGuard {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~PngReadGuard() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

struct PngWriteGuard {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~PngWriteGuard() { png_destroy_write_struct(&png, info ? &info : nullptr); }
};

/// Decodes into image; returns nullptr on success or libpng's message (in ctx) on failure.
const char* decode_png(PngContext& ctx, Image8& image, std::vector<png_bytep>& rows) {
  PngReadGuard guard;
  guard.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &ctx, png_error_fn, png_warning_fn);
  if (!guard.png) return "cannot create libpng read struct";
  guard.info = png_create_info_struct(guard.png);
  if (!guard.info) return "cannot create libpng info struct";
  if (setjmp(png_jmpbuf(guard.png))) return ctx.message;

  png_set_read_fn(guard.png, &ctx, png_read_fn);
  png_set_user_limits(guard.png, max_dimension, max_dimension);
  png_read_info(guard.png, guard.info);
  png_set_expand(guard.png);  // palette → RGB, gray < 8 bits → 8 bits, tRNS → alpha
#ifdef PNG_READ_SCALE_16_TO_8_SUPPORTED
  png_set_scale_16(guard.png);  // like png_set_strip_16, but rounds instead of truncating
#else
  png_set_strip_16(guard.png);
#endif
  png_set_gray_to_rgb(guard.png);
  png_set_add_alpha(guard.png, 0xff, PNG_FILLER_AFTER);
  png_set_interlace_handling(guard.png);
  png_read_update_info(guard.png, guard.info);

  const png_uint_32 width = png_get_image_width(guard.png, guard.info);
  const png_uint_32 height = png_get_image_height(guard.png, guard.info);
  if (png_get_rowbytes(guard.png, guard.info) != static_cast<png_size_t>(width) * 4)
    png_error(guard.png, "unexpected row size after conversion to RGBA8");
  image.width = static_cast<int>(width);
  image.height = static_cast<int>(height);
  image.rgba.resize(static_cast<std::size_t>(width) * height * 4);  // may throw bad_alloc: no jump involved
  rows.resize(height);
  for (png_uint_32 y = 0; y < height; ++y) rows[y] = image.rgba.data() + static_cast<std::size_t>(y) * width * 4;
  png_read_image(guard.png, rows.data());
  png_read_end(guard.png, nullptr);
  return nullptr;
}

const char* encode_png(PngContext& ctx, const Image8& image, std::vector<png_bytep>& rows) {
  PngWriteGuard guard;
  guard.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &ctx, png_error_fn, png_warning_fn);
  if (!guard.png) return "cannot create libpng write struct";
  guard.info = png_create_info_struct(guard.png);
  if (!guard.info) return "cannot create libpng info struct";
  if (setjmp(png_jmpbuf(guard.png))) return ctx.message;

  png_set_write_fn(guard.png, &ctx, png_write_fn, png_flush_fn);
  png_set_IHDR(guard.png, guard.info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height), 8,
               PNG_COLOR_TYPE_RGB_ALPHA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(guard.png, guard.info);
  png_write_image(guard.png, rows.data());
  png_write_end(guard.png, nullptr);
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// PFM

std::uint32_t byteswap32(std::uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

bool is_space(std::uint8_t c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

}  // namespace

void write_png(const Image8& image, const std::filesystem::path& path) {
  if (image.width <= 0 || image.height <= 0 || image.width > max_dimension || image.height > max_dimension)
    throw InvalidInput(fmt::format("{}: cannot write a {}×{} PNG", path.string(), image.width, image.height));
  if (image.rgba.size() != static_cast<std::size_t>(image.width) * image.height * 4)
    throw InvalidInput(fmt::format("{}: image has {} bytes, expected {}×{}×4", path.string(), image.rgba.size(),
                                   image.width, image.height));
  std::vector<std::uint8_t> encoded;
  encoded.reserve(image.rgba.size() / 2 + 1024);
  std::vector<png_bytep> rows(static_cast<std::size_t>(image.height));
  for (int y = 0; y < image.height; ++y)  // libpng takes non-const row pointers but does not write through them
    rows[y] = const_cast<png_bytep>(image.pixel(0, y));
  PngContext ctx;
  ctx.out = &encoded;
  if (const char* error = encode_png(ctx, image, rows))
    throw IoError(fmt::format("{}: PNG encoding failed: {}", path.string(), error));
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(encoded.data()), static_cast<std::streamsize>(encoded.size()));
  });
}

Image8 read_png(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0)
    throw FormatError(fmt::format("{}: not a PNG file (bad signature)", path.string()));
  Image8 image;
  std::vector<png_bytep> rows;
  PngContext ctx;
  ctx.data = bytes.data();
  ctx.size = bytes.size();
  if (const char* error = decode_png(ctx, image, rows))
    throw FormatError(fmt::format("{}: corrupt PNG: {}", path.string(), error));
  return image;
}

void write_pfm(const FloatImage& image, const std::filesystem::path& path) {
  if (image.channels != 1 && image.channels != 3)
    throw InvalidInput(fmt::format("{}: PFM needs 1 or 3 channels, image has {}", path.string(), image.channels));
  if (image.width <= 0 || image.height <= 0 || image.width > max_dimension || image.height > max_dimension)
    throw InvalidInput(fmt::format("{}: cannot write a {}×{} PFM", path.string(), image.width, image.height));
  const std::size_t row = static_cast<std::size_t>(image.width) * image.channels;
  if (image.data.size() != row * image.height)
    throw InvalidInput(fmt::format("{}: image has {} floats, expected {}×{}×{}", path.string(), image.data.size(),
                                   image.width, image.height, image.channels));
  write_file_atomically(path, [&](std::ostream& out) {
    const std::string header = fmt::format("{}\n{} {}\n-1\n", image.channels == 3 ? "PF" : "Pf", image.width, image.height);
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    std::vector<std::uint32_t> line(row);
    for (int y = image.height - 1; y >= 0; --y) {  // bottom row first on disk
      std::memcpy(line.data(), image.data.data() + static_cast<std::size_t>(y) * row, row * sizeof(float));
      if constexpr (std::endian::native == std::endian::big)
        for (auto& v : line) v = byteswap32(v);
      out.write(reinterpret_cast<const char*>(line.data()), static_cast<std::streamsize>(row * sizeof(float)));
    }
  });
}

FloatImage read_pfm(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  const std::string name = path.string();
  std::size_t pos = 0;
  // Header: magic, width, height, scale, separated by whitespace, then exactly one whitespace byte.
  auto token = [&](const char* what) {
    while (pos < bytes.size() && is_space(bytes[pos])) ++pos;
    const std::size_t begin = pos;
    while (pos < bytes.size() && !is_space(bytes[pos]) && pos - begin < 64) ++pos;
    if (pos == begin || pos >= bytes.size() || !is_space(bytes[pos]))
      throw FormatError(fmt::format("{}: malformed PFM header: cannot read the {} (byte offset {})", name, what, begin));
    return std::string_view(reinterpret_cast<const char*>(bytes.data()) + begin, pos - begin);
  };
  FloatImage image;
  const std::string_view magic = token("magic 'PF' or 'Pf'");
  if (magic == "PF")
    image.channels = 3;
  else if (magic == "Pf")
    image.channels = 1;
  else
    throw FormatError(fmt::format("{}: not a PFM file (magic '{}', expected 'PF' or 'Pf')", name, magic.substr(0, 8)));
  auto dimension = [&](const char* what) {
    const std::string_view tok = token(what);
    int v = 0;
    const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (ec != std::errc() || ptr != tok.data() + tok.size() || v <= 0 || v > max_dimension)
      throw FormatError(fmt::format("{}: PFM {} '{}' is not an integer in [1, {}]", name, what, tok, max_dimension));
    return v;
  };
  image.width = dimension("width");
  image.height = dimension("height");
  const std::string_view scale_tok = token("scale");
  double scale = 0;
  const auto [ptr, ec] = std::from_chars(scale_tok.data(), scale_tok.data() + scale_tok.size(), scale);
  if (ec != std::errc() || ptr != scale_tok.data() + scale_tok.size() || scale == 0 || !std::isfinite(scale))
    throw FormatError(fmt::format("{}: PFM scale '{}' is not a non-zero number", name, scale_tok));
  ++pos;  // the single whitespace byte that ends the header
  const bool file_little = scale < 0;

  const std::size_t row = static_cast<std::size_t>(image.width) * image.channels;
  const std::size_t expected = row * image.height * sizeof(float);
  const std::size_t available = bytes.size() - pos;
  if (available < expected)
    throw FormatError(fmt::format("{}: truncated PFM: {}×{}×{} floats need {} bytes after the header (offset {}), "
                                  "found {}",
                                  name, image.width, image.height, image.channels, expected, pos, available));
  if (available > expected)
    log::warn("{}: PFM has {} bytes after the pixel data; ignored", name, available - expected);

  image.data.resize(row * image.height);
  const bool swap = file_little != (std::endian::native == std::endian::little);
  for (int y = 0; y < image.height; ++y) {  // disk row y is image row height-1-y
    float* dst = image.data.data() + static_cast<std::size_t>(image.height - 1 - y) * row;
    std::memcpy(dst, bytes.data() + pos + static_cast<std::size_t>(y) * row * sizeof(float), row * sizeof(float));
    if (swap)
      for (std::size_t i = 0; i < row; ++i) {
        std::uint32_t v;
        std::memcpy(&v, dst + i, 4);
        v = byteswap32(v);
        std::memcpy(dst + i, &v, 4);
      }
  }
  return image;
}

Image8 box_filter(const Image8& image, int factor) {
  if (factor < 1 || image.width % factor || image.height % factor)
    throw InvalidInput(fmt::format("box filter: {}x{} is not a multiple of {}", image.width, image.height, factor));
  if (factor == 1) return image;
  Image8 out{image.width / factor, image.height / factor, {}};
  out.rgba.resize(std::size_t(out.width) * out.height * 4);
  const unsigned n = unsigned(factor * factor);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      unsigned sum[3] = {0, 0, 0}, alpha = 0;
      for (int dy = 0; dy < factor; ++dy)
        for (int dx = 0; dx < factor; ++dx) {
          const std::uint8_t* p = image.pixel(x * factor + dx, y * factor + dy);
          for (int k = 0; k < 3; ++k) sum[k] += unsigned(p[k]) * p[3];
          alpha += p[3];
        }
      std::uint8_t* q = out.pixel(x, y);
      for (int k = 0; k < 3; ++k) q[k] = alpha ? std::uint8_t((sum[k] + alpha / 2) / alpha) : 0;
      q[3] = std::uint8_t((alpha + n / 2) / n);
    }
  return out;
}

}  // namespace quadrix
