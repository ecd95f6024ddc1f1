#include "core/io/file.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>

#include <fmt/format.h>
#include <zlib.h>

#include "core/error.h"

namespace quadrix::io {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void too_big(std::string_view what, const ByteLimit& limit, std::string_view how) {
  throw FormatError(fmt::format("{}: {} more than the {} bytes {}", what, how, limit.bytes, limit.why));
}

void check_readable(const fs::path& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) throw IoError(fmt::format("{}: no such file", path.string()));
  if (fs::is_directory(st)) throw IoError(fmt::format("{}: is a folder, not a file", path.string()));
}

}  // namespace

ByteLimit inflate_limit(std::uint64_t compressed_bytes) {
  const std::uint64_t ratio_bound = compressed_bytes > kMaxInflated / kMaxInflateRatio
                                        ? kMaxInflated
                                        : std::max<std::uint64_t>(compressed_bytes * kMaxInflateRatio, 1 << 20);
  return {static_cast<std::size_t>(ratio_bound),
          fmt::format("allowed for {} compressed bytes ({} times their size, at least 1 MiB, at most {} GiB)",
                      compressed_bytes, kMaxInflateRatio, kMaxInflated >> 30)};
}

std::string read_file(const fs::path& path, const ByteLimit& limit) {
  const std::size_t max_bytes = limit.bytes;
  check_readable(path);
  std::error_code ec;
  const bool regular = fs::is_regular_file(path, ec);
  if (regular) {
    const auto size = fs::file_size(path, ec);
    if (!ec && size > max_bytes) too_big(path.string(), limit, fmt::format("holds {} bytes,", size));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  std::string out;
  if (regular && !ec) out.reserve(static_cast<std::size_t>(fs::file_size(path, ec)));
  std::array<char, 1 << 16> buf{};
  while (in) {
    in.read(buf.data(), buf.size());
    const auto n = static_cast<std::size_t>(in.gcount());
    if (n > max_bytes - out.size()) too_big(path.string(), limit, "holds");
    out.append(buf.data(), n);
  }
  if (in.bad()) throw IoError(fmt::format("{}: read failed: {}", path.string(), std::strerror(errno)));
  return out;
}

std::string read_file_prefix(const fs::path& path, std::size_t max_bytes) {
  check_readable(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  std::string out;  // grows with what the file holds, not with max_bytes (a 1 MiB header bound)
  std::array<char, 1 << 16> buf{};
  while (in && out.size() < max_bytes) {
    in.read(buf.data(), static_cast<std::streamsize>(std::min(buf.size(), max_bytes - out.size())));
    out.append(buf.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw IoError(fmt::format("{}: read failed: {}", path.string(), std::strerror(errno)));
  return out;
}

std::string read_gzip(const fs::path& path, const ByteLimit& limit, bool is_prefix) {
  const std::size_t max_bytes = limit.bytes;
  check_readable(path);
  gzFile f = gzopen(path.string().c_str(), "rb");
  if (!f) throw IoError(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  std::string out;
  std::array<char, 1 << 16> buf{};
  for (;;) {
    const int n = gzread(f, buf.data(), static_cast<unsigned>(buf.size()));
    if (n < 0) {
      int code = 0;
      const std::string msg = gzerror(f, &code);
      gzclose(f);
      throw FormatError(fmt::format("{}: corrupt gzip data after {} decompressed bytes: {}", path.string(), out.size(),
                                    echo(msg)));
    }
    if (n == 0) break;
    if (out.empty() && gzdirect(f)) {  // zlib passes other bytes through unchanged
      gzclose(f);
      throw FormatError(fmt::format("{}: not gzip data (no gzip magic at byte 0)", path.string()));
    }
    const auto k = static_cast<std::size_t>(n);
    if (k > max_bytes - out.size()) {
      gzclose(f);
      if (is_prefix) return out.append(buf.data(), max_bytes - out.size());
      too_big(path.string(), limit, "decompresses to");
    }
    out.append(buf.data(), k);
  }
  gzclose(f);
  return out;
}

std::string gunzip(std::string_view data, const std::string& what, const ByteLimit& limit) {
  const std::size_t max_bytes = limit.bytes;
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) throw FormatError(fmt::format("{}: cannot initialise zlib", what));
  std::string out;
  std::array<char, 1 << 16> buf{};
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(data.size());
  int rc = Z_OK;
  while (rc != Z_STREAM_END) {
    z.next_out = reinterpret_cast<Bytef*>(buf.data());
    z.avail_out = static_cast<uInt>(buf.size());
    rc = inflate(&z, Z_NO_FLUSH);
    if (rc != Z_OK && rc != Z_STREAM_END) {
      inflateEnd(&z);
      throw FormatError(fmt::format("{}: corrupt gzip data after {} decompressed bytes", what, out.size()));
    }
    const std::size_t n = buf.size() - z.avail_out;
    if (n > max_bytes - out.size()) {
      inflateEnd(&z);
      too_big(what, limit, "decompresses to");
    }
    out.append(buf.data(), n);
    if (rc == Z_OK && z.avail_in == 0 && z.avail_out != 0) {
      inflateEnd(&z);
      throw FormatError(fmt::format("{}: truncated gzip data after {} decompressed bytes", what, out.size()));
    }
  }
  const std::size_t left = z.avail_in;
  inflateEnd(&z);
  if (left > 0)
    throw FormatError(fmt::format("{}: {} bytes after the end of the gzip data (trailing data)", what, left));
  return out;
}

std::string echo(std::string_view token) {
  constexpr std::size_t kMax = 80;
  std::string out;
  std::size_t shown = 0, i = 0;
  for (; i < token.size() && shown < kMax; ++i, ++shown) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f)
      out.push_back(static_cast<char>(c));
    else
      out += fmt::format("\\x{:02x}", c);
  }
  if (i < token.size()) out += fmt::format("… ({} bytes)", token.size());
  return out;
}

std::string text_message(const fs::path& path, std::size_t line, std::size_t col, std::string_view what) {
  return fmt::format("{}:{}:{}: {}", path.string(), line, col, what);
}

std::string byte_message(const fs::path& path, std::uint64_t byte, std::string_view what) {
  return fmt::format("{}: byte {}: {}", path.string(), byte, what);
}

std::string lower_extension(const fs::path& path) {
  std::string e = path.extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

}  // namespace quadrix::io
