#include "core/io/io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <tuple>

#include <Eigen/Geometry>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <fmt/format.h>

#include "core/error.h"
#include "core/io/file.h"
#include "core/io/formats.h"
#include "core/log.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;

enum class Format { ply, off, obj, stl, xyz, pts, qxm, slim2t };

/// The file's format by extension; by its first bytes for an unknown one; nothing when neither
/// tells (format_of reads such a file as XYZ).
std::optional<Format> known_format(const fs::path& path) {
  io::read_file_prefix(path, 0);  // a missing file or a folder: IoError naming it, before anything else
  const std::string ext = io::lower_extension(path);
  if (ext == ".ply") return Format::ply;
  if (ext == ".off") return Format::off;
  if (ext == ".obj") return Format::obj;
  if (ext == ".stl") return Format::stl;
  if (ext == ".xyz" || ext == ".txt") return Format::xyz;
  if (ext == ".pts") return Format::pts;
  if (ext == ".qxm") return Format::qxm;
  if (ext == ".slim2t") return Format::slim2t;
  const std::string head = io::read_file_prefix(path, 128);
  if (head.starts_with("ply")) return Format::ply;
  const std::string_view first(head.data(), std::min(head.find_first_of(" \t\r\n"), head.size()));
  if (first.ends_with("OFF") && first.size() <= 6) return Format::off;
  if (head.starts_with("solid")) return Format::stl;
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (!ec && head.size() >= 84) {
    std::uint32_t n;
    std::memcpy(&n, head.data() + 80, 4);
    if (size - 84 == 50 * std::uint64_t{n}) return Format::stl;
  }
  if (head.size() >= 12) {
    std::int32_t d;
    std::memcpy(&d, head.data(), 4);
    if (d == 1 || d == 2 || d == -1 || d == -2) return Format::slim2t;
  }
  return std::nullopt;
}

Format format_of(const fs::path& path) { return known_format(path).value_or(Format::xyz); }

/// Silences OpenMesh's omerr/omlog (they write to stderr/stdout on their own) for one scope.
/// The streams are process-wide, so concurrent OpenMesh use elsewhere is muted meanwhile.
class OpenMeshQuiet {
public:
  OpenMeshQuiet() : err_(::omerr().is_enabled()), log_(::omlog().is_enabled()) {
    ::omerr().disable();
    ::omlog().disable();
  }
  ~OpenMeshQuiet() {
    if (err_) ::omerr().enable();
    if (log_) ::omlog().enable();
  }
  OpenMeshQuiet(const OpenMeshQuiet&) = delete;
  OpenMeshQuiet& operator=(const OpenMeshQuiet&) = delete;

private:
  bool err_, log_;
};

/// Number of faces OpenMesh's halfedge mesh refuses (complex edge or vertex, repeated vertex),
/// adding the faces in file order. Indices must be valid.
std::size_t count_non_manifold_faces(const PolygonMesh& mesh) {
  OpenMesh::PolyMesh_ArrayKernelT<> om;
  om.reserve(mesh.vertices.size(), mesh.indices.size() / 2 + 3, mesh.face_count());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) om.add_vertex({0.0f, 0.0f, 0.0f});
  OpenMeshQuiet quiet;
  std::size_t refused = 0;
  std::vector<OpenMesh::VertexHandle> vhs;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    vhs.clear();
    for (const int v : mesh.face(f)) vhs.emplace_back(v);
    bool repeated = false;
    for (std::size_t a = 0; a < vhs.size() && !repeated; ++a)
      for (std::size_t b = a + 1; b < vhs.size(); ++b) repeated = repeated || vhs[a] == vhs[b];
    if (repeated || !om.add_face(vhs).is_valid()) ++refused;
  }
  return refused;
}


io::Surface read_surface(const fs::path& path, Format format) {
  switch (format) {
    case Format::ply: return io::read_ply(io::read_file(path), path);
    case Format::off: return io::read_off(io::read_file(path), path);
    case Format::obj: return io::read_obj(io::read_file(path), path);
    case Format::stl: return io::read_stl(io::read_file(path), path);
    case Format::qxm:
    case Format::slim2t:
      throw FormatError(fmt::format("{}: a quadric model, not a mesh or point cloud", path.string()));
    default:
      throw FormatError(fmt::format("{}: unsupported mesh format '{}' (expected .ply, .off, .obj or .stl)",
                                    path.string(), io::lower_extension(path)));
  }
}

}  // namespace

