#include "convert/kuhn_bisection.h"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix {
namespace {

using Point = Eigen::Vector3i;

constexpr int kBits = 21;
constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
constexpr int kPermutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};

std::uint64_t key_of(const Point& p) {
  return static_cast<std::uint64_t>(p.x()) | static_cast<std::uint64_t>(p.y()) << kBits |
         static_cast<std::uint64_t>(p.z()) << (2 * kBits);
}

struct Edge {
  std::uint64_t a, b;  // a < b
  Edge(const Point& p, const Point& q) : a(key_of(p)), b(key_of(q)) {
    if (a > b) std::swap(a, b);
  }
  bool operator==(const Edge&) const = default;
};
struct EdgeHash {
  std::size_t operator()(const Edge& e) const {
    const std::uint64_t h = (e.a * 0x9E3779B97F4A7C15ull) ^ (e.b + 0x632BE59BD9B4E019ull + (e.a << 6));
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

/// Rivara's longest-edge bisection on the Kuhn tetrahedra of the cells it has taken in. A cell is
/// taken in (its six Kuhn tetrahedra added) before any edge it holds is cut, so the tetrahedra of
/// the cells never taken in meet the refined ones along uncut faces.
class KuhnRefiner {
 public:
  KuhnRefiner(const Point& cells, int levels) : cells_(cells), scale_(1 << levels) {}

  void refine_cell(const Point& cell, int depth) {
    if (!take_in(cell)) return;
    const int target = 3 * depth;
    const std::uint64_t k = key_of(cell);
    for (std::size_t i = 0; i < in_cell_.at(k).size(); ++i) {  // grows as its tetrahedra are cut
      const int t = in_cell_.at(k)[i];
      if (tets_[t].alive && tets_[t].generation < target) {
        const auto [a, b] = longest(t);
        split(tets_[t].p[a], tets_[t].p[b]);
      }
    }
  }

  KuhnRefinement result(int levels) && {
    KuhnRefinement out;
    out.levels = levels;
    out.cells = std::move(taken_);
    for (const Tet& t : tets_)
      if (t.alive) out.tets.push_back(t.p);
    return out;
  }

 private:
  struct Tet {
    std::array<Point, 4> p;
    int generation = 0;
    std::uint64_t cell = 0;
    bool alive = true;
  };

  bool take_in(const Point& cell) {
    if ((cell.array() < 0).any() || (cell.array() >= cells_.array()).any()) return false;
    const std::uint64_t k = key_of(cell);
    if (!in_cell_.emplace(k, std::vector<int>{}).second) return true;
    taken_.push_back(cell);
    for (const auto& perm : kPermutations) {
      std::array<Point, 4> p;
      p[0] = cell * scale_;
      for (int s = 0; s < 3; ++s) p[s + 1] = p[s] + scale_ * Point::Unit(perm[s]);
      add(p, 0, k);
    }
    return true;
  }

  void add(const std::array<Point, 4>& p, int generation, std::uint64_t cell) {
    const int t = static_cast<int>(tets_.size());
    tets_.push_back({p, generation, cell, true});
    in_cell_[cell].push_back(t);
    for (const auto& e : kEdges) around_[Edge(p[e[0]], p[e[1]])].push_back(t);
  }

  /// The longest edge of tetrahedron t (local corners), ties broken by the edge's key.
  std::pair<int, int> longest(int t) const {
    const auto& p = tets_[t].p;
    int best = 0;
    std::int64_t best_len = -1;
    Edge best_edge(p[0], p[1]);
    for (int i = 0; i < 6; ++i) {
      const Point d = p[kEdges[i][1]] - p[kEdges[i][0]];
      const std::int64_t len = d.cast<std::int64_t>().squaredNorm();
      const Edge e(p[kEdges[i][0]], p[kEdges[i][1]]);
      if (len > best_len || (len == best_len && (e.a > best_edge.a || (e.a == best_edge.a && e.b > best_edge.b)))) {
        best = i;
        best_len = len;
        best_edge = e;
      }
    }
    return {kEdges[best][0], kEdges[best][1]};
  }

  /// Cuts the edge (a, b) in every tetrahedron around it, after cutting first the longest edge of
  /// any of them whose longest edge it is not (lengths grow along that chain, so it ends).
  void split(const Point a, const Point b) {
    // The cells holding the edge are those whose closed box holds its midpoint.
    const Point twice = a + b;
    std::array<std::vector<int>, 3> options;
    for (int axis = 0; axis < 3; ++axis) {
      const int c = twice[axis] / (2 * scale_);  // lattice coordinates are never negative
      options[axis].push_back(c);
      if (twice[axis] % (2 * scale_) == 0) options[axis].push_back(c - 1);
    }
    for (const int x : options[0])
      for (const int y : options[1])
        for (const int z : options[2]) take_in({x, y, z});
    const Edge edge(a, b);
    for (;;) {
      const auto it = around_.find(edge);
      if (it == around_.end()) return;
      int other = -1;
      for (const int t : it->second) {
        const auto [i, j] = longest(t);
        if (!(Edge(tets_[t].p[i], tets_[t].p[j]) == edge)) {
          other = t;
          break;
        }
      }
      if (other < 0) break;
      const auto [i, j] = longest(other);
      split(tets_[other].p[i], tets_[other].p[j]);
    }
    const Point m = twice / 2;
    const std::vector<int> ring = around_.at(edge);
    for (const int t : ring) bisect(t, a, b, m);
  }

  void bisect(int t, const Point& a, const Point& b, const Point& m) {
    Tet& tet = tets_[t];
    tet.alive = false;
    for (const auto& e : kEdges) {
      auto& list = around_.at(Edge(tet.p[e[0]], tet.p[e[1]]));
      list.erase(std::find(list.begin(), list.end(), t));
      if (list.empty()) around_.erase(Edge(tet.p[e[0]], tet.p[e[1]]));
    }
    std::array<Point, 4> first = tet.p, second = tet.p;
    for (int i = 0; i < 4; ++i) {
      if (first[i] == a) first[i] = m;
      if (second[i] == b) second[i] = m;
    }
    const int generation = tet.generation + 1;
    const std::uint64_t cell = tet.cell;
    add(first, generation, cell);  // invalidates `tet`
    add(second, generation, cell);
  }

  Point cells_;
  int scale_;
  std::vector<Tet> tets_;
  std::unordered_map<Edge, std::vector<int>, EdgeHash> around_;  // edge → live tetrahedra holding it
  std::unordered_map<std::uint64_t, std::vector<int>> in_cell_;  // cell → its tetrahedra, cut or not
  std::vector<Point> taken_;
};

}  // namespace

KuhnRefinement refine_kuhn_cells(const Eigen::Vector3i& cells_per_axis, std::span<const KuhnCellDepth> wanted,
                                 int levels) {
  if (levels < 1 || levels > 8) throw InvalidInput(fmt::format("Kuhn refinement: {} levels (1 to 8)", levels));
  if (cells_per_axis.maxCoeff() >= (1 << (kBits - levels)) || (cells_per_axis.array() < 1).any())
    throw InvalidInput(fmt::format("Kuhn refinement: a grid of {}×{}×{} cells does not fit {} levels", cells_per_axis.x(),
                                   cells_per_axis.y(), cells_per_axis.z(), levels));
  KuhnRefiner refiner(cells_per_axis, levels);
  for (const KuhnCellDepth& w : wanted) refiner.refine_cell(w.cell, std::clamp(w.depth, 1, levels));
  return std::move(refiner).result(levels);
}

}  // namespace quadrix
