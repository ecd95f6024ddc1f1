#include "core/slim_lod.h"

#include <nanoflann.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "core/error.h"
#include "core/slim.h"

namespace quadrix {
namespace {

void require_valid(const Model& m) {
  if (const std::string why = validate_slim_hierarchy(m); !why.empty())
    throw InvalidInput("invalid SLIM hierarchy: " + why);
}

// `slim_hierarchy_error distance` (fit --lod-levels) says the errors are distances; without that
// line, a .slim2t's are Kanai's fitting energies.
bool errors_are_energies(const Model& m) {
  if (const auto unit = m.metadata.find("slim_hierarchy_error"); unit != m.metadata.end()) return unit->second != "distance";
  const auto it = m.metadata.find("source_format");
  return it != m.metadata.end() && it->second == "slim2t";
}

/// Children as a CSR table and the balls in breadth-first order from the roots (parents first).
struct Tree {
  std::vector<std::uint32_t> first;
  std::vector<std::int32_t> child, roots, order;
};

Tree make_tree(const SlimHierarchy& h) {
  const std::size_t n = h.size();
  Tree t;
  t.first.assign(n + 1, 0);
  for (std::int32_t p : h.parent)
    if (p >= 0) ++t.first[static_cast<std::size_t>(p) + 1];
  for (std::size_t i = 0; i < n; ++i) t.first[i + 1] += t.first[i];
  t.child.resize(t.first[n]);
  std::vector<std::uint32_t> fill(t.first.begin(), t.first.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    if (h.parent[i] >= 0) t.child[fill[static_cast<std::size_t>(h.parent[i])]++] = static_cast<std::int32_t>(i);
    else t.roots.push_back(static_cast<std::int32_t>(i));
  }
  t.order = t.roots;
  t.order.reserve(n);
  for (std::size_t k = 0; k < t.order.size(); ++k) {
    const auto b = static_cast<std::size_t>(t.order[k]);
    t.order.insert(t.order.end(), t.child.begin() + t.first[b], t.child.begin() + t.first[b + 1]);
  }
  return t;
}

struct SampleCloud {
  std::vector<Eigen::Vector3d> points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};
using SampleTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, SampleCloud>, SampleCloud,
                                                       3, std::uint32_t>;

constexpr int kSampleGrid = 2;
constexpr std::size_t kNearest = 8;  // nearest leaves whose quadrics refine a distance

// Taubin distance from a ball's quadric to a world point, world units (capped at 2R: a flat spot
// of g away from its zero set).
double ball_distance(const SlimPatch& ball, const Eigen::Vector3d& p) {
  const double d = ball.local.taubin_distance((p - ball.centre) / ball.radius) * ball.radius;
  return std::isfinite(d) ? std::min(d, 2 * ball.radius) : 2 * ball.radius;
}

// Two-sided, per ball, against the leaves directly: (1) the leaves' zero-set samples below it
// that lie in its ball, to its quadric (samples outside it, a hole, by their distance to the
// ball); (2) its own zero-set samples to the nearest leaf sample, or nearer, the quadric of one
// of the 8 nearest leaves whose ball holds the sample: spurious sheets of a merged ball count.
std::vector<double> measure_errors(const Model& m, const Tree& t) {
  const SlimHierarchy& h = m.slim_hierarchy;
  const std::size_t n = h.size();
  std::vector<std::int32_t> leaves, interior;
  for (std::size_t b = 0; b < n; ++b)
    (t.first[b] == t.first[b + 1] ? leaves : interior).push_back(static_cast<std::int32_t>(b));
  // The leaves' samples (the full-detail surface) and the leaf each came from.
  std::vector<std::vector<SlimSurfaceSample>> per_leaf(leaves.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 256), [&](const auto& range) {
    for (std::size_t k = range.begin(); k < range.end(); ++k)
      sample_slim_patch(slim_ball(m, static_cast<std::size_t>(leaves[k])), kSampleGrid, per_leaf[k]);
  });
  SampleCloud cloud;
  std::vector<std::int32_t> owner;
  for (std::size_t k = 0; k < leaves.size(); ++k)
    for (const SlimSurfaceSample& s : per_leaf[k]) cloud.points.push_back(s.point), owner.push_back(leaves[k]);
  std::vector<double> err(n, 0.0);
  if (cloud.points.empty()) return err;
  // (1) leaves → ancestors.
  tbb::enumerable_thread_specific<std::vector<double>> partial([n] { return std::vector<double>(n, 0.0); });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 256), [&](const auto& range) {
    std::vector<double>& e = partial.local();
    for (std::size_t k = range.begin(); k < range.end(); ++k)
      for (const SlimSurfaceSample& s : per_leaf[k])
        for (std::int32_t a = h.parent[static_cast<std::size_t>(leaves[k])]; a >= 0; a = h.parent[static_cast<std::size_t>(a)]) {
          const SlimPatch& ball = slim_ball(m, static_cast<std::size_t>(a));
          const double outside = (s.point - ball.centre).norm() - ball.radius;
          // A leaf sample outside the ball is a hole the ball would leave: it counts by its
          // distance to the ball (a nearest-parent hierarchy of independent fits leaves seams).
          const double d = outside <= 0 ? ball_distance(ball, s.point) : outside;
          e[static_cast<std::size_t>(a)] = std::max(e[static_cast<std::size_t>(a)], d);
        }
  });
  for (const auto& p : partial)
    for (std::size_t b = 0; b < n; ++b) err[b] = std::max(err[b], p[b]);
  // (2) each merged ball's zero set → the leaves' surface: the nearest leaf sample, or nearer, the
  // quadric of one of the nearest leaves whose ball holds the point.
  // (nanoflann 1.4 builds each tree in its constructor.)
  const SampleTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  SampleCloud leaf_centres;
  for (std::int32_t leaf : leaves) leaf_centres.points.push_back(slim_ball(m, static_cast<std::size_t>(leaf)).centre);
  const SampleTree centre_tree(3, leaf_centres, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, interior.size(), 64), [&](const auto& range) {
    std::vector<SlimSurfaceSample> samples;
    for (std::size_t k = range.begin(); k < range.end(); ++k) {
      const auto b = static_cast<std::size_t>(interior[k]);
      samples.clear();
      sample_slim_patch(slim_ball(m, b), kSampleGrid, samples);
      double worst = 0;
      for (const SlimSurfaceSample& s : samples) {
        std::uint32_t j = 0;
        double d2 = 0;
        tree.knnSearch(s.point.data(), 1, &j, &d2);
        double d = std::sqrt(d2);
        std::uint32_t near[kNearest];
        double near_d2[kNearest];
        const std::size_t found = centre_tree.knnSearch(s.point.data(), kNearest, near, near_d2);
        for (std::size_t q = 0; q < found; ++q) {
          const SlimPatch& leaf = slim_ball(m, static_cast<std::size_t>(leaves[near[q]]));
          if (near_d2[q] <= leaf.radius * leaf.radius) d = std::min(d, ball_distance(leaf, s.point));
        }
        worst = std::max(worst, d);
      }
      err[b] = std::max(err[b], worst);  // one writer per ball
    }
  });
  return err;
}

