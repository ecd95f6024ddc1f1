// Conforming bisection of a grid's Kuhn triangulation: volume kept, faces shared, no T-junction
// at the seam with the cells left whole.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <Eigen/Geometry>

#include "convert/kuhn_bisection.h"
#include "core/error.h"

using namespace quadrix;

namespace {

using Face = std::array<std::array<int, 3>, 3>;

std::array<int, 3> as_array(const Eigen::Vector3i& p) { return {p.x(), p.y(), p.z()}; }

Face face_of(const std::array<Eigen::Vector3i, 4>& t, int skip) {
  Face f;
  int k = 0;
  for (int i = 0; i < 4; ++i)
    if (i != skip) f[k++] = as_array(t[i]);
  std::sort(f.begin(), f.end());
  return f;
}

long six_volume(const std::array<Eigen::Vector3i, 4>& t) {
  const Eigen::Vector3d a = (t[1] - t[0]).cast<double>(), b = (t[2] - t[0]).cast<double>(), c = (t[3] - t[0]).cast<double>();
  return std::lround(std::abs(a.dot(b.cross(c))));
}

/// The six Kuhn tetrahedra of the cell at c (lattice scale s).
std::vector<std::array<Eigen::Vector3i, 4>> kuhn(const Eigen::Vector3i& c, int s) {
  constexpr int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  std::vector<std::array<Eigen::Vector3i, 4>> out;
  for (const auto& p : perms) {
    std::array<Eigen::Vector3i, 4> t;
    t[0] = c * s;
    for (int k = 0; k < 3; ++k) t[k + 1] = t[k] + s * Eigen::Vector3i::Unit(p[k]);
    out.push_back(t);
  }
  return out;
}

/// Faces used once, but those on the grid's own boundary (0 or `end` on an axis): where the
/// union of the tetrahedra meets other cells of the grid.
std::set<Face> boundary(const std::vector<std::array<Eigen::Vector3i, 4>>& tets, const Eigen::Vector3i& end,
                        std::size_t* shared_thrice = nullptr) {
  const auto on_grid_boundary = [&](const Face& f) {
    for (int axis = 0; axis < 3; ++axis)
      for (const int plane : {0, end[axis]})
        if (f[0][axis] == plane && f[1][axis] == plane && f[2][axis] == plane) return true;
    return false;
  };
  std::map<Face, int> uses;
  for (const auto& t : tets)
    for (int k = 0; k < 4; ++k) ++uses[face_of(t, k)];
  std::set<Face> out;
  for (const auto& [f, n] : uses) {
    if (n == 1 && !on_grid_boundary(f)) out.insert(f);
    if (n > 2 && shared_thrice) ++*shared_thrice;
  }
  return out;
}

}  // namespace

TEST(KuhnBisection, RefinedCellsConformAndMeetTheWholeCellsAlongUncutFaces) {
  const Eigen::Vector3i cells(5, 4, 4);
  constexpr int levels = 3, s = 1 << levels;
  const std::vector<KuhnCellDepth> wanted = {{{1, 1, 1}, 3}, {{2, 1, 1}, 1}, {{3, 3, 2}, 2}, {{4, 0, 0}, 3}, {{9, 0, 0}, 1}};
  const KuhnRefinement r = refine_kuhn_cells(cells, wanted, levels);
  ASSERT_EQ(r.levels, levels);
  // The requested cells (the one outside the grid aside) and more: the closure reaches neighbours.
  std::set<std::array<int, 3>> taken;
  for (const auto& c : r.cells) taken.insert(as_array(c));
  for (const auto& w : wanted) {
    if ((w.cell.array() < cells.array()).all()) {
      EXPECT_TRUE(taken.contains(as_array(w.cell)));
    }
  }
  EXPECT_FALSE(taken.contains({9, 0, 0}));
  EXPECT_GT(taken.size(), 4u);
  // The volume of the cells taken, none degenerate.
  long volume = 0;
  for (const auto& t : r.tets) {
    const long v = six_volume(t);
    EXPECT_GT(v, 0);
    volume += v;
  }
  EXPECT_EQ(volume, static_cast<long>(taken.size()) * 6 * s * s * s);
  // Conforming: every face in one or two tetrahedra; inside the grid, the faces used once are
  // exactly the boundary faces of the same cells split plainly, so the whole cells beside them
  // share every face whole (no T-junction at the seam).
  std::size_t thrice = 0;
  const std::set<Face> refined_boundary = boundary(r.tets, cells * s, &thrice);
  EXPECT_EQ(thrice, 0u);
  std::vector<std::array<Eigen::Vector3i, 4>> plain;
  for (const auto& c : r.cells)
    for (const auto& t : kuhn(c, s)) plain.push_back(t);
  EXPECT_FALSE(refined_boundary.empty());
  EXPECT_EQ(refined_boundary, boundary(plain, cells * s));
  // Each requested cell cut down to its depth: tetrahedra of (s / 2^depth)³ / 6 at most.
  for (const auto& w : wanted) {
    if (!(w.cell.array() < cells.array()).all()) continue;
    const int side = s >> w.depth;
    std::size_t inside = 0;
    for (const auto& t : r.tets) {
      const Eigen::Vector3i sum = t[0] + t[1] + t[2] + t[3];
      if (((sum.array() > 4 * s * w.cell.array()) && (sum.array() < 4 * s * (w.cell.array() + 1))).all()) {
        ++inside;
        EXPECT_LE(six_volume(t), static_cast<long>(side) * side * side);
      }
    }
    // At least its own depth's count; more where a deeper neighbour's closure cut it further.
    EXPECT_GE(inside, static_cast<std::size_t>(6) << (3 * w.depth)) << "cell " << w.cell.transpose();
  }
}

TEST(KuhnBisection, BadLevelsRefused) {
  const std::vector<KuhnCellDepth> none;
  EXPECT_THROW(refine_kuhn_cells({4, 4, 4}, none, 0), InvalidInput);
  EXPECT_THROW(refine_kuhn_cells({1 << 20, 4, 4}, none, 3), InvalidInput);
}
