// TetGen 1.5 behind validation and a child process (convert/tetrahedralize.h).
#include "convert/tetrahedralize.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tetgen.h>

#include "core/child_process.h"
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

struct Batch {
  std::size_t done = 0;                      // cells [first, done) succeeded
  std::vector<std::vector<TetIndices>> tets;  // their tetrahedra
  std::string why;                           // why cell `done` failed
};

// Runs TetGen on cells[first..] in a child process until the end or the first failure.
Batch run_batch(std::span<const std::vector<Vector3d>> cells, const std::vector<std::vector<int>>& keep,
                std::size_t first, const std::string& source) {
  // The child: one record per cell: int32 cell, int32 count (−1: TetGen error), count × 4 int32.
  const ChildRun child = run_in_child([&](int fd) {
    std::vector<TetIndices> tets;
    for (std::size_t c = first; c < cells.size(); ++c) {
      tets.clear();
      const bool ok = run_tetgen(cells[c], keep[c], tets) && !tets.empty();
      const std::int32_t head[2] = {static_cast<std::int32_t>(c), ok ? static_cast<std::int32_t>(tets.size()) : -1};
      if (!write_all(fd, head, sizeof head)) return 3;
      if (!ok) return 2;
      if (!write_all(fd, tets.data(), tets.size() * sizeof(TetIndices))) return 3;
    }
    return 0;
  });
  if (!child.ran()) throw SolverError(fmt::format("{}: cannot run TetGen in a process of its own: {}", source, child.not_run));
  const std::string& buffer = child.output;
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
    b.why = tetgen_error ? std::string("TetGen reported an error or no tetrahedra")
                         : child.exit_code() < 0 ? "TetGen " + child.how() : "the TetGen process " + child.how();
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

// ---------------------------------------------------------------- closed surfaces

namespace quadrix {
namespace {

// Child side: TetGen on a closed surface; the result as int64 point count, points (3 doubles
// each), int64 tetrahedron count, tetrahedra (4 int32 each). Returns false on a TetGen error.
bool run_tetgen_surface(std::span<const Vector3d> vertices, std::span<const std::array<int, 3>> triangles,
                        const SurfaceTetrahedralizeOptions& o, int fd) {
  tetgenio in, out;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(vertices.size());
  in.pointlist = new REAL[3 * vertices.size()];
  for (std::size_t i = 0; i < vertices.size(); ++i)
    for (int a = 0; a < 3; ++a) in.pointlist[3 * i + a] = vertices[i][a];
  in.numberoffacets = static_cast<int>(triangles.size());
  in.facetlist = new tetgenio::facet[triangles.size()];
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    tetgenio::facet& facet = in.facetlist[f];
    tetgenio::init(&facet);
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&facet.polygonlist[0]);
    facet.polygonlist[0].numberofvertices = 3;
    facet.polygonlist[0].vertexlist = new int[3]{triangles[f][0], triangles[f][1], triangles[f][2]};
  }
  std::string switches = "pzQ";  // PLC, zero-based, quiet
  if (o.quality > 0) switches += fmt::format("q{:.6g}", o.quality);
  if (o.max_volume > 0) switches += fmt::format("a{:.17g}", o.max_volume);
  try {
    tetrahedralize(switches.data(), &in, &out);
  } catch (...) {
    return false;
  }
  if (out.numberofpoints <= 0 || out.numberoftetrahedra <= 0 || out.numberofcorners < 4) return false;
  const std::int64_t np = out.numberofpoints, nt = out.numberoftetrahedra;
  if (!write_all(fd, &np, sizeof np) || !write_all(fd, out.pointlist, sizeof(REAL) * 3 * out.numberofpoints) ||
      !write_all(fd, &nt, sizeof nt))
    return false;
  std::vector<std::int32_t> tets(4 * static_cast<std::size_t>(nt));
  for (std::int64_t t = 0; t < nt; ++t)
    for (int a = 0; a < 4; ++a) tets[4 * t + a] = out.tetrahedronlist[t * out.numberofcorners + a];
  return write_all(fd, tets.data(), tets.size() * sizeof(std::int32_t));
}

}  // namespace

