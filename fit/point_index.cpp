#include "fit/point_index.h"

#include <nanoflann.hpp>

#include "core/morton.h"

namespace quadrix {
namespace {

struct Adaptor {
  const std::vector<Eigen::Vector3d>* points;
  std::size_t kdtree_get_point_count() const { return points->size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return (*points)[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor>, Adaptor, 3,
                                                 std::uint32_t>;

}  // namespace

// The tree is built over a copy of the points in Morton order, so that a leaf's points lie
// together in memory (the tree reads them through its permutation): on 1M points sampled from
// the armadillo in random order, one build took 0.12 s instead of 0.31 s and a 12-nearest query
// 2.3 µs instead of 3.6 µs (1.0 µs when the queries come in Morton order too). Answers carry
// the caller's indices. (Before, the tree was also built twice: nanoflann 1.4's constructor
// builds it, and buildIndex() was called again.)
struct PointIndex::Impl {
  std::vector<std::uint32_t> original;  // sorted[k] is the caller's point original[k]
  std::vector<Eigen::Vector3d> sorted;
  Adaptor adaptor;
  Tree tree;  // nanoflann 1.4 builds the tree in its constructor (once: the points are in place by then)
  explicit Impl(std::span<const Eigen::Vector3d> p)
      : original(morton_order(p)), sorted(in_order(p, original)), adaptor{&sorted},
        tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
  static std::vector<Eigen::Vector3d> in_order(std::span<const Eigen::Vector3d> p, const std::vector<std::uint32_t>& order) {
    std::vector<Eigen::Vector3d> out(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) out[k] = p[order[k]];
    return out;
  }
};

PointIndex::PointIndex(std::span<const Eigen::Vector3d> points) : impl_(std::make_unique<Impl>(points)) {}
PointIndex::~PointIndex() = default;
PointIndex::PointIndex(PointIndex&&) noexcept = default;
PointIndex& PointIndex::operator=(PointIndex&&) noexcept = default;

std::size_t PointIndex::size() const { return impl_->sorted.size(); }
std::span<const std::uint32_t> PointIndex::order() const { return impl_->original; }

void PointIndex::radius(const Eigen::Vector3d& q, double r, std::vector<Neighbour>& out, bool sorted) const {
  out.clear();
  nanoflann::SearchParams params;
  params.sorted = sorted;
  impl_->tree.radiusSearch(q.data(), r * r, out, params);
  for (auto& n : out) n.first = impl_->original[n.first];
}

void PointIndex::nearest(const Eigen::Vector3d& q, std::size_t k, std::vector<Neighbour>& out) const {
  k = std::min(k, size());
  // Per-thread buffers, not two allocations per query.
  thread_local std::vector<std::uint32_t> idx;
  thread_local std::vector<double> d2;
  if (idx.size() < k) idx.resize(k), d2.resize(k);
  const std::size_t found = impl_->tree.knnSearch(q.data(), k, idx.data(), d2.data());
  out.resize(found);
  for (std::size_t i = 0; i < found; ++i) out[i] = {impl_->original[idx[i]], d2[i]};
}

}  // namespace quadrix
