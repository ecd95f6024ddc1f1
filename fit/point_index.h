#pragma once
/// A static kd-tree over 3-D points (nanoflann behind a small interface), built once and
/// queried from many threads (const queries are thread-safe).
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

/// (point index, squared distance)
using Neighbour = std::pair<std::uint32_t, double>;

class PointIndex {
public:
  /// points: N×3 world units; the span must outlive the index.
  explicit PointIndex(std::span<const Eigen::Vector3d> points);
  ~PointIndex();
  PointIndex(PointIndex&&) noexcept;
  PointIndex& operator=(PointIndex&&) noexcept;

  /// Every point with ‖p − q‖ ≤ r, sorted by distance when `sorted` (out is cleared first).
  void radius(const Eigen::Vector3d& q, double r, std::vector<Neighbour>& out, bool sorted = false) const;
  /// The k nearest points, nearest first (fewer when the cloud is smaller; out is cleared first).
  void nearest(const Eigen::Vector3d& q, std::size_t k, std::vector<Neighbour>& out) const;
  std::size_t size() const;
  /// The points' indices in the index's Morton order: loops that query every point visit them
  /// in this order, so that neighbouring queries share the tree's cache lines (point_index.cpp).
  std::span<const std::uint32_t> order() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace quadrix
