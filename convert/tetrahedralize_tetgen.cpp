// TetGen 1.5 behind validation and a child process (convert/tetrahedralize.h).
#include "convert/tetrahedralize.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <sys/wait.h>
#include <tetgen.h>
#include <unistd.h>

#include "core/error.h"

namespace quadrix {
namespace {

using Eigen::Vector3d;

// The distinct points of a cell (merged within tol) and, per kept point, its input index.
std::vector<int> distinct(const std::vector<Vector3d>& p, double tol) {
  std::vector<int> keep;
  for (int i = 0; i < static_cast<int>(p.size()); ++i) {
    bool dup = false;
    for (const int k : keep) dup = dup || (p[i] - p[k]).norm() <= tol;
    if (!dup) keep.push_back(i);
  }
  return keep;
}

double orient(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a);
}

// Child side: TetGen on one cell. Returns false when TetGen reports an error.
bool run_tetgen(const std::vector<Vector3d>& p, const std::vector<int>& keep, std::vector<TetIndices>& out) {
  tetgenio in, result;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(keep.size());
  in.pointlist = new REAL[3 * keep.size()];
  for (std::size_t i = 0; i < keep.size(); ++i)
    for (int a = 0; a < 3; ++a) in.pointlist[3 * i + a] = p[keep[i]][a];
  try {
    char switches[] = "Qz";  // quiet, zero-based; no 'p': the Delaunay tetrahedralisation of the hull
    tetrahedralize(switches, &in, &result);
  } catch (...) {
    return false;
  }
  for (int t = 0; t < result.numberoftetrahedra; ++t) {
    TetIndices tet;
    for (int a = 0; a < 4; ++a) {
      const int v = result.tetrahedronlist[t * result.numberofcorners + a];
      if (v < 0 || v >= static_cast<int>(keep.size())) return false;
      tet[a] = keep[v];
    }
    if (orient(p[tet[0]], p[tet[1]], p[tet[2]], p[tet[3]]) < 0) std::swap(tet[1], tet[2]);
    out.push_back(tet);
  }
  return true;
}

bool write_all(int fd, const void* data, std::size_t n) {
  const char* c = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, c, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    c += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

struct Batch {
  std::size_t done = 0;                      // cells [first, done) succeeded
  std::vector<std::vector<TetIndices>> tets;  // their tetrahedra
  std::string why;                           // why cell `done` failed
};

// Runs TetGen on cells[first..] in a child process until the end or the first failure.
Batch run_batch(std::span<const std::vector<Vector3d>> cells, const std::vector<std::vector<int>>& keep,
                std::size_t first, const std::string& source) {
  int fds[2];
  if (::pipe(fds) != 0) throw SolverError(fmt::format("{}: cannot create a pipe for TetGen: {}", source, std::strerror(errno)));
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw SolverError(fmt::format("{}: cannot fork the TetGen process: {}", source, std::strerror(errno)));
  }
  if (pid == 0) {
    // Child: one record per cell: int32 cell, int32 count (−1: TetGen error), count × 4 int32.
    ::close(fds[0]);
    std::vector<TetIndices> tets;
    for (std::size_t c = first; c < cells.size(); ++c) {
      tets.clear();
      const bool ok = run_tetgen(cells[c], keep[c], tets) && !tets.empty();
      const std::int32_t head[2] = {static_cast<std::int32_t>(c), ok ? static_cast<std::int32_t>(tets.size()) : -1};
      if (!write_all(fds[1], head, sizeof head)) ::_exit(3);
      if (!ok) ::_exit(2);
      if (!write_all(fds[1], tets.data(), tets.size() * sizeof(TetIndices))) ::_exit(3);
    }
    ::close(fds[1]);
    ::_exit(0);
  }
  ::close(fds[1]);
  std::vector<char> buffer;
  std::array<char, 1 << 16> chunk{};
  for (;;) {
    const ssize_t n = ::read(fds[0], chunk.data(), chunk.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    buffer.insert(buffer.end(), chunk.data(), chunk.data() + n);
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  Batch b;
  b.done = first;
  std::size_t pos = 0;
  bool tetgen_error = false;
  while (pos + 8 <= buffer.size()) {
    std::int32_t head[2];
    std::memcpy(head, buffer.data() + pos, 8);
    if (head[0] != static_cast<std::int32_t>(b.done)) break;
    if (head[1] < 0) {
      tetgen_error = true;
      break;
    }
    const std::size_t bytes = static_cast<std::size_t>(head[1]) * sizeof(TetIndices);
    if (pos + 8 + bytes > buffer.size()) break;
    std::vector<TetIndices> t(static_cast<std::size_t>(head[1]));
    std::memcpy(t.data(), buffer.data() + pos + 8, bytes);
    b.tets.push_back(std::move(t));
    pos += 8 + bytes;
    ++b.done;
  }
  if (b.done < cells.size())
    b.why = tetgen_error             ? "TetGen reported an error or no tetrahedra"
            : WIFSIGNALED(status)    ? fmt::format("TetGen crashed (signal {})", WTERMSIG(status))
            : WIFEXITED(status)      ? fmt::format("the TetGen process exited with status {}", WEXITSTATUS(status))
                                     : std::string("the TetGen process failed");
  return b;
}

}  // namespace

Tetrahedralization tetrahedralize_convex_cells(std::span<const std::vector<Vector3d>> cells,
                                               const TetrahedralizeOptions& options) {
  // Validate everything before TetGen sees any of it.
  std::vector<std::vector<int>> keep(cells.size());
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const auto& p = cells[c];
    for (std::size_t i = 0; i < p.size(); ++i)
      if (!p[i].allFinite())
        throw InvalidInput(fmt::format("{}: cell {}: point {} is not finite", options.source, c, i));
    double diam = 0;
    for (std::size_t i = 0; i < p.size(); ++i)
      for (std::size_t j = i + 1; j < p.size(); ++j) diam = std::max(diam, (p[i] - p[j]).norm());
    keep[c] = distinct(p, options.merge_tolerance * diam);
    if (keep[c].size() < 4)
      throw InvalidInput(fmt::format("{}: cell {} has {} distinct points; a tetrahedralisation needs 4",
                                     options.source, c, keep[c].size()));
    // Volume test in O(n): a = farthest from k0, b = farthest from the line k0–a, then the
    // largest |orientation| with a fourth point.
    const auto& k = keep[c];
    const Vector3d& o = p[k[0]];
    std::size_t a = 1, b = 1;
    for (std::size_t i = 1; i < k.size(); ++i)
      if ((p[k[i]] - o).squaredNorm() > (p[k[a]] - o).squaredNorm()) a = i;
    const Vector3d u = (p[k[a]] - o).normalized();
    const auto off_line = [&](std::size_t i) { const Vector3d d = p[k[i]] - o; return (d - d.dot(u) * u).squaredNorm(); };
    for (std::size_t i = 1; i < k.size(); ++i)
      if (off_line(i) > off_line(b)) b = i;
    double vol = 0;
    for (std::size_t i = 1; i < k.size(); ++i) vol = std::max(vol, std::abs(orient(o, p[k[a]], p[k[b]], p[k[i]])));
    if (vol <= options.min_relative_volume * diam * diam * diam)
      throw InvalidInput(fmt::format("{}: cell {} is flat (all {} points coplanar)", options.source, c, k.size()));
  }

  Tetrahedralization out;
  out.cells.resize(cells.size());
  std::size_t next = 0;
  while (next < cells.size()) {
    const Batch batch = run_batch(cells, keep, next, options.source);
    for (std::size_t c = next; c < batch.done; ++c) out.cells[c] = std::move(batch.tets[c - next]);
    if (batch.done == cells.size()) break;
    // TetGen failed or crashed on cell batch.done.
    const std::string why = fmt::format("{}: {} on cell {} ({} points)", options.source, batch.why, batch.done,
                                        cells[batch.done].size());
    if (!options.skip_failed) throw SolverError(why + fmt::format("; {} of {} cells were done", batch.done, cells.size()));
    if (out.failed.empty()) out.first_failure = why;
    out.failed.push_back(batch.done);
    next = batch.done + 1;
  }
  return out;
}

}  // namespace quadrix
