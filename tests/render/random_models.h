#pragma once
// Random quad meshes for render property tests: an open height-field sheet and a closed blob.
#include <array>
#include <cmath>
#include <map>
#include <random>

#include "core/mesh_io.h"

namespace quadrix::test {

/// An open n×n sheet of non-planar quads over [0, 1]² with random heights, faces towards +z.
inline PolygonMesh random_quad_sheet(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> u(-1, 1);
  const double a = u(rng), b = u(rng), c = u(rng);
  PolygonMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = double(i) / n, y = double(j) / n;
      const double z = 0.2 * std::sin(3 * x + a) * std::cos(2 * y + b) + 0.1 * c * x * y + 0.3 * u(rng) / n;
      m.vertices.emplace_back(x, y, z);
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int v = j * (n + 1) + i;
      m.add_face(std::array{v, v + 1, v + n + 2, v + n + 1});
    }
  return m;
}

/// A closed quad blob: a cube's faces cut k×k, pushed onto a bumpy sphere; outward faces.
inline PolygonMesh random_quad_blob(std::mt19937_64& rng, int k) {
  std::uniform_real_distribution<double> u(-1, 1);
  const Eigen::Vector3d phase(u(rng), u(rng), u(rng));
  PolygonMesh m;
  std::map<std::array<int, 3>, int> index;
  const auto vertex = [&](std::array<int, 3> p) {
    const auto [it, fresh] = index.try_emplace(p, static_cast<int>(m.vertices.size()));
    if (fresh) {
      const Eigen::Vector3d d = (Eigen::Vector3d(p[0], p[1], p[2]) / k - Eigen::Vector3d::Constant(0.5)).normalized();
      const double r = 1.0 + 0.15 * std::sin(3 * d.x() + phase.x()) * std::sin(2 * d.y() + phase.y()) +
                       0.1 * std::sin(4 * d.z() + phase.z()) + 0.02 * u(rng);
      m.vertices.push_back(r * d);
    }
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (const int side : {0, 1}) {
      // Tangent axes (s, t) with s × t along the outward normal (+axis for side 1, −axis for 0).
      int s = (axis + 1) % 3, t = (axis + 2) % 3;
      if (side == 0) std::swap(s, t);
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i) {
          std::array<int, 4> q;
          const int corner[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
          for (int c = 0; c < 4; ++c) {
            std::array<int, 3> p;
            p[axis] = side * k;
            p[s] = corner[c][0];
            p[t] = corner[c][1];
            q[c] = vertex(p);
          }
          m.add_face(q);
        }
    }
  return m;
}

}  // namespace quadrix::test
