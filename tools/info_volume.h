#pragma once
// quadrix info VOLUME: what a volume holds and which iso-values suit it (convert/volume_stats.h).
#include <optional>
#include <string>

#include "convert/volume.h"
#include "tools/cli.h"

namespace quadrix::cli {

/// The raw-volume options of `info` and `convert volume`.
struct RawVolumeArgs {
  std::string dims, type, spacing;
  bool big_endian = false;
  std::size_t header_bytes = 0;
};

/// True when the file names a volume by extension (.nhdr, .nrrd, .inr, .inr.gz) or raw options are given.
bool is_volume_file(const std::string& path, const RawVolumeArgs& raw);

/// The raw layout the options describe (none without --dims and --type). \throws CLI::ValidationError.
std::optional<RawVolumeLayout> raw_layout(const RawVolumeArgs& raw);

/// Prints the volume's statistics and suggested iso-values (JSON with json), into the report too.
ExitCode run_info_volume(const std::string& path, const RawVolumeArgs& raw, bool json, Report& report);

}  // namespace quadrix::cli
