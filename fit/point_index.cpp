#include "fit/point_index.h"

#include <nanoflann.hpp>

namespace quadrix {
namespace {

struct Adaptor {
  std::span<const Eigen::Vector3d> points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor>, Adaptor, 3,
                                                 std::uint32_t>;

}  // namespace

struct PointIndex::Impl {
  Adaptor adaptor;
  Tree tree;
  explicit Impl(std::span<const Eigen::Vector3d> p)
      : adaptor{p}, tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
    tree.buildIndex();
  }
};

PointIndex::PointIndex(std::span<const Eigen::Vector3d> points) : impl_(std::make_unique<Impl>(points)) {}
PointIndex::~PointIndex() = default;
PointIndex::PointIndex(PointIndex&&) noexcept = default;
PointIndex& PointIndex::operator=(PointIndex&&) noexcept = default;

std::size_t PointIndex::size() const { return impl_->adaptor.points.size(); }

void PointIndex::radius(const Eigen::Vector3d& q, double r, std::vector<Neighbour>& out, bool sorted) const {
  out.clear();
  nanoflann::SearchParams params;
  params.sorted = sorted;
  impl_->tree.radiusSearch(q.data(), r * r, out, params);
}

void PointIndex::nearest(const Eigen::Vector3d& q, std::size_t k, std::vector<Neighbour>& out) const {
  k = std::min(k, size());
  std::vector<std::uint32_t> idx(k);
  std::vector<double> d2(k);
  const std::size_t found = impl_->tree.knnSearch(q.data(), k, idx.data(), d2.data());
  out.resize(found);
  for (std::size_t i = 0; i < found; ++i) out[i] = {idx[i], d2[i]};
}

}  // namespace quadrix
