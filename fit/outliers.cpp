#include "fit/outliers.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "fit/point_index.h"

namespace quadrix {

namespace {

std::vector<std::uint32_t> outliers_once(std::span<const Eigen::Vector3d> points, const OutlierOptions& options) {
  const std::size_t n = points.size(), k = std::max<std::size_t>(options.neighbours, 6);
  constexpr std::size_t kSpacing = 6;  // the spacing: the distance to the 6th nearest other point
  if (n < k + 2) return {};
  const PointIndex index(points);
  // Per point, from its k nearest others: their spacing, plane (centroid, normal), roughness
  // about it, and whether they span a plane at all (not along a wire or a scanner's line).
  std::vector<std::uint32_t> near(n * k);
  std::vector<double> spacing(n), rough(n), d1(n);
  std::vector<Eigen::Vector3d> centroid(n), normal(n);
  std::vector<std::uint8_t> planar(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    std::vector<Neighbour> nb;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      index.nearest(points[i], k + 1, nb);
      std::size_t m = 0;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const auto& [j, d2] : nb)  // the point itself left out (a coincident copy stays)
        if (j != i && m < k) near[i * k + m++] = j, c += points[j];
      for (std::size_t q = m; q < k; ++q) near[i * k + q] = near[i * k];
      spacing[i] = (points[near[i * k + std::min(kSpacing, m) - 1]] - points[i]).norm();
      d1[i] = (points[near[i * k]] - points[i]).norm();
      c /= double(m);
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      for (std::size_t q = 0; q < m; ++q) C += (points[near[i * k + q]] - c) * (points[near[i * k + q]] - c).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
      const double l0 = std::max(0.0, eig.eigenvalues()(0));
      centroid[i] = c;
      normal[i] = eig.eigenvectors().col(0);
      rough[i] = std::sqrt(l0 / double(m));
      planar[i] = eig.eigenvalues()(1) > 16.0 * l0;
    }
  });
  std::vector<std::uint8_t> out(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    std::vector<double> s(k);
    std::vector<Neighbour> wide;
    std::vector<std::uint32_t> wide_ids;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::uint32_t* nb = &near[i * k];
      for (std::size_t q = 0; q < k; ++q) s[q] = spacing[nb[q]];
      std::nth_element(s.begin(), s.begin() + k / 2, s.end());
      const double median_spacing = s[k / 2];
      // Off its neighbours' plane by more than `spacings` of their spacing and `roughness` of
      // their roughness (a stray return beside the surface).
      const double h = std::abs(normal[i].dot(points[i] - centroid[i]));
      if (planar[i] && h > options.spacings * median_spacing && h > options.roughness * rough[i]) {
        out[i] = 1;
        continue;
      }
      // Alone: farther than `isolated` × their own spacing from most of the nearest three points
      // whose neighbours span a plane (among its k nearest, else its 4k nearest), and off those
      // planes by more than 30° as seen from them. A sample between the lines of a scanner's
      // sweep lies along the surface (radar.xyz has points 5–28 of its lines' spacings from
      // them); a stray return lies along their normals, and one among other strays (their
      // neighbours span no plane) is measured against the surface points nearest it.
      const auto alone = [&](std::span<const std::uint32_t> candidates) {
        std::size_t asked = 0, off = 0;
        for (const std::uint32_t j : candidates) {
          if (j == i || !planar[j]) continue;
          const Eigen::Vector3d v = points[i] - points[j];
          off += v.norm() > options.isolated * spacing[j] && std::abs(normal[j].dot(v)) > 0.5 * v.norm();
          if (++asked == 3) break;
        }
        return asked == 0 ? -1 : int(2 * off > asked);
      };
      int verdict = alone(std::span<const std::uint32_t>(nb, k));
      if (verdict < 0) {
        index.nearest(points[i], 4 * k + 1, wide);
        wide_ids.clear();
        for (const auto& [j, d2] : wide) wide_ids.push_back(j);
        verdict = alone(wide_ids);
      }
      if (verdict > 0) out[i] = 1;
    }
  });
  std::vector<std::uint32_t> ids;
  for (std::size_t i = 0; i < n; ++i)
    if (out[i]) ids.push_back(std::uint32_t(i));
  return ids;
}

}  // namespace

std::vector<std::uint32_t> find_outliers(std::span<const Eigen::Vector3d> points, const OutlierOptions& options) {
  // Outliers among outliers (a scatter of stray returns, each the others' nearest) span no plane
  // and look alone to no one: each pass finds those beside the surface, and the next pass sees
  // the rest without them.
  std::vector<std::uint32_t> ids(points.size());
  std::iota(ids.begin(), ids.end(), 0u);
  std::vector<Eigen::Vector3d> kept(points.begin(), points.end());
  std::vector<std::uint32_t> all;
  for (int pass = 0; pass < options.passes; ++pass) {
    const std::vector<std::uint32_t> found = outliers_once(kept, options);
    if (found.empty()) break;
    std::vector<std::uint8_t> drop(kept.size(), 0);
    for (const auto k : found) drop[k] = 1, all.push_back(ids[k]);
    std::size_t w = 0;
    for (std::size_t k = 0; k < kept.size(); ++k)
      if (!drop[k]) kept[w] = kept[k], ids[w] = ids[k], ++w;
    kept.resize(w);
    ids.resize(w);
  }
  std::sort(all.begin(), all.end());
  return all;
}

}  // namespace quadrix