FileKind detect_file_kind(const fs::path& path) { return known_file_kind(path).value_or(FileKind::points); }

std::optional<FileKind> known_file_kind(const fs::path& path) {
  const std::optional<Format> format = known_format(path);
  if (!format) return std::nullopt;
  switch (*format) {
    case Format::qxm:
    case Format::slim2t: return FileKind::model;
    case Format::off:
    case Format::obj:
    case Format::stl: return FileKind::mesh;
    case Format::xyz:
    case Format::pts: return FileKind::points;
    case Format::ply: break;
  }
  // PLY: the header says which.
  const std::string head = io::read_file_prefix(path, 1 << 16);
  const auto end = head.find("end_header");
  std::string_view h(head.data(), end == std::string::npos ? head.size() : end);
  bool has_faces = false;
  while (!h.empty()) {
    const auto eol = std::min(h.find('\n'), h.size());
    std::string_view line = h.substr(0, eol);
    h.remove_prefix(std::min(eol + 1, h.size()));
    if (line.starts_with("comment quadrix-format")) return FileKind::model;
    if (line.starts_with("element face ")) has_faces = line.substr(13).find_first_not_of("0 \r") != std::string_view::npos;
  }
  return has_faces ? FileKind::mesh : FileKind::points;
}

std::size_t orient_faces_coherently(PolygonMesh& mesh) {
  const std::size_t F = mesh.face_count();
  struct Use {
    int lo, hi;
    std::uint32_t face;
    bool forward;  // the face runs lo → hi
  };
  std::vector<Use> uses;
  uses.reserve(mesh.indices.size());
  for (std::size_t f = 0; f < F; ++f) {
    const auto vs = mesh.face(f);
    for (std::size_t k = 0; k < vs.size(); ++k) {
      const int a = vs[k], b = vs[(k + 1) % vs.size()];
      if (a != b) uses.push_back({std::min(a, b), std::max(a, b), static_cast<std::uint32_t>(f), a < b});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const Use& x, const Use& y) { return std::tie(x.lo, x.hi, x.face) < std::tie(y.lo, y.hi, y.face); });
  // Faces across each edge used by exactly two faces: same = they run it the same way.
  struct Link {
    std::uint32_t other;
    bool same;
  };
  std::vector<std::vector<Link>> links(F);
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    if (j - i == 2 && uses[i].face != uses[i + 1].face) {
      const bool same = uses[i].forward == uses[i + 1].forward;
      links[uses[i].face].push_back({uses[i + 1].face, same});
      links[uses[i + 1].face].push_back({uses[i].face, same});
    }
    i = j;
  }
  const auto area = [&](std::size_t f) {
    const auto vs = mesh.face(f);
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < vs.size(); ++k) n += mesh.vertices[vs[k]].cross(mesh.vertices[vs[(k + 1) % vs.size()]]);
    return std::isfinite(n.norm()) ? n.norm() : 0.0;
  };
  // Twice the signed volume the face's fan adds (closed parts: positive when wound outward).
  const auto volume = [&](std::size_t f) {
    const auto vs = mesh.face(f);
    double v = 0;
    for (std::size_t k = 1; k + 1 < vs.size(); ++k)
      v += mesh.vertices[vs[0]].dot(mesh.vertices[vs[k]].cross(mesh.vertices[vs[k + 1]]));
    return std::isfinite(v) ? v : 0.0;
  };
  std::vector<std::int8_t> turn(F, -1);  // -1: not reached
  std::vector<std::uint32_t> part, queue;
  std::size_t turned = 0;
  for (std::size_t seed = 0; seed < F; ++seed) {
    if (turn[seed] >= 0) continue;
    part.clear();
    queue.assign(1, static_cast<std::uint32_t>(seed));
    turn[seed] = 0;
    bool orientable = true, closed = true;
    while (!queue.empty()) {
      const std::uint32_t f = queue.back();
      queue.pop_back();
      part.push_back(f);
      const auto vs = mesh.face(f);
      std::size_t edges = 0;
      for (std::size_t k = 0; k < vs.size(); ++k) edges += vs[k] != vs[(k + 1) % vs.size()];
      closed = closed && links[f].size() == edges;
      for (const Link& l : links[f]) {
        const auto want = static_cast<std::int8_t>(turn[f] ^ (l.same ? 1 : 0));
        if (turn[l.other] < 0) turn[l.other] = want, queue.push_back(l.other);
        else orientable = orientable && turn[l.other] == want;
      }
    }
    // A part that cannot be wound one way (a Möbius strip) is left as it is; so is one that is.
    if (!orientable || std::none_of(part.begin(), part.end(), [&](std::uint32_t f) { return turn[f] != 0; })) continue;
    // Which set turns: a closed part ends wound outward (positive volume); an open one keeps the
    // winding of the larger area.
    bool invert;
    if (closed) {
      double v = 0;
      for (const auto f : part) v += turn[f] ? -volume(f) : volume(f);
      invert = v < 0;
    } else {
      double kept = 0, flipped = 0;
      for (const auto f : part) (turn[f] ? flipped : kept) += area(f);
      invert = flipped > kept;
    }
    for (const auto f : part) {
      if ((turn[f] != 0) == invert) continue;
      std::reverse(mesh.indices.begin() + mesh.offsets[f] + 1, mesh.indices.begin() + mesh.offsets[f + 1]);
      ++turned;
    }
  }
  return turned;
}

