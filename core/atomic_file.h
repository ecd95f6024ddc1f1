#pragma once
/// Outputs are written to a temporary file beside the target (`.NAME.tmp-PID-HEX`) and renamed at
/// the end, so a crash or an error never leaves a half-written file behind. While an
/// OutputTransaction is open, the renames wait for its commit: a command's outputs appear
/// together or not at all. Temporary files of the same target left by killed processes (their PID
/// no longer runs) are removed by the next write to that target.
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

/// Whether path can be written as far as its folder goes: the folder exists and is a folder.
/// \throws IoError naming the path and its folder otherwise.
void check_output_folder(const std::filesystem::path& path);

/// Groups the writes made while it is open (by any thread) so that they land together: commit()
/// renames every temporary file into place; destruction without commit removes them all and
/// leaves every target untouched. One open transaction at a time.
class OutputTransaction {
public:
  /// \throws std::logic_error when another transaction is open.
  OutputTransaction();
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;
  /// Renames the temporary files onto their targets, in the order written.
  /// \throws IoError naming the target that could not be renamed (the rest are removed).
  void commit();
};

/// Removes `.NAME.tmp-PID-*` files beside path whose PID is not a running process; returns how
/// many were removed. write_file_atomically calls it before each write.
int remove_stale_temporaries(const std::filesystem::path& path);

/// Whole-file reading lives in the I/O kit; kept here for callers of quadrix::read_file.
using io::read_file;

}  // namespace quadrix
