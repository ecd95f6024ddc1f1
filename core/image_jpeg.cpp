#include <csetjmp>
#include <cstddef>
#include <cstdio>

#include <jpeglib.h>

#include <cstdlib>
#include <memory>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image.h"

namespace quadrix {
namespace {

// libjpeg reports errors through error_exit, which must not return: it longjmps back to the
// setjmp in encode/decode. Nothing with a destructor is created after the setjmp.
struct JpegError {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = "unknown libjpeg error";
};

void error_exit(j_common_ptr info) {
  auto* e = reinterpret_cast<JpegError*>(info->err);
  (*info->err->format_message)(info, e->message);
  std::longjmp(e->jump, 1);
}

void silent(j_common_ptr) {}

struct MemFree {
  void operator()(unsigned char* p) const { std::free(p); }
};

// Encodes RGB rows; false with the message on a libjpeg error.
bool encode(const Image8& image, int quality, const std::vector<std::uint8_t>& rgb, unsigned char** out,
            unsigned long* size, JpegError& err) {
  jpeg_compress_struct c{};
  c.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = error_exit;
  err.mgr.output_message = silent;
  if (setjmp(err.jump)) {
    jpeg_destroy_compress(&c);
    return false;
  }
  jpeg_create_compress(&c);
  jpeg_mem_dest(&c, out, size);
  c.image_width = static_cast<JDIMENSION>(image.width);
  c.image_height = static_cast<JDIMENSION>(image.height);
  c.input_components = 3;
  c.in_color_space = JCS_RGB;
  jpeg_set_defaults(&c);
  jpeg_set_quality(&c, quality, TRUE);
  jpeg_start_compress(&c, TRUE);
  while (c.next_scanline < c.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(rgb.data() + std::size_t(c.next_scanline) * image.width * 3);
    jpeg_write_scanlines(&c, &row, 1);
  }
  jpeg_finish_compress(&c);
  jpeg_destroy_compress(&c);
  return true;
}

bool decode(const std::string& bytes, Image8& image, std::vector<std::uint8_t>& rgb, JpegError& err) {
  jpeg_decompress_struct d{};
  d.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = error_exit;
  err.mgr.output_message = silent;
  if (setjmp(err.jump)) {
    jpeg_destroy_decompress(&d);
    return false;
  }
  jpeg_create_decompress(&d);
  jpeg_mem_src(&d, reinterpret_cast<const unsigned char*>(bytes.data()), static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&d, TRUE);
  d.out_color_space = JCS_RGB;
  jpeg_start_decompress(&d);
  image.width = static_cast<int>(d.output_width);
  image.height = static_cast<int>(d.output_height);
  rgb.resize(std::size_t(d.output_width) * d.output_height * 3);
  while (d.output_scanline < d.output_height) {
    JSAMPROW row = rgb.data() + std::size_t(d.output_scanline) * d.output_width * 3;
    jpeg_read_scanlines(&d, &row, 1);
  }
  jpeg_finish_decompress(&d);
  jpeg_destroy_decompress(&d);
  return true;
}

}  // namespace

void write_jpeg(const Image8& image, const std::filesystem::path& path, const JpegOptions& options) {
  if (image.width <= 0 || image.height <= 0) throw InvalidInput(fmt::format("{}: cannot write an empty image", path.string()));
  if (options.quality < 1 || options.quality > 100)
    throw InvalidInput(fmt::format("{}: JPEG quality {} is outside 1..100", path.string(), options.quality));
  std::vector<std::uint8_t> rgb(std::size_t(image.width) * image.height * 3);
  for (std::size_t i = 0, n = rgb.size() / 3; i < n; ++i)
    for (int k = 0; k < 3; ++k) rgb[3 * i + k] = image.rgba[4 * i + k];
  unsigned char* out = nullptr;
  unsigned long size = 0;
  JpegError err;
  const bool ok = encode(image, options.quality, rgb, &out, &size, err);
  const std::unique_ptr<unsigned char, MemFree> owned(out);
  if (!ok) throw IoError(fmt::format("{}: JPEG encoding failed: {}", path.string(), err.message));
  write_file_atomically(path, [&](std::ostream& s) { s.write(reinterpret_cast<const char*>(out), std::streamsize(size)); });
}

Image8 read_jpeg(const std::filesystem::path& path) {
  const std::string bytes = read_file(path);
  Image8 image;
  std::vector<std::uint8_t> rgb;
  JpegError err;
  if (!decode(bytes, image, rgb, err)) throw FormatError(fmt::format("{}: not a readable JPEG: {}", path.string(), err.message));
  image.rgba.resize(std::size_t(image.width) * image.height * 4);
  for (std::size_t i = 0, n = rgb.size() / 3; i < n; ++i) {
    for (int k = 0; k < 3; ++k) image.rgba[4 * i + k] = rgb[3 * i + k];
    image.rgba[4 * i + 3] = 255;
  }
  return image;
}

}  // namespace quadrix
