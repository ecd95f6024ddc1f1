#include "core/bvh.h"

#include <algorithm>
#include <numeric>

namespace quadrix {
namespace {

struct Builder {
  std::span<const Box3> boxes;
  std::vector<Eigen::Vector3d> centres;
  std::vector<Bvh::Node>& nodes;
  std::vector<std::uint32_t>& items;
  int leaf_size;

  // Depth-first layout: a node's left child is the next node; `first` holds the right child.
  void build(std::uint32_t begin, std::uint32_t end, int depth) {
    const auto index = static_cast<std::uint32_t>(nodes.size());
    nodes.push_back({});
    Box3 box, cbox;
    for (std::uint32_t i = begin; i < end; ++i) {
      box.extend(boxes[items[i]]);
      cbox.extend(centres[items[i]]);
    }
    nodes[index].min = box.min;
    nodes[index].max = box.max;
    const std::uint32_t count = end - begin;
    int axis = 0;
    const double extent = (cbox.max - cbox.min).maxCoeff(&axis);
    // Depth is bounded by the median split (log₂ n); 100 guards the traversal stack.
    if (count <= static_cast<std::uint32_t>(leaf_size) || !(extent > 0.0) || depth >= 100) {
      nodes[index].first = begin;
      nodes[index].count = count;
      return;
    }
    const std::uint32_t mid = begin + count / 2;
    std::nth_element(items.begin() + begin, items.begin() + mid, items.begin() + end,
                     [&](std::uint32_t a, std::uint32_t b) { return centres[a][axis] < centres[b][axis]; });
    build(begin, mid, depth + 1);
    const auto right = static_cast<std::uint32_t>(nodes.size());
    build(mid, end, depth + 1);
    nodes[index].first = right;
    nodes[index].count = 0;
  }
};

}  // namespace

Bvh::Bvh(std::span<const Box3> boxes, int leaf_size) {
  const std::size_t n = boxes.size();
  if (n == 0) return;
  items_.resize(n);
  std::iota(items_.begin(), items_.end(), 0u);
  Builder b{boxes, {}, nodes_, items_, std::max(1, leaf_size)};
  b.centres.resize(n);
  for (std::size_t i = 0; i < n; ++i) b.centres[i] = boxes[i].centre();
  nodes_.reserve(2 * n / b.leaf_size + 2);
  b.build(0, static_cast<std::uint32_t>(n), 0);
}

}  // namespace quadrix
