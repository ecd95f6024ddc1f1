#pragma once
/// A bounding volume hierarchy over axis-aligned boxes (each split by the surface area heuristic
/// over 16 centroid bins per axis, else at the median of the longest axis), for ray and
/// nearest-point queries: the CPU reference, the fit's data surface.
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "core/model.h"
#include "core/ray.h"

namespace quadrix {

class Bvh {
public:
  struct Node {
    Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();
    std::uint32_t first = 0;  ///< leaf: first item in items(); inner: index of the right child
    std::uint32_t count = 0;  ///< leaf: number of items; 0 for inner nodes (left child is next)
  };

  Bvh() = default;
  /// boxes: one per primitive; the BVH refers to primitives by their index in this span.
  explicit Bvh(std::span<const Box3> boxes, int leaf_size = 4);

  const std::vector<Node>& nodes() const { return nodes_; }
  const std::vector<std::uint32_t>& items() const { return items_; }

  /// Visits, nearest box first, every leaf item whose box the ray enters before bound(), where
  /// bound() may shrink during the walk. visit(item) is called per item.
  template <typename Bound, typename Visit>
  void traverse(const Ray& ray, double tmin, Bound&& bound, Visit&& visit) const;

  /// Visits, nearest box first, every leaf item whose box lies nearer x than √best2, in squared
  /// distances; visit(item) may lower best2 as it finds nearer items. Stops once best2 ≤ good2.
  template <typename Visit>
  void nearest(const Eigen::Vector3d& x, double& best2, double good2, Visit&& visit) const;

private:
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> items_;
};

namespace detail {
/// Slab test; returns the entry distance or +inf when missed within [tmin, tmax].
inline double ray_box(const Eigen::Vector3d& inv_dir, const Eigen::Vector3d& origin, const Eigen::Vector3d& mn,
                      const Eigen::Vector3d& mx, double tmin, double tmax) {
  for (int a = 0; a < 3; ++a) {
    double t0 = (mn[a] - origin[a]) * inv_dir[a];
    double t1 = (mx[a] - origin[a]) * inv_dir[a];
    if (t0 > t1) std::swap(t0, t1);
    if (std::isnan(t0)) t0 = -std::numeric_limits<double>::infinity();  // 0·∞ on a slab boundary
    if (std::isnan(t1)) t1 = std::numeric_limits<double>::infinity();
    tmin = std::max(tmin, t0);
    tmax = std::min(tmax, t1 * (1.0 + 4e-16));
    if (tmin > tmax) return std::numeric_limits<double>::infinity();
  }
  return tmin;
}
}  // namespace detail

template <typename Bound, typename Visit>
void Bvh::traverse(const Ray& ray, double tmin, Bound&& bound, Visit&& visit) const {
  if (nodes_.empty()) return;
  constexpr double kMiss = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d inv = ray.dir.cwiseInverse();
  // Each node is pushed with its box's entry distance, tested against the bound when pushed; on
  // pop only that distance is compared with the bound, which may have shrunk since (the box test
  // again would give the same answer).
  struct Entry {
    std::uint32_t node;
    double t;
  };
  Entry stack[128];
  int sp = 0;
  if (const double t = detail::ray_box(inv, ray.origin, nodes_[0].min, nodes_[0].max, tmin, bound()); t != kMiss)
    stack[sp++] = {0, t};
  while (sp > 0) {
    const Entry e = stack[--sp];
    if (e.t > bound()) continue;
    const Node& n = nodes_[e.node];
    if (n.count > 0) {
      for (std::uint32_t i = 0; i < n.count; ++i) visit(items_[n.first + i]);
      continue;
    }
    const std::uint32_t left = e.node + 1, right = n.first;
    const double b = bound();
    const double tl = detail::ray_box(inv, ray.origin, nodes_[left].min, nodes_[left].max, tmin, b);
    const double tr = detail::ray_box(inv, ray.origin, nodes_[right].min, nodes_[right].max, tmin, b);
    // Push the far child first so the near one is visited first.
    if (tl <= tr) {
      if (tr != kMiss) stack[sp++] = {right, tr};
      if (tl != kMiss) stack[sp++] = {left, tl};
    } else {
      if (tl != kMiss) stack[sp++] = {left, tl};
      stack[sp++] = {right, tr};
    }
  }
}

template <typename Visit>
void Bvh::nearest(const Eigen::Vector3d& x, double& best2, double good2, Visit&& visit) const {
  if (nodes_.empty()) return;
  const auto box_distance = [&](const Node& n) { return (x - x.cwiseMax(n.min).cwiseMin(n.max)).squaredNorm(); };
  std::uint32_t stack[128];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& n = nodes_[stack[--sp]];
    if (box_distance(n) >= best2) continue;
    if (n.count > 0) {
      for (std::uint32_t i = 0; i < n.count; ++i) visit(items_[n.first + i]);
      if (best2 <= good2) break;
      continue;
    }
    const std::uint32_t left = static_cast<std::uint32_t>(&n - nodes_.data()) + 1, right = n.first;
    const double dl = box_distance(nodes_[left]), dr = box_distance(nodes_[right]);
    // Push the far child first so the near one is visited first.
    if (dl <= dr) {
      if (dr < best2) stack[sp++] = right;
      if (dl < best2) stack[sp++] = left;
    } else {
      if (dl < best2) stack[sp++] = left;
      if (dr < best2) stack[sp++] = right;
    }
  }
}

}  // namespace quadrix
