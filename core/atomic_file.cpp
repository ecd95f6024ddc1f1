#include "core/atomic_file.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>
#include <sstream>

#include "core/error.h"

namespace quadrix {

void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw IoError(fmt::format("{}: cannot write: folder '{}' does not exist", path.string(), dir.string()));
  std::random_device rd;
  const fs::path tmp = dir / fmt::format(".{}.tmp-{}-{:08x}", path.filename().string(), ::getpid(), rd());
  try {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError(fmt::format("{}: cannot create temporary file: {}", tmp.string(), std::strerror(errno)));
    write(out);
    out.flush();
    if (!out) throw IoError(fmt::format("{}: write failed: {}", path.string(), std::strerror(errno)));
    out.close();
    fs::rename(tmp, path, ec);
    if (ec) throw IoError(fmt::format("{}: cannot rename temporary file into place: {}", path.string(), ec.message()));
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

}  // namespace quadrix