PolygonMesh read_mesh(const fs::path& path) {
  io::Surface s = read_surface(path, format_of(path));
  PolygonMesh mesh = std::move(s.mesh);
  if (s.normals.size() == mesh.vertices.size()) mesh.normals = std::move(s.normals);
  if (mesh.face_count() == 0) throw FormatError(fmt::format("{}: the mesh has no faces", path.string()));
  if (const std::size_t turned = orient_faces_coherently(mesh); turned > 0)
    log::warn("{}: {} of {} faces were wound against their neighbours (an edge run the same way by both of its "
              "faces); turned to agree with them",
              path.string(), turned, mesh.face_count());
  if (const std::size_t refused = count_non_manifold_faces(mesh); refused > 0)
    log::warn("{}: {} of {} faces are non-manifold or degenerate (complex edge or vertex, repeated vertex); they "
              "are kept, but OpenMesh's halfedge mesh would drop them",
              path.string(), refused, mesh.face_count());
  log::debug("{}: {} vertices, {} faces", path.string(), mesh.vertices.size(), mesh.face_count());
  return mesh;
}

void write_mesh(const PolygonMesh& mesh, const fs::path& path) {
  const std::string ext = io::lower_extension(path);
  if (ext == ".off") return io::write_off(mesh, path);
  if (ext == ".obj") return io::write_obj(mesh, path);
  if (ext == ".ply") return io::write_ply(mesh, path);
  if (ext == ".stl") return io::write_stl(mesh, path);
  throw InvalidInput(
      fmt::format("{}: cannot write mesh format '{}' (expected .ply, .obj, .off or .stl)", path.string(), ext));
}

PointCloud read_points(const fs::path& path) {
  const Format format = format_of(path);
  PointCloud cloud;
  if (format == Format::xyz || format == Format::pts) {
    cloud = io::read_xyz(io::read_file(path), path, format == Format::pts);
  } else {
    io::Surface s = read_surface(path, format);
    cloud.points = std::move(s.mesh.vertices);
    cloud.normals = std::move(s.normals);
    cloud.colours = std::move(s.mesh.colours);
  }
  if (cloud.points.empty()) throw FormatError(fmt::format("{}: no points", path.string()));
  return cloud;
}

