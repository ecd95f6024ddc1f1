#include "core/morton.h"

#include <algorithm>
#include <tuple>
#include <utility>

#include "core/model.h"

namespace quadrix {
namespace {

// Interleaves the low 21 bits of x with two zero bits between each.
std::uint64_t spread3(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

std::uint64_t morton_key(const Eigen::Vector3d& u) {
  const Eigen::Vector3d c = u.cwiseMax(0.0).cwiseMin(1.0);
  const auto q = [&](int k) { return static_cast<std::uint64_t>(c[k] * double((1 << 21) - 1)); };
  return spread3(q(0)) | spread3(q(1)) << 1 | spread3(q(2)) << 2;
}

std::vector<std::uint32_t> morton_order(std::span<const Eigen::Vector3d> points) {
  const std::size_t n = points.size();
  std::vector<std::uint32_t> order(n);
  if (n == 0) return order;
  Box3 all;
  for (const auto& p : points) all.extend(p);
  const Eigen::Vector3d extent = (all.max - all.min).cwiseMax(Eigen::Vector3d::Constant(1e-300));
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
  for (std::size_t i = 0; i < n; ++i)
    keyed[i] = {morton_key(((points[i] - all.min).array() / extent.array()).matrix()), static_cast<std::uint32_t>(i)};
  // Within one cell by coordinates, then by index: the same points in any order come out in the
  // same order (fit_slim relies on it), copies of one position in their input order.
  std::sort(keyed.begin(), keyed.end(), [&](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first < b.first;
    const auto &p = points[a.second], &q = points[b.second];
    return std::tie(p.x(), p.y(), p.z(), a.second) < std::tie(q.x(), q.y(), q.z(), b.second);
  });
  for (std::size_t i = 0; i < n; ++i) order[i] = keyed[i].second;
  return order;
}

}  // namespace quadrix