std::vector<double> errors_of(const Model& m, const Tree& t) {
  if (m.slim_hierarchy.empty()) return std::vector<double>(m.slims.size(), 0.0);
  if (errors_are_energies(m)) return measure_errors(m, t);
  return m.slim_hierarchy.error;
}

}  // namespace

std::vector<double> slim_lod_errors(const Model& model) {
  require_valid(model);
  return errors_of(model, make_tree(model.slim_hierarchy));
}

SlimLod::SlimLod(const Model& m) {
  require_valid(m);
  const SlimHierarchy& h = m.slim_hierarchy;
  const std::size_t n = h.empty() ? m.slims.size() : h.size();
  centre_.resize(n);
  radius_.resize(n);
  for (std::size_t b = 0; b < n; ++b) {
    const SlimPatch& s = slim_ball(m, b);
    centre_[b] = s.centre;
    radius_[b] = s.radius;
  }
  height_.assign(n, 0);
  if (h.empty()) {
    error_.assign(n, 0.0);
    return;
  }
  Tree t = make_tree(h);
  error_ = errors_of(m, t);
  reach_ = radius_;
  for (auto it = t.order.rbegin(); it != t.order.rend(); ++it) {
    const auto b = static_cast<std::size_t>(*it);
    if (h.parent[b] >= 0) {
      const auto p = static_cast<std::size_t>(h.parent[b]);
      height_[p] = std::max(height_[p], height_[b] + 1u);
      reach_[p] = std::max(reach_[p], (centre_[b] - centre_[p]).norm() + reach_[b]);
    }
    levels_ = std::max<std::size_t>(levels_, height_[b] + 1);
  }
  first_child_ = std::move(t.first);
  child_ = std::move(t.child);
  roots_ = std::move(t.roots);
}

