#include "core/model.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix {

Box3 bounds(const SlimPatch& s) {
  const Eigen::Vector3d r = Eigen::Vector3d::Constant(s.radius);
  return {s.centre - r, s.centre + r};
}

Box3 bounds(const TetPatch& t) {
  Box3 b;
  for (const auto& p : t.corners) b.extend(p);
  return b;
}

Box3 bounds(const Glyph& g) {
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
  switch (g.kind) {
    case GlyphKind::sphere: half.setConstant(g.radius); break;
    case GlyphKind::ellipsoid:
      // Extent of an ellipsoid x = centre + axes·u, ‖u‖ ≤ 1, along each world axis.
      half = g.axes.rowwise().norm();
      break;
    case GlyphKind::cylinder: {
      const Eigen::Vector3d a = g.axes.col(0);
      const double len2 = a.squaredNorm();
      // Disc of radius r perpendicular to a: extent r·sqrt(1 − (a_i/|a|)²) per axis.
      for (int i = 0; i < 3; ++i) {
        const double s = len2 > 0 ? std::sqrt(std::max(0.0, 1.0 - a[i] * a[i] / len2)) : 1.0;
        half[i] = std::abs(a[i]) + g.radius * s;
      }
      break;
    }
  }
  return {g.centre - half, g.centre + half};
}

namespace {

/// Depth of every ball (roots 1), or the id of a ball on a cycle through `cycle`.
std::vector<std::size_t> depths(const SlimHierarchy& h, std::int64_t& cycle) {
  const std::size_t n = h.size();
  std::vector<std::size_t> depth(n, 0);  // 0: not yet known
  std::vector<std::size_t> path;
  cycle = -1;
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t j = i;
    path.clear();
    // Walk up until a known depth or a root; a walk longer than n is a cycle.
    while (depth[j] == 0) {
      path.push_back(j);
      if (path.size() > n) {
        cycle = static_cast<std::int64_t>(j);
        return depth;
      }
      if (h.parent[j] < 0) break;
      j = static_cast<std::size_t>(h.parent[j]);
    }
    std::size_t d = depth[j] == 0 ? 0 : depth[j];
    for (auto it = path.rbegin(); it != path.rend(); ++it) depth[*it] = ++d;
  }
  return depth;
}

void require_valid(const Model& m) {
  if (const std::string why = validate_slim_hierarchy(m); !why.empty())
    throw InvalidInput("invalid SLIM hierarchy: " + why);
}

}  // namespace

std::string validate_slim_hierarchy(const Model& m) {
  const SlimHierarchy& h = m.slim_hierarchy;
  if (h.empty()) return h.others.empty() ? "" : "balls outside the drawn set but no parent links";
  const std::size_t n = m.slims.size() + h.others.size();
  if (h.parent.size() != n || h.error.size() != n)
    return fmt::format("{} balls but {} parent links and {} errors", n, h.parent.size(), h.error.size());
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t p = h.parent[i];
    if (p < -1 || p >= static_cast<std::int64_t>(n)) return fmt::format("ball {}: parent {} is not in [-1, {})", i, p, n);
    if (p == static_cast<std::int64_t>(i)) return fmt::format("ball {}: parent {} is itself", i, p);
    if (!std::isfinite(h.error[i]) || h.error[i] < 0)
      return fmt::format("ball {}: error {} is not finite and >= 0", i, h.error[i]);
  }
  std::int64_t cycle = -1;
  depths(h, cycle);
  if (cycle >= 0) return fmt::format("ball {}: its parent links form a cycle", cycle);
  return {};
}

SlimHierarchyStats slim_hierarchy_stats(const Model& m) {
  require_valid(m);
  const SlimHierarchy& h = m.slim_hierarchy;
  SlimHierarchyStats s;
  if (h.empty()) return s;
  std::int64_t cycle = -1;
  const std::vector<std::size_t> depth = depths(h, cycle);
  std::vector<char> has_child(h.size(), 0);
  for (std::int32_t p : h.parent)
    if (p >= 0) has_child[static_cast<std::size_t>(p)] = 1;
  for (std::size_t i = 0; i < h.size(); ++i) {
    s.levels = std::max(s.levels, depth[i]);
    (has_child[i] ? s.interior : s.leaves) += 1;
    s.roots += h.parent[i] < 0;
  }
  const auto [lo, hi] = std::minmax_element(h.error.begin(), h.error.end());
  s.min_error = *lo;
  s.max_error = *hi;
  return s;
}

std::vector<std::int32_t> select_slim_cut(const Model& m, double max_error) {
  require_valid(m);
  const SlimHierarchy& h = m.slim_hierarchy;
  std::vector<std::int32_t> cut;
  if (h.empty()) {
    cut.resize(m.slims.size());
    for (std::size_t i = 0; i < cut.size(); ++i) cut[i] = static_cast<std::int32_t>(i);
    return cut;
  }
  // Children as a CSR table, then a depth-first walk from every root.
  const std::size_t n = h.size();
  std::vector<std::size_t> first(n + 1, 0);
  for (std::int32_t p : h.parent)
    if (p >= 0) ++first[static_cast<std::size_t>(p) + 1];
  for (std::size_t i = 0; i < n; ++i) first[i + 1] += first[i];
  std::vector<std::int32_t> child(first[n]);
  std::vector<std::size_t> fill(first.begin(), first.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    if (h.parent[i] >= 0) child[fill[static_cast<std::size_t>(h.parent[i])]++] = static_cast<std::int32_t>(i);
  std::vector<std::int32_t> stack;
  for (std::size_t i = 0; i < n; ++i)
    if (h.parent[i] < 0) stack.push_back(static_cast<std::int32_t>(i));
  while (!stack.empty()) {
    const auto b = static_cast<std::size_t>(stack.back());
    stack.pop_back();
    if (first[b] == first[b + 1] || (max_error >= 0 && h.error[b] <= max_error)) {
      cut.push_back(static_cast<std::int32_t>(b));
      continue;
    }
    for (std::size_t k = first[b]; k < first[b + 1]; ++k) stack.push_back(child[k]);
  }
  std::sort(cut.begin(), cut.end());
  return cut;
}

Box3 bounds(const Model& m) {
  Box3 b;
  for (const auto& s : m.slims) b.extend(bounds(s));
  for (const auto& t : m.tets) b.extend(bounds(t));
  for (const auto& g : m.glyphs) b.extend(bounds(g));
  for (const auto& s : m.implicits) b.extend(s.bounds);
  return b;
}

std::optional<double> metadata_number(const Model& model, const std::string& key) {
  const auto it = model.metadata.find(key);
  if (it == model.metadata.end()) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str()) return std::nullopt;
  return v;
}

}  // namespace quadrix
