#include "convert/between_views.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "convert/mesh_measure.h"
#include "fit/data_surface.h"

namespace quadrix {
namespace {

/// Face centroids hashed into cubes of a given size, for the faces near a point.
class FaceGrid {
 public:
  FaceGrid(const PolygonMesh& m, std::size_t first_face) : mesh_(m) {
    for (std::size_t f = first_face; f < m.face_count(); ++f) {
      const auto t = m.face(f);
      const Eigen::Vector3d c = centroid(f);
      for (const int v : t) radius_ = std::max(radius_, (m.vertices[v] - c).norm());
    }
    cell_ = std::max(radius_, 1e-12);
    for (std::size_t f = first_face; f < m.face_count(); ++f) cells_[key(cell_of(centroid(f)))].push_back(f);
  }

  /// The face nearest x among those whose centroid lies within reach + their radius; −1: none.
  std::ptrdiff_t nearest(const Eigen::Vector3d& x, double reach) const {
    const int k = static_cast<int>(std::ceil((reach + radius_) / cell_));
    const Eigen::Vector3i c = cell_of(x);
    double best = reach;
    std::ptrdiff_t out = -1;
    for (int dz = -k; dz <= k; ++dz)
      for (int dy = -k; dy <= k; ++dy)
        for (int dx = -k; dx <= k; ++dx) {
          const auto it = cells_.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (const std::size_t f : it->second) {
            const auto t = mesh_.face(f);
            const double d = point_triangle_distance(x, mesh_.vertices[t[0]], mesh_.vertices[t[1]], mesh_.vertices[t[2]]);
            if (d <= best) best = d, out = static_cast<std::ptrdiff_t>(f);
          }
        }
    return out;
  }

 private:
  Eigen::Vector3d centroid(std::size_t f) const {
    const auto t = mesh_.face(f);
    return (mesh_.vertices[t[0]] + mesh_.vertices[t[1]] + mesh_.vertices[t[2]]) / 3.0;
  }
  Eigen::Vector3i cell_of(const Eigen::Vector3d& x) const { return (x / cell_).array().floor().cast<int>(); }
  static std::uint64_t key(const Eigen::Vector3i& c) {
    const auto u = [](int v) { return static_cast<std::uint64_t>(static_cast<std::uint32_t>(v) & 0x1fffffu); };
    return u(c.x()) | u(c.y()) << 21 | u(c.z()) << 42;
  }

  const PolygonMesh& mesh_;
  double radius_ = 0, cell_ = 1;
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells_;
};

}  // namespace

std::size_t move_between_views(PolygonMesh& mesh, std::span<const SurfaceError::Beyond> beyond,
                               const BetweenViewsOptions& o, std::vector<double>& offset) {
  offset.resize(mesh.vertices.size(), 0.0);
  if (beyond.empty() || !(o.bound > 0)) return 0;
  const std::vector<Eigen::Vector3d> normals = vertex_normals(mesh);
  const FaceGrid faces(mesh, o.first_face);
  // Per vertex the largest move asked for each way along its normal, and (a point beside the
  // face, past an open edge) the largest straight towards a point.
  std::vector<double> out(mesh.vertices.size(), 0.0), in(mesh.vertices.size(), 0.0);
  std::vector<Eigen::Vector3d> towards(mesh.vertices.size(), Eigen::Vector3d::Zero());
  for (const auto& [p, distance] : beyond) {
    const std::ptrdiff_t f = faces.nearest(p, 1.001 * distance);
    if (f < 0) continue;
    const auto t = mesh.face(static_cast<std::size_t>(f));
    const Eigen::Vector3d &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    const double side = (p - a).dot(n);  // the point's height over the face's plane
    if (std::abs(side) < 0.9 * distance) {
      // Nearest at an edge or corner: the point is beside the face (past an open edge); the face
      // moves towards it, away from its centroid.
      const double move = distance - o.keep * o.bound;
      const Eigen::Vector3d w = (p - (a + b + c) / 3.0).normalized();
      for (const int v : t)
        if (move > towards[v].norm()) towards[v] = move * w;
      continue;
    }
    const double move = std::abs(side) - o.keep * o.bound;
    if (!(move > 0)) continue;
    for (const int v : t) {
      // Along the vertex normal, the share of it that moves the face towards the point.
      const double along = normals[v].dot(n);
      if (!(along > 0.5)) continue;
      (side > 0 ? out : in)[v] = std::max((side > 0 ? out : in)[v], move / along);
    }
  }
  std::size_t moved = 0;
  const double cap = o.max_offset * o.bound;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (out[v] == 0 && in[v] == 0 && towards[v].squaredNorm() > 0) {
      const double room = cap - std::abs(offset[v]);
      if (!(room > 0)) continue;
      const double m = std::min(room, towards[v].norm());
      mesh.vertices[v] += m * towards[v].normalized();
      offset[v] += offset[v] < 0 ? -m : m;
      ++moved;
      continue;
    }
    if ((out[v] > 0) == (in[v] > 0)) continue;  // not asked, or pulled both ways
    const double target = std::clamp(offset[v] + (out[v] > 0 ? out[v] : -in[v]), -cap, cap);
    if (target == offset[v]) continue;
    mesh.vertices[v] += (target - offset[v]) * normals[v];
    offset[v] = target;
    ++moved;
  }
  return moved;
}

}  // namespace quadrix