PointCloud read_surface_points(const fs::path& path) {
  const Format format = format_of(path);
  if (format == Format::xyz || format == Format::pts) return read_points(path);
  io::Surface s = read_surface(path, format);
  if (s.mesh.face_count() == 0) {
    if (s.mesh.vertices.empty()) throw FormatError(fmt::format("{}: no points", path.string()));
    return {std::move(s.mesh.vertices), std::move(s.normals), std::move(s.mesh.colours)};
  }
  if (const std::size_t turned = orient_faces_coherently(s.mesh); turned > 0)
    log::warn("{}: {} of {} faces were wound against their neighbours; turned to agree with them", path.string(), turned,
              s.mesh.face_count());
  PointCloud cloud = points_from_mesh(s.mesh);
  if (cloud.points.empty()) throw FormatError(fmt::format("{}: no face has a non-zero area", path.string()));
  if (cloud.points.size() < s.mesh.vertices.size())
    log::info("{}: {} of {} vertices left out (in no face, or their face normals cancel)", path.string(),
              s.mesh.vertices.size() - cloud.points.size(), s.mesh.vertices.size());
  return cloud;
}

EdgeUses::EdgeUses(const PolygonMesh& mesh) {
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    for (std::size_t k = 0; k < vs.size(); ++k) edges_.push_back(std::minmax(vs[k], vs[(k + 1) % vs.size()]));
  }
  std::sort(edges_.begin(), edges_.end());
}

bool EdgeUses::open(int a, int b) const {
  const std::pair<int, int> key = std::minmax(a, b);
  const auto [lo, hi] = std::equal_range(edges_.begin(), edges_.end(), key);
  return hi - lo == 1;
}

bool EdgeUses::wound_inward(const PolygonMesh& mesh) const {
  std::size_t distinct = 0, open = 0;  // edges not used by exactly two faces
  for (std::size_t i = 0; i < edges_.size();) {
    std::size_t j = i;
    while (j < edges_.size() && edges_[j] == edges_[i]) ++j;
    ++distinct;
    open += j - i != 2;
    i = j;
  }
  if (distinct == 0 || open * 200 > distinct) return false;
  // The signed volume about the vertices' box centre: about the world origin, a nearly closed
  // mesh's holes count their cones to the origin, and an open box (its top missing, 0.4 % of its
  // edges open) moved 1e5 away read as wound inward: fits of its points were judged inside out
  // (99.6 % of its pixels "open").
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& v : mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  const Eigen::Vector3d c = 0.5 * (lo + hi);
  double volume6 = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    const Eigen::Vector3d p0 = mesh.vertices[vs[0]] - c;
    for (std::size_t k = 1; k + 1 < vs.size(); ++k) volume6 += p0.dot((mesh.vertices[vs[k]] - c).cross(mesh.vertices[vs[k + 1]] - c));
  }
  return volume6 < 0;
}

bool mesh_wound_inward(const PolygonMesh& mesh) { return EdgeUses(mesh).wound_inward(mesh); }

PointCloud points_from_mesh(const PolygonMesh& mesh) {
  std::vector<Eigen::Vector3d> sum(mesh.vertices.size(), Eigen::Vector3d::Zero());
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    Eigen::Vector3d n = Eigen::Vector3d::Zero();  // Newell: twice the area vector
    for (std::size_t k = 0; k < vs.size(); ++k) n += mesh.vertices[vs[k]].cross(mesh.vertices[vs[(k + 1) % vs.size()]]);
    for (const int v : vs) sum[v] += n;
  }
  const double sign = mesh_wound_inward(mesh) ? -1.0 : 1.0;
  PointCloud cloud;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const double len = sum[v].norm();
    if (!(len > 0) || !std::isfinite(len)) continue;
    cloud.points.push_back(mesh.vertices[v]);
    cloud.normals.push_back(sign * sum[v] / len);
    if (mesh.colours.size() == mesh.vertices.size()) cloud.colours.push_back(mesh.colours[v]);
  }
  return cloud;
}

namespace {

PointCloud centroids(const PolygonMesh& mesh, double sign, std::vector<std::uint32_t>* face_of) {
  PointCloud cloud;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    Eigen::Vector3d c = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
    double edge2 = 0;
    for (std::size_t k = 0; k < vs.size(); ++k) {
      const Eigen::Vector3d &a = mesh.vertices[vs[k]], &b = mesh.vertices[vs[(k + 1) % vs.size()]];
      c += a;
      n += (a - mesh.vertices[vs[0]]).cross(b - mesh.vertices[vs[0]]);
      edge2 = std::max(edge2, (b - a).squaredNorm());
    }
    if (is_sliver(n.norm(), edge2)) continue;
    cloud.points.push_back(c / double(vs.size()));
    cloud.normals.push_back(sign * n.normalized());
    if (face_of) face_of->push_back(static_cast<std::uint32_t>(f));
  }
  return cloud;
}

}  // namespace

