// Self-intersections of a triangle soup through CGAL (one heavy translation unit in its own
// library): box_self_intersection_d for the pairs whose boxes meet, exact predicates for the test.
// CGAL 5.5's Polygon_mesh_processing::self_intersections wants a face graph; a soup made one
// (orient_polygon_soup) duplicates vertices at non-manifold spots, so triangles that only share
// such a vertex would read as touching: hence this soup test, with the same case analysis.
#include "convert/self_intersections.h"

#include <algorithm>
#include <array>
#include <numeric>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

namespace quadrix {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t>;

// Whether p lies strictly inside the angle the coplanar rays v→a and v→b span (< 180°).
bool inside_angle(const Point& v, const Point& a, const Point& b, const Point& p) {
  return CGAL::coplanar_orientation(v, a, b, p) == CGAL::POSITIVE && CGAL::coplanar_orientation(v, b, a, p) == CGAL::POSITIVE;
}

}  // namespace

SelfIntersections self_intersections(const PolygonMesh& m, std::size_t keep) {
  SelfIntersections out;
  // One id per position: vertices at one point are one vertex.
  std::vector<int> order(m.vertices.size());
  std::iota(order.begin(), order.end(), 0);
  const auto less = [&](int i, int j) {
    const auto &p = m.vertices[std::size_t(i)], &q = m.vertices[std::size_t(j)];
    return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<int> id(m.vertices.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    id[std::size_t(order[k])] = k > 0 && m.vertices[std::size_t(order[k])] == m.vertices[std::size_t(order[k - 1])]
                                    ? id[std::size_t(order[k - 1])]
                                    : order[k];

  // The triangles (faces fanned from their first vertex), by canonical ids.
  std::vector<std::array<int, 3>> tris;
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto face = m.face(f);
    for (std::size_t k = 1; k + 1 < face.size(); ++k)
      tris.push_back({id[std::size_t(face[0])], id[std::size_t(face[k])], id[std::size_t(face[k + 1])]});
  }
  const auto point = [&](int v) {
    const auto& p = m.vertices[std::size_t(v)];
    return Point(p.x(), p.y(), p.z());
  };
  std::vector<Box> boxes;
  boxes.reserve(tris.size());
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const auto [a, b, c] = tris[t];
    const Point pa = point(a), pb = point(b), pc = point(c);
    if (a == b || b == c || a == c || CGAL::collinear(pa, pb, pc)) {
      ++out.degenerate;
      continue;
    }
    boxes.emplace_back(pa.bbox() + pb.bbox() + pc.bbox(), t);
  }

  const auto meet = [&](std::size_t i, std::size_t j) {
    const auto &s = tris[i], &t = tris[j];
    std::array<int, 3> si{-1, -1, -1}, tj{-1, -1, -1};  // the shared corners' positions in each
    int shared = 0;
    for (int x = 0; x < 3; ++x)
      for (int y = 0; y < 3; ++y)
        if (s[std::size_t(x)] == t[std::size_t(y)]) si[std::size_t(shared)] = x, tj[std::size_t(shared)] = y, ++shared;
    const K::Triangle_3 T1(point(s[0]), point(s[1]), point(s[2])), T2(point(t[0]), point(t[1]), point(t[2]));
    if (shared == 0) return CGAL::do_intersect(T1, T2);
    if (shared == 3) return true;  // the same triangle twice
    if (shared == 1) {
      // v shared; each triangle's opposite edge against the other, and coplanar overlap of the
      // two corners' angles at v.
      const Point v = point(s[std::size_t(si[0])]);
      const Point a = point(s[std::size_t((si[0] + 1) % 3)]), b = point(s[std::size_t((si[0] + 2) % 3)]);
      const Point c = point(t[std::size_t((tj[0] + 1) % 3)]), d = point(t[std::size_t((tj[0] + 2) % 3)]);
      if (CGAL::do_intersect(K::Segment_3(a, b), T2) || CGAL::do_intersect(K::Segment_3(c, d), T1)) return true;
      if (CGAL::orientation(v, a, b, c) != CGAL::COPLANAR || CGAL::orientation(v, a, b, d) != CGAL::COPLANAR) return false;
      return inside_angle(v, a, b, c) || inside_angle(v, a, b, d) || inside_angle(v, c, d, a) || inside_angle(v, c, d, b);
    }
    // An edge shared: they meet elsewhere only folded onto each other (coplanar, one side).
    const Point u = point(s[std::size_t(si[0])]), w = point(s[std::size_t(si[1])]);
    const Point a = point(s[std::size_t(3 - si[0] - si[1])]), b = point(t[std::size_t(3 - tj[0] - tj[1])]);
    return CGAL::orientation(u, w, a, b) == CGAL::COPLANAR && CGAL::coplanar_orientation(u, w, a, b) == CGAL::POSITIVE;
  };
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& x, const Box& y) {
    const std::size_t i = std::min(x.info(), y.info()), j = std::max(x.info(), y.info());
    if (!meet(i, j)) return;
    ++out.pairs;
    if (out.examples.size() < keep) out.examples.emplace_back(std::uint32_t(i), std::uint32_t(j));
  });
  std::sort(out.examples.begin(), out.examples.end());
  return out;
}

}  // namespace quadrix
