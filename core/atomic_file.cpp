#include "core/atomic_file.h"

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <mutex>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/error.h"

namespace quadrix {
namespace {

// The open transaction's pending renames (temporary file, target).
struct Pending {
  std::mutex mutex;
  bool open = false;
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> renames;
};
Pending& pending() {
  static Pending p;
  return p;
}

std::string temporary_prefix(const std::filesystem::path& path) { return fmt::format(".{}.tmp-", path.filename().string()); }

}  // namespace

OutputTransaction::OutputTransaction() {
  std::lock_guard lock(pending().mutex);
  if (pending().open) throw std::logic_error("OutputTransaction: another transaction is open");
  pending().open = true;
}

OutputTransaction::~OutputTransaction() {
  std::lock_guard lock(pending().mutex);
  std::error_code ec;
  for (const auto& [tmp, target] : pending().renames) std::filesystem::remove(tmp, ec);
  pending().renames.clear();
  pending().open = false;
}

void OutputTransaction::commit() {
  std::lock_guard lock(pending().mutex);
  auto renames = std::move(pending().renames);
  pending().renames.clear();
  std::error_code ec;
  for (std::size_t i = 0; i < renames.size(); ++i) {
    std::filesystem::rename(renames[i].first, renames[i].second, ec);
    if (ec) {
      for (std::size_t j = i; j < renames.size(); ++j) std::filesystem::remove(renames[j].first, ec);
      throw IoError(fmt::format("{}: cannot rename temporary file into place: {}", renames[i].second.string(),
                                ec.message()));
    }
  }
}

int remove_stale_temporaries(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  const std::string prefix = temporary_prefix(path);
  int removed = 0;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    // .NAME.tmp-PID-HEX: the writer's PID, then random hex.
    const std::string rest = name.substr(prefix.size());
    const auto dash = rest.find('-');
    if (dash == 0 || dash == std::string::npos || rest.find_first_not_of("0123456789") != dash) continue;
    if (dash > 9) continue;
    const long pid = std::stol(rest.substr(0, dash));
    if (pid <= 0 || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // still running
    std::error_code rm;
    if (fs::remove(it->path(), rm)) ++removed;
  }
  return removed;
}

void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw IoError(fmt::format("{}: cannot write: folder '{}' does not exist", path.string(), dir.string()));
  remove_stale_temporaries(path);
  std::random_device rd;
  const fs::path tmp = dir / fmt::format("{}{}-{:08x}", temporary_prefix(path), ::getpid(), rd());
  try {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError(fmt::format("{}: cannot create temporary file: {}", tmp.string(), std::strerror(errno)));
    write(out);
    out.flush();
    if (!out) throw IoError(fmt::format("{}: write failed: {}", path.string(), std::strerror(errno)));
    out.close();
    {
      std::lock_guard lock(pending().mutex);
      if (pending().open) {
        pending().renames.emplace_back(tmp, path);
        return;
      }
    }
    fs::rename(tmp, path, ec);
    if (ec) throw IoError(fmt::format("{}: cannot rename temporary file into place: {}", path.string(), ec.message()));
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

void check_output_folder(const std::filesystem::path& path) {
  const std::filesystem::path folder = path.parent_path();
  if (folder.empty()) return;
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec))
    throw IoError(fmt::format("{}: cannot write here: {} is not an existing folder", path.string(), folder.string()));
}

}  // namespace quadrix