PointCloud face_centroids(const PolygonMesh& mesh, std::vector<std::uint32_t>* face_of) {
  return centroids(mesh, mesh_wound_inward(mesh) ? -1.0 : 1.0, face_of);
}

// Calls visit(f, a, b, c, n, longest edge) for each fan triangle of each face that is not a
// sliver (n: the unnormalised cross product).
template <class Visit>
void for_each_fan_triangle(const PolygonMesh& mesh, Visit&& visit) {
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    for (std::size_t k = 1; k + 1 < vs.size(); ++k) {
      const Eigen::Vector3d &a = mesh.vertices[vs[0]], &b = mesh.vertices[vs[k]], &c = mesh.vertices[vs[k + 1]];
      const Eigen::Vector3d n = (b - a).cross(c - a);
      const double L = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
      if (!is_sliver(n.norm(), L * L)) visit(f, a, b, c, n, L);
    }
  }
}

PointCloud sample_faces_uniformly(const PolygonMesh& mesh, std::size_t count, std::uint64_t seed) {
  const double sign = mesh_wound_inward(mesh) ? -1.0 : 1.0;
  struct Tri {
    Eigen::Vector3d a, b, c, n;
  };
  std::vector<Tri> tris;
  std::vector<double> area;
  for_each_fan_triangle(mesh, [&](std::size_t, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                  const Eigen::Vector3d& n, double) {
    tris.push_back({a, b, c, sign * n.normalized()});
    area.push_back(0.5 * n.norm());
  });
  PointCloud cloud;
  if (tris.empty()) return cloud;
  std::mt19937_64 rng(seed);
  std::discrete_distribution<std::size_t> pick(area.begin(), area.end());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  cloud.points.reserve(count);
  cloud.normals.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const Tri& t = tris[pick(rng)];
    double s = u(rng), r = u(rng);
    if (s + r > 1.0) s = 1.0 - s, r = 1.0 - r;  // the reflected half: uniform over the triangle
    cloud.points.push_back(t.a + s * (t.b - t.a) + r * (t.c - t.a));
    cloud.normals.push_back(t.n);
  }
  return cloud;
}

PointCloud face_samples(const PolygonMesh& mesh, double large_factor, std::vector<std::uint32_t>* face_of,
                        double min_spacing) {
  const double sign = mesh_wound_inward(mesh) ? -1.0 : 1.0;
  PointCloud cloud = centroids(mesh, sign, face_of);
  const std::size_t F = mesh.face_count();
  if (F == 0) return cloud;
  std::vector<double> longest(F, 0.0);
  for (std::size_t f = 0; f < F; ++f) {
    const auto vs = mesh.face(f);
    for (std::size_t k = 0; k < vs.size(); ++k)
      longest[f] = std::max(longest[f], (mesh.vertices[vs[(k + 1) % vs.size()]] - mesh.vertices[vs[k]]).norm());
  }
  std::vector<double> sorted = longest;
  std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(F / 2), sorted.end());
  const double spacing = sorted[F / 2];
  if (!(spacing > 0) || !(spacing > min_spacing)) return cloud;
  for_each_fan_triangle(mesh, [&](std::size_t f, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                  const Eigen::Vector3d& n, double L) {
    if (!(longest[f] > large_factor * spacing)) return;
    const int m = static_cast<int>(std::min(1000.0, std::ceil(L / spacing)));
    for (int i = 0; i <= m; ++i)
      for (int j = 0; i + j <= m; ++j) {
        if ((i == 0 && j == 0) || i == m || j == m) continue;  // the corners
        cloud.points.push_back(a + (double(i) / m) * (b - a) + (double(j) / m) * (c - a));
        cloud.normals.push_back(sign * n.normalized());
        if (face_of) face_of->push_back(static_cast<std::uint32_t>(f));
      }
  });
  return cloud;
}

void write_points_xyz(const PointCloud& cloud, const fs::path& path) { io::write_xyz(cloud, path); }

}  // namespace quadrix
