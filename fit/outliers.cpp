#include "fit/outliers.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <numeric>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
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
  std::vector<double> spacing(n), rough(n);
  std::vector<Eigen::Vector3d> centroid(n), normal(n);
  std::vector<std::uint8_t> planar(n, 0);
  const auto order = index.order();  // visited in Morton order (PointIndex::order)
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    std::vector<Neighbour> nb;
    for (std::size_t o = r.begin(); o != r.end(); ++o) {
      const std::size_t i = order[o];
      index.nearest(points[i], k + 1, nb);
      std::size_t m = 0;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const auto& [j, d2] : nb)  // the point itself left out (a coincident copy stays)
        if (j != i && m < k) near[i * k + m++] = j, c += points[j];
      for (std::size_t q = m; q < k; ++q) near[i * k + q] = near[i * k];
      spacing[i] = (points[near[i * k + std::min(kSpacing, m) - 1]] - points[i]).norm();
      c /= double(m);
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      for (std::size_t q = 0; q < m; ++q) C += (points[near[i * k + q]] - c) * (points[near[i * k + q]] - c).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
      const double l0 = std::max(0.0, eig.eigenvalues()(0));
      centroid[i] = c;
      normal[i] = eig.eigenvectors().col(0);
      rough[i] = std::sqrt(l0 / double(m));
      // Spread over a plane: thin across it, and not along a line (a row of a grid, a scanner's
      // line: any plane through it fits).
      planar[i] = eig.eigenvalues()(1) > 16.0 * l0 && eig.eigenvalues()(1) > 0.02 * eig.eigenvalues()(2);
    }
  });
  std::vector<std::uint8_t> out(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    std::vector<double> s(k);
    std::vector<Neighbour> wide;
    std::vector<std::uint32_t> wide_ids;
    for (std::size_t o = r.begin(); o != r.end(); ++o) {
      const std::size_t i = order[o];
      const std::uint32_t* nb = &near[i * k];
      for (std::size_t q = 0; q < k; ++q) s[q] = spacing[nb[q]];
      std::nth_element(s.begin(), s.begin() + k / 2, s.end());
      const double median_spacing = s[k / 2];
      if (!(median_spacing > 0)) continue;
      // Off its neighbours' plane by more than `spacings` of their spacing and `roughness` of
      // their roughness (a stray return beside the surface).
      const double h = std::abs(normal[i].dot(points[i] - centroid[i]));
      // Seen from their centroid it rises more than 30° off the plane: a sparse point beside a
      // dense patch of a curved surface lies off that patch's plane by its curvature, along it.
      if (planar[i] && h > options.spacings * median_spacing && h > options.roughness * rough[i] &&
          h > 0.5 * (points[i] - centroid[i]).norm()) {
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
          if (j == i || !planar[j] || !(spacing[j] > 0)) continue;
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

std::vector<std::uint32_t> distinct_positions(std::span<const Eigen::Vector3d> points, std::vector<std::uint32_t>& position) {
  std::vector<std::uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  const auto key = [&](std::uint32_t a) { return std::tie(points[a].x(), points[a].y(), points[a].z(), a); };
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
  // Numbered by first copy, so the distinct positions keep the input's order.
  std::vector<std::uint32_t> first;
  std::vector<std::uint32_t> group(points.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (k == 0 || points[order[k]] != points[order[k - 1]]) first.push_back(order[k]);
    group[order[k]] = std::uint32_t(first.size() - 1);
  }
  std::vector<std::uint32_t> rank(first.size());
  std::iota(rank.begin(), rank.end(), 0u);
  std::sort(rank.begin(), rank.end(), [&](std::uint32_t a, std::uint32_t b) { return first[a] < first[b]; });
  std::vector<std::uint32_t> renumber(first.size());
  for (std::size_t r = 0; r < rank.size(); ++r) renumber[rank[r]] = std::uint32_t(r);
  position.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) position[i] = renumber[group[i]];
  std::vector<std::uint32_t> out(first.size());
  for (std::size_t g = 0; g < first.size(); ++g) out[renumber[g]] = first[g];
  return out;
}

std::vector<std::uint32_t> find_outliers(std::span<const Eigen::Vector3d> points, const OutlierOptions& options) {
  // Each position once: copies of a point (a merged or quantised scan) are its 6th neighbour at
  // distance 0, and every spacing would be 0 (a sphere written 7 times lost 18,606 of 21,000
  // points). The verdict on a position is its copies'.
  std::vector<std::uint32_t> position;
  const std::vector<std::uint32_t> first = distinct_positions(points, position);
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(first.size());
  for (const auto i : first) kept.push_back(points[i]);
  const std::size_t unique = kept.size();
  std::vector<std::uint32_t> ids(unique);
  std::iota(ids.begin(), ids.end(), 0u);
  std::vector<std::uint32_t> all;
  // Outliers among outliers (a scatter of stray returns, each the others' nearest) span no plane
  // and look alone to no one: each pass finds those beside the surface, and the next pass sees
  // the rest without them.
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
  std::vector<std::uint8_t> position_stray(unique, 0);
  for (const auto u : all) position_stray[u] = 1;
  std::vector<std::uint32_t> result;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (position_stray[position[i]]) result.push_back(std::uint32_t(i));
  return result;
}

std::vector<std::vector<std::uint32_t>> outlier_clumps(std::span<const Eigen::Vector3d> points,
                                                       std::span<const std::uint32_t> outliers, std::size_t least) {
  if (outliers.size() < std::max<std::size_t>(least, 2)) return {};
  std::vector<std::uint8_t> is_out(points.size(), 0);
  for (const auto i : outliers) is_out[i] = 1;
  std::vector<Eigen::Vector3d> kept, strays;
  std::vector<std::uint32_t> stray_id;
  for (std::size_t i = 0; i < points.size(); ++i) {
    (is_out[i] ? strays : kept).push_back(points[i]);
    if (is_out[i]) stray_id.push_back(std::uint32_t(i));
  }
  if (kept.empty()) return {};
  const PointIndex kept_index(kept), stray_index(strays);
  std::vector<double> to_kept(strays.size());
  std::vector<Neighbour> nb;
  for (std::size_t a = 0; a < strays.size(); ++a) {
    kept_index.nearest(strays[a], 1, nb);
    to_kept[a] = std::sqrt(nb[0].second);
  }
  // Linked: nearer each other than a fifth of their distance to the rest (strays scattered at
  // random lie about as far from each other as from the surface).
  constexpr double kTight = 0.2;
  std::vector<std::uint32_t> parent(strays.size());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto root = [&](std::uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (std::size_t a = 0; a < strays.size(); ++a) {
    stray_index.radius(strays[a], kTight * to_kept[a], nb);
    for (const auto& [b, d2] : nb)
      if (b != a && std::sqrt(d2) < kTight * std::min(to_kept[a], to_kept[b])) parent[root(std::uint32_t(a))] = root(b);
  }
  std::vector<std::vector<std::uint32_t>> groups(strays.size());
  for (std::size_t a = 0; a < strays.size(); ++a) groups[root(std::uint32_t(a))].push_back(stray_id[a]);
  std::erase_if(groups, [&](const auto& g) { return g.size() < least; });
  std::sort(groups.begin(), groups.end(), [](const auto& x, const auto& y) { return x.size() > y.size(); });
  return groups;
}

double estimate_noise(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                      const PointIndex& index, std::size_t samples, std::size_t neighbours) {
  const std::size_t n = points.size();
  if (n < neighbours || neighbours < 8) return 0.0;
  const bool with_normals = normals.size() == n;
  const std::size_t want = std::max<std::size_t>(1, samples);
  const std::size_t step = (n + want - 1) / want;  // at most `samples` points
  const std::size_t count = (n + step - 1) / step;
  std::vector<double> residual(count, -1.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbour> nb;
    std::vector<std::uint32_t> kept;
    for (std::size_t s = r.begin(); s != r.end(); ++s) {
      const std::size_t i = s * step;
      // The nearest on the point's own side: a neighbour whose normal turns more than 60° from
      // its own lies on the other side of a thin part (a plate 0.04 thick sampled every 0.02:
      // the quadric through both sides read their half-thickness as noise).
      index.nearest(points[i], with_normals ? 2 * neighbours : neighbours, nb);
      kept.clear();
      for (const auto& [j, d2] : nb) {
        if (kept.size() == neighbours) break;
        if (!with_normals || normals[j].dot(normals[i]) >= 0.5) kept.push_back(j);
      }
      if (kept.size() < neighbours) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const auto j : kept) mean += points[j];
      mean /= double(kept.size());
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      for (const auto j : kept) C += (points[j] - mean) * (points[j] - mean).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
      if (eig.info() != Eigen::Success) continue;
      const Eigen::Vector3d normal = eig.eigenvectors().col(0), u = eig.eigenvectors().col(2), w = eig.eigenvectors().col(1);
      // h = c₀ + c₁x + c₂y + c₃x² + c₄xy + c₅y² by least squares, in the PCA frame.
      Eigen::MatrixXd A(kept.size(), 6);
      Eigen::VectorXd h(kept.size());
      for (std::size_t k = 0; k < kept.size(); ++k) {
        const Eigen::Vector3d v = points[kept[k]] - mean;
        const double x = v.dot(u), y = v.dot(w);
        A.row(Eigen::Index(k)) << 1.0, x, y, x * x, x * y, y * y;
        h[Eigen::Index(k)] = v.dot(normal);
      }
      const Eigen::VectorXd c = A.colPivHouseholderQr().solve(h);
      if (!c.allFinite()) continue;
      residual[s] = std::sqrt((A * c - h).squaredNorm() / double(kept.size() - 6));
    }
  });
  std::erase_if(residual, [](double r) { return r < 0.0; });
  if (residual.empty()) return 0.0;
  std::nth_element(residual.begin(), residual.begin() + std::ptrdiff_t(residual.size() / 2), residual.end());
  return residual[residual.size() / 2];
}

}  // namespace quadrix
