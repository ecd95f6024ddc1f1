#pragma once
/// Morton (Z-order) keys: points sorted by them are near in memory when near in space, for
/// cache-friendly traversal (render chunks, neighbour queries in bulk).
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

/// The 63-bit Morton key of u ∈ [0, 1]³ (21 bits per axis; values outside are clamped).
std::uint64_t morton_key(const Eigen::Vector3d& u);

/// Indices of points in Morton order over their bounding box; points in one cell (2⁻²¹ of the
/// box per axis) by their coordinates, copies of a position in input order.
std::vector<std::uint32_t> morton_order(std::span<const Eigen::Vector3d> points);

}  // namespace quadrix