SlimLodCut SlimLod::cut(const Camera& camera, const SlimLodOptions& options) const {
  SlimLodCut c;
  c.level_counts.assign(levels_, 0);
  if (roots_.empty()) {
    c.balls.resize(centre_.size());
    for (std::size_t i = 0; i < c.balls.size(); ++i) c.balls[i] = static_cast<std::int32_t>(i);
    c.level_counts[0] = c.balls.size();
    return c;
  }
  // A length e at eye-space depth z spans e·focal/z pixels; test e·focal ≤ P·z at the ball's
  // nearest depth (the near plane for a ball around or behind the eye).
  const double focal = 0.5 * camera.height / std::tan(0.5 * camera.fov_y_deg * std::numbers::pi / 180.0);
  const Eigen::Vector3d eye = camera.eye, forward = camera.forward();
  const double P = options.pixel_error;
  // The frustum's side planes in eye coordinates (x right, y up, z along the view).
  const Eigen::Vector3d right = forward.cross(camera.up).normalized(), up = right.cross(forward);
  const double ty = std::tan(0.5 * camera.fov_y_deg * std::numbers::pi / 180.0);
  const double tx = ty * camera.width / std::max(camera.height, 1);
  const double cy = 1 / std::sqrt(1 + ty * ty), cx = 1 / std::sqrt(1 + tx * tx);
  const auto outside = [&](const Eigen::Vector3d& centre, double r) {
    const Eigen::Vector3d d = centre - eye;
    const double x = d.dot(right), y = d.dot(up), z = d.dot(forward);
    return z + r < camera.near_plane || z - r > camera.far_plane || (std::abs(x) - z * tx) * cx > r ||
           (std::abs(y) - z * ty) * cy > r;
  };
  std::vector<std::int32_t> stack(roots_.rbegin(), roots_.rend());
  while (!stack.empty()) {
    const auto b = static_cast<std::size_t>(stack.back());
    stack.pop_back();
    const bool leaf = first_child_[b] == first_child_[b + 1];
    if (!leaf && P > 0) {
      const double z = std::max(camera.near_plane, (centre_[b] - eye).dot(forward) - radius_[b]);
      const bool hidden = options.skip_outside_view && outside(centre_[b], reach_[b]);
      if (hidden || error_[b] * focal <= P * z) {
        c.balls.push_back(static_cast<std::int32_t>(b));
        c.outside_view += hidden;
        continue;
      }
    }
    if (leaf) {
      c.balls.push_back(static_cast<std::int32_t>(b));
      continue;
    }
    for (std::uint32_t k = first_child_[b]; k < first_child_[b + 1]; ++k) stack.push_back(child_[k]);
  }
  std::sort(c.balls.begin(), c.balls.end());
  for (std::int32_t b : c.balls) ++c.level_counts[height_[static_cast<std::size_t>(b)]];
  return c;
}

SlimLodCut select_slim_lod(const Model& model, const Camera& camera, const SlimLodOptions& options) {
  return SlimLod(model).cut(camera, options);
}

Model slim_cut_model(const Model& model, std::span<const std::int32_t> balls) {
  Model out;
  out.tets = model.tets;
  out.glyphs = model.glyphs;
  out.implicits = model.implicits;
  out.metadata = model.metadata;
  const std::size_t n = model.slim_hierarchy.empty() ? model.slims.size() : model.slim_hierarchy.size();
  out.slims.reserve(balls.size());
  for (std::int32_t b : balls) {
    if (b < 0 || static_cast<std::size_t>(b) >= n)
      throw InvalidInput(fmt::format("SLIM cut: ball {} is not in [0, {})", b, n));
    out.slims.push_back(slim_ball(model, static_cast<std::size_t>(b)));
  }
  return out;
}

}  // namespace quadrix
