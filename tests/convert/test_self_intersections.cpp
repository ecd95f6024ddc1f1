// convert/self_intersections.h: crossing triangles found by CGAL's exact predicates on a soup,
// with what two triangles share (no vertex, one, an edge) told apart; vertices at one position
// are one vertex.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "convert/self_intersections.h"
#include "core/mesh_io.h"

using namespace quadrix;

namespace {

// The closed unit cube [0,1]³ as 12 outward triangles, moved by `at`.
void add_cube(PolygonMesh& m, const Eigen::Vector3d& at, double size = 1.0) {
  const int base = static_cast<int>(m.vertices.size());
  for (int i = 0; i < 8; ++i) m.vertices.push_back(at + size * Eigen::Vector3d(i & 1, (i >> 1) & 1, (i >> 2) & 1));
  const std::array<std::array<int, 4>, 6> quads{{{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
  for (const auto& f : quads) {
    m.add_face(std::array<int, 3>{base + f[0], base + f[1], base + f[2]});
    m.add_face(std::array<int, 3>{base + f[0], base + f[2], base + f[3]});
  }
}

// The same triangles with three vertices of their own each (an STL read without merging).
PolygonMesh as_soup(const PolygonMesh& m) {
  PolygonMesh s;
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    std::array<int, 3> ids{};
    for (int k = 0; k < 3; ++k) {
      ids[std::size_t(k)] = static_cast<int>(s.vertices.size());
      s.vertices.push_back(m.vertices[std::size_t(m.face(f)[std::size_t(k)])]);
    }
    s.add_face(ids);
  }
  return s;
}

PolygonMesh two_triangles(const std::array<Eigen::Vector3d, 3>& a, const std::array<Eigen::Vector3d, 3>& b) {
  PolygonMesh m;
  for (const auto& p : a) m.vertices.push_back(p);
  for (const auto& p : b) m.vertices.push_back(p);
  m.add_face(std::array<int, 3>{0, 1, 2});
  m.add_face(std::array<int, 3>{3, 4, 5});
  return m;
}

}  // namespace

TEST(SelfIntersections, ACubeAndTwoApartDoNotCross) {
  PolygonMesh m;
  add_cube(m, Eigen::Vector3d::Zero());
  EXPECT_EQ(self_intersections(m).pairs, 0u);
  // Faces sharing corners and edges only, however the vertices are numbered.
  EXPECT_EQ(self_intersections(as_soup(m)).pairs, 0u);
  add_cube(m, Eigen::Vector3d(2, 0, 0));
  EXPECT_EQ(self_intersections(m).pairs, 0u);
}

TEST(SelfIntersections, OverlappingCubesCrossAndTheExamplesNameThePairs) {
  PolygonMesh m;
  add_cube(m, Eigen::Vector3d::Zero());
  add_cube(m, Eigen::Vector3d(0.75, 0.25, 0.25), 0.5);  // pokes out through the +x face
  const SelfIntersections s = self_intersections(m, 100);
  EXPECT_GT(s.pairs, 0u);
  ASSERT_EQ(s.examples.size(), s.pairs);
  // Every pair is one triangle of each cube, and the big cube's +x face (triangles 10, 11) is in one.
  bool x_face = false;
  for (const auto& [f, g] : s.examples) {
    EXPECT_LT(f, 12u);
    EXPECT_GE(g, 12u);
    x_face = x_face || f == 10 || f == 11;
  }
  EXPECT_TRUE(x_face);
  EXPECT_EQ(self_intersections(m, 2).examples.size(), 2u);
}

TEST(SelfIntersections, SharedVertexOrEdgeCountsOnlyWhereTheyMeetElsewhere) {
  const Eigen::Vector3d o(0, 0, 0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  // One common vertex, the triangles apart elsewhere: a fan's neighbours.
  EXPECT_EQ(self_intersections(two_triangles({o, x, y}, {o, y * -1.0, z})).pairs, 0u);
  // One common vertex, the second's far edge through the first.
  EXPECT_EQ(self_intersections(two_triangles({o, x, y}, {o, Eigen::Vector3d(0.3, 0.3, 1), Eigen::Vector3d(0.3, 0.3, -1)})).pairs, 1u);
  // One common vertex, coplanar, one inside the other's angle.
  EXPECT_EQ(self_intersections(two_triangles({o, x, y}, {o, Eigen::Vector3d(0.2, 0.1, 0), Eigen::Vector3d(0.1, 0.2, 0)})).pairs, 1u);
  // A common edge: a hinge apart, a hinge folded flat onto the same side.
  EXPECT_EQ(self_intersections(two_triangles({o, x, y}, {x, o, Eigen::Vector3d(0.5, -1, 0)})).pairs, 0u);
  EXPECT_EQ(self_intersections(two_triangles({o, x, y}, {x, o, Eigen::Vector3d(0.5, -1, 0.3)})).pairs, 0u);
  EXPECT_EQ(self_intersections(two_triangles({o, x, y}, {x, o, Eigen::Vector3d(0.5, 0.3, 0)})).pairs, 1u);
  // No common vertex: crossing, then apart by a little.
  EXPECT_EQ(self_intersections(two_triangles({o, x, y}, {Eigen::Vector3d(0.2, 0.2, -1), Eigen::Vector3d(0.2, 0.2, 1), Eigen::Vector3d(2, 2, 0)})).pairs, 1u);
  EXPECT_EQ(self_intersections(two_triangles({o, x, y}, {Eigen::Vector3d(0, 0, 1e-9), Eigen::Vector3d(1, 0, 1e-9), Eigen::Vector3d(0, 1, 1e-9)})).pairs, 0u);
  // The same triangle twice, and a triangle of zero area (counted apart, not tested).
  EXPECT_EQ(self_intersections(two_triangles({o, x, y}, {y, o, x})).pairs, 1u);
  const SelfIntersections d = self_intersections(two_triangles({o, x, y}, {o, x, x * 2.0}));
  EXPECT_EQ(d.pairs, 0u);
  EXPECT_EQ(d.degenerate, 1u);
}
