#pragma once
/// Outputs are written to a temporary file beside the target and renamed at the end,
/// so a crash or an error never leaves a half-written file behind.
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "core/io/file.h"

namespace quadrix {

/// Calls write(stream) on a temporary file in path's folder, flushes, checks the stream and
/// renames it onto path. On any failure the temporary file is removed and the target untouched.
/// \throws IoError naming the path when the file cannot be created, written or renamed;
///         rethrows whatever write throws.
void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

/// Whole-file reading lives in the I/O kit; kept here for callers of quadrix::read_file.
using io::read_file;

}  // namespace quadrix
