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

namespace quadrix::io {

inline constexpr std::size_t kNoLimit = std::numeric_limits<std::size_t>::max();

/// The whole file as bytes, at most max_bytes of them.
/// \throws IoError naming the path when it is missing, a folder, unopenable or unreadable;
///         FormatError when it holds more than max_bytes (checked before reading a regular
///         file, while reading anything else, e.g. /dev/zero).
std::string read_file(const std::filesystem::path& path, std::size_t max_bytes = kNoLimit);

/// At most the first max_bytes of a file (for sniffing its format). \throws IoError as read_file.
std::string read_file_prefix(const std::filesystem::path& path, std::size_t max_bytes);

/// The decompressed content of a gzip file (one or more members), at most max_bytes of it.
/// With is_prefix the first max_bytes are returned quietly; otherwise more is a FormatError,
/// raised as soon as the inflated bytes pass the bound (a small bomb is never inflated whole).
/// \throws IoError as read_file; FormatError for corrupt or truncated gzip data.
std::string read_gzip(const std::filesystem::path& path, std::size_t max_bytes, bool is_prefix = false);

/// Inflates one in-memory gzip or zlib stream; `what` names it in messages. Bounded as read_gzip;
/// bytes after the end of the stream are a FormatError (trailing data).
std::string gunzip(std::string_view data, const std::string& what, std::size_t max_bytes);

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