void validate_closed_surface(std::span<const Vector3d> vertices, std::span<const std::array<int, 3>> triangles,
                             const std::string& source) {
  if (triangles.empty()) throw InvalidInput(fmt::format("{}: no faces: a closed surface is needed", source));
  for (std::size_t i = 0; i < vertices.size(); ++i)
    if (!vertices[i].allFinite()) throw InvalidInput(fmt::format("{}: vertex {} is not finite", source, i));
  const long long n = static_cast<long long>(vertices.size());
  // Directed edges (a, b) → the triangle that has it, with a count per undirected edge.
  std::map<std::pair<int, int>, std::size_t> directed;
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const auto& t = triangles[f];
    for (int a = 0; a < 3; ++a)
      if (t[a] < 0 || t[a] >= n)
        throw InvalidInput(fmt::format("{}: triangle {} has vertex index {} outside [0, {})", source, f, t[a], n));
    const Vector3d& p = vertices[t[0]];
    const double area2 = (vertices[t[1]] - p).cross(vertices[t[2]] - p).norm();
    const double scale = std::max({(vertices[t[1]] - p).squaredNorm(), (vertices[t[2]] - p).squaredNorm(),
                                   (vertices[t[2]] - vertices[t[1]]).squaredNorm()});
    if (!(area2 > 1e-14 * scale))
      throw InvalidInput(fmt::format("{}: face {} (vertices {} {} {}) has zero area", source, f, t[0], t[1], t[2]));
    for (int a = 0; a < 3; ++a) {
      const std::pair<int, int> e{t[a], t[(a + 1) % 3]};
      const auto [it, fresh] = directed.emplace(e, f);
      if (!fresh)
        throw InvalidInput(fmt::format(
            "{}: edge ({}, {}) runs the same way in faces {} and {}: not consistently oriented or not manifold", source,
            e.first, e.second, it->second, f));
    }
  }
  for (const auto& [e, f] : directed)
    if (!directed.count({e.second, e.first}))
      throw InvalidInput(fmt::format("{}: edge ({}, {}) of face {} has no face on its other side: the surface is "
                                     "open (a closed surface is needed)",
                                     source, e.first, e.second, f));
}

SurfaceTetrahedralization tetrahedralize_closed_surface(std::span<const Vector3d> vertices,
                                                        std::span<const std::array<int, 3>> triangles,
                                                        const SurfaceTetrahedralizeOptions& o) {
  validate_closed_surface(vertices, triangles, o.source);
  if (o.quality != 0 && !(o.quality >= 1.1 && std::isfinite(o.quality)))
    throw InvalidInput(fmt::format("{}: quality {} is not 0 or ≥ 1.1", o.source, o.quality));
  if (!(o.max_volume >= 0 && std::isfinite(o.max_volume)))
    throw InvalidInput(fmt::format("{}: max volume {} is not ≥ 0", o.source, o.max_volume));
  const ChildRun child = run_in_child([&](int fd) { return run_tetgen_surface(vertices, triangles, o, fd) ? 0 : 2; });
  if (!child.ran()) throw SolverError(fmt::format("{}: cannot run TetGen in a process of its own: {}", o.source, child.not_run));
  const std::string& bytes = child.output;
  if (!child.succeeded())
    throw SolverError(fmt::format(
        "{}: {} (a self-intersecting surface, or one TetGen cannot mesh)", o.source,
        child.exit_code() < 0    ? "TetGen " + child.how()
        : child.exit_code() == 2 ? std::string("TetGen reported an error or no tetrahedra")
                                 : "the TetGen process " + child.how()));
  // Parse and check what the child sent.
  const auto fail = [&](std::string_view what) -> SolverError {
    return SolverError(fmt::format("{}: bad TetGen output: {}", o.source, what));
  };
  std::size_t pos = 0;
  const auto take = [&](void* dst, std::size_t n) {
    if (bytes.size() - pos < n) throw fail("truncated");
    std::memcpy(dst, bytes.data() + pos, n);
    pos += n;
  };
  std::int64_t np = 0, nt = 0;
  take(&np, sizeof np);
  if (np < static_cast<std::int64_t>(vertices.size()) || static_cast<std::uint64_t>(np) > bytes.size() / 24)
    throw fail(fmt::format("{} points", np));
  SurfaceTetrahedralization r;
  r.points.resize(static_cast<std::size_t>(np));
  for (auto& p : r.points) take(p.data(), 3 * sizeof(double));
  take(&nt, sizeof nt);
  if (nt <= 0 || static_cast<std::uint64_t>(nt) > bytes.size() / 16) throw fail(fmt::format("{} tetrahedra", nt));
  r.tets.resize(static_cast<std::size_t>(nt));
  for (auto& t : r.tets) {
    std::array<std::int32_t, 4> v;
    take(v.data(), sizeof v);
    for (int a = 0; a < 4; ++a) {
      if (v[a] < 0 || v[a] >= np) throw fail(fmt::format("vertex index {}", v[a]));
      t[a] = v[a];
    }
    if (orient(r.points[t[0]], r.points[t[1]], r.points[t[2]], r.points[t[3]]) < 0) std::swap(t[1], t[2]);
  }
  if (pos != bytes.size()) throw fail("trailing bytes");
  return r;
}

}  // namespace quadrix
