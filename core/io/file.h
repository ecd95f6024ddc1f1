#pragma once
/// The I/O kit's byte layer: whole-file and bounded gzip reading, and the one message format
/// every reader uses: `FILE:LINE:COL: what` for text, `FILE: byte N: what` for binary data.
/// Tokens echoed in messages go through echo() (at most 80 printable characters).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <string_view>
#include <utility>

namespace quadrix::io {

inline constexpr std::size_t kNoLimit = std::numeric_limits<std::size_t>::max();

/// A bound on the bytes read or inflated, with where it comes from for the message
/// "FILE: holds more than the N bytes WHY" (a plain number converts: "… N bytes allowed").
struct ByteLimit {
  ByteLimit(std::size_t b = kNoLimit, std::string w = "allowed") : bytes(b), why(std::move(w)) {}
  std::size_t bytes;  // kNoLimit: none
  std::string why;    // e.g. kHeaderPromise
};
inline constexpr const char* kHeaderPromise = "its header promises";

/// The most a gzip file of compressed_bytes with no header promise (a molecule) may inflate to:
/// kMaxInflateRatio times its size, at least 1 MiB, at most kMaxInflated. Text compresses 3–8
/// times (PDB files 4–5); gzip's own ceiling is about 1032 (a bomb).
inline constexpr std::size_t kMaxInflateRatio = 32;
inline constexpr std::size_t kMaxInflated = std::size_t{4} << 30;  // 4 GiB
ByteLimit inflate_limit(std::uint64_t compressed_bytes);

/// The whole file as bytes, at most limit.bytes of them.
/// \throws IoError naming the path when it is missing, a folder, unopenable or unreadable;
///         FormatError when it holds more than the limit (checked before reading a regular
///         file, while reading anything else, e.g. /dev/zero).
std::string read_file(const std::filesystem::path& path, const ByteLimit& limit = {});

/// At most the first max_bytes of a file (for sniffing its format). \throws IoError as read_file.
std::string read_file_prefix(const std::filesystem::path& path, std::size_t max_bytes);

/// The decompressed content of a gzip file (one or more members), at most limit.bytes of it,
/// inflated 64 KiB at a time. With is_prefix the first limit.bytes are returned quietly;
/// otherwise more is a FormatError, raised as soon as the inflated bytes pass the bound (a small
/// bomb is never inflated whole). A file without a header promise takes inflate_limit(its size).
/// \throws IoError as read_file; FormatError for corrupt or truncated gzip data.
std::string read_gzip(const std::filesystem::path& path, const ByteLimit& limit, bool is_prefix = false);

/// Inflates one in-memory gzip or zlib stream; `what` names it in messages. Bounded as read_gzip;
/// bytes after the end of the stream are a FormatError (trailing data).
std::string gunzip(std::string_view data, const std::string& what, const ByteLimit& limit);

/// A token cut to 80 characters, control and non-ASCII bytes as \xNN, an ellipsis when cut.
std::string echo(std::string_view token);

/// `FILE:LINE:COL: what` (1-based line and column).
std::string text_message(const std::filesystem::path& path, std::size_t line, std::size_t col, std::string_view what);
/// `FILE: byte N: what`.
std::string byte_message(const std::filesystem::path& path, std::uint64_t byte, std::string_view what);

/// The extension in lower case, with its dot (".ply"); ".inr.gz" style double extensions are
/// not joined.
std::string lower_extension(const std::filesystem::path& path);

}  // namespace quadrix::io
