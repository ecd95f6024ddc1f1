// Triangle meshes through CGAL, in one heavy translation unit of its own library:
// - self-intersections of a triangle soup: box_self_intersection_d for the pairs whose boxes
//   meet, exact predicates for the test. CGAL 5.5's Polygon_mesh_processing::self_intersections
//   wants a face graph; a soup made one (orient_polygon_soup) duplicates vertices at non-manifold
//   spots, so triangles that only share such a vertex would read as touching: hence this soup
//   test, with the same case analysis;
// - the union of closed meshes by corefinement (Polygon_mesh_processing::corefine_and_compute_union),
//   or, with cylinders among them, by autorefining them as one soup
//   (Polygon_mesh_processing::experimental::autorefine_and_remove_self_intersections) in a child
//   process.
#include "convert/mesh_union.h"
#include "convert/self_intersections.h"
#include "core/child_process.h"
#include "core/log.h"
#include "core/morton.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <exception>
#include <map>
#include <numeric>

#include <fmt/format.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Surface_mesh.h>
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

namespace {

// Exact constructions: with rounded intersection points (Epick) a union could come out
// self-intersecting, and the next union of it ran on without end (4lfq balls-and-sticks).
using KE = CGAL::Exact_predicates_exact_constructions_kernel;
using Surface = CGAL::Surface_mesh<KE::Point_3>;
using SurfaceD = CGAL::Surface_mesh<K::Point_3>;

// Adds m's triangles (faces fanned from their first vertex) to s, with vertices of their own.
void add_to_surface(const PolygonMesh& m, Surface& s) {
  std::vector<Surface::Vertex_index> v;
  v.reserve(m.vertices.size());
  for (const auto& p : m.vertices) v.push_back(s.add_vertex(KE::Point_3(p.x(), p.y(), p.z())));
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto face = m.face(f);
    for (std::size_t k = 1; k + 1 < face.size(); ++k)
      s.add_face(v[std::size_t(face[0])], v[std::size_t(face[k])], v[std::size_t(face[k + 1])]);
  }
}

Surface to_surface(const PolygonMesh& m) {
  Surface s;
  s.reserve(static_cast<Surface::size_type>(m.vertices.size()), static_cast<Surface::size_type>(3 * m.face_count() / 2),
            static_cast<Surface::size_type>(m.face_count()));
  add_to_surface(m, s);
  return s;
}

void append(const Surface& s, PolygonMesh& out) {
  std::map<Surface::Vertex_index, int> id;
  for (const auto v : s.vertices()) {
    const KE::Point_3& p = s.point(v);
    id[v] = static_cast<int>(out.vertices.size());
    out.vertices.emplace_back(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
  }
  for (const auto f : s.faces()) {
    std::vector<int> ids;
    for (const auto v : CGAL::vertices_around_face(s.halfedge(f), s)) ids.push_back(id[v]);
    out.add_face(ids);
  }
}

}  // namespace

MeshUnion union_of_closed_meshes(std::vector<PolygonMesh> parts, const std::function<void(double)>& progress) {
  MeshUnion out;
  out.parts = parts.size();
  if (parts.empty()) return out;
  // Neighbours first: the parts in Morton order of their centres (core/morton.h).
  std::vector<Eigen::Vector3d> centre(parts.size(), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < parts.size(); ++i) {
    for (const auto& p : parts[i].vertices) centre[i] += p;
    if (!parts[i].vertices.empty()) centre[i] /= double(parts[i].vertices.size());
  }
  const std::vector<std::uint32_t> order = morton_order(centre);
  // Each slot: the union so far, and the meshes a refused union left beside it.
  struct Slot {
    Surface mesh;
    std::vector<Surface> apart;
  };
  std::vector<Slot> level(parts.size());
  for (std::size_t i = 0; i < parts.size(); ++i) level[i].mesh = to_surface(parts[order[i]]);
  parts.clear();
  std::size_t failed = 0;
  const double rounds = std::max(1.0, std::ceil(std::log2(double(level.size()))));
  double round = 0;
  while (level.size() > 1) {
    std::vector<Slot> next((level.size() + 1) / 2);
    // One pair after another: corefinement makes its coplanar constructions with CGAL's lazy exact
    // kernel (Epeck), which is not thread-safe in CGAL 5.5 (pairs in parallel crashed there).
    for (std::size_t k = 0; k < level.size() / 2; ++k) {
      Slot& a = level[2 * k];
      Slot& b = level[2 * k + 1];
      Slot& c = next[k];
      bool ok = false;
      try {
        // In place into a. A refusal (the union would not be a closed manifold) leaves both
        // corefined only: the same surfaces with the intersection curves' vertices added.
        ok = CGAL::Polygon_mesh_processing::corefine_and_compute_union(a.mesh, b.mesh, a.mesh);
      } catch (const std::exception& e) {
        log::debug("union: CGAL refused a pair: {}", e.what());
        ok = false;
      }
      c.mesh = std::move(a.mesh);
      c.apart = std::move(a.apart);
      if (!ok) {
        ++failed;
        c.apart.push_back(std::move(b.mesh));
      }
      for (auto& s : b.apart) c.apart.push_back(std::move(s));
    }
    if (level.size() % 2) next.back() = std::move(level.back());
    level = std::move(next);
    round += 1;
    log::debug("union: round {}: {} meshes left, {} refused so far", int(round), level.size(), failed);
    if (progress) progress(std::min(1.0, round / rounds));
  }
  out.failed = failed;
  append(level[0].mesh, out.mesh);
  for (const auto& s : level[0].apart) append(s, out.mesh);
  return out;
}

}  // namespace quadrix

namespace quadrix {

// The child writes: uint64 vertices, uint64 triangles, uint64 all fixed (1) or not (0), then the
// vertices (3 doubles each) and the triangles (3 uint32 each). It exits 0 after a complete record;
// 2 when CGAL threw (written instead: uint64 length, then the message's bytes); 3 where a write
// failed or a face is not a triangle; 5 where the rounded copy cannot link a face; 4 on any other
// throw (run_in_child).
MeshUnion union_by_autorefinement(std::vector<PolygonMesh> parts) {
  MeshUnion out;
  out.parts = parts.size();
  const auto as_they_were = [&](std::string why) -> MeshUnion {
    out.why = std::move(why);
    out.apart = true;
    out.failed = parts.size() > 1 ? parts.size() - 1 : 0;
    for (const auto& p : parts) {
      const int base = static_cast<int>(out.mesh.vertices.size());
      out.mesh.vertices.insert(out.mesh.vertices.end(), p.vertices.begin(), p.vertices.end());
      for (std::size_t f = 0; f < p.face_count(); ++f) {
        const auto face = p.face(f);
        for (std::size_t k = 1; k + 1 < face.size(); ++k)
          out.mesh.add_face(std::array<int, 3>{base + face[0], base + face[k], base + face[k + 1]});
      }
    }
    return out;
  };
  if (parts.size() < 2) {
    MeshUnion one = as_they_were("");
    one.apart = false;
    return one;
  }
  // A deadline against a child that runs on without end (a union of rounded constructions did):
  // 4lfq's 1,187 parts take about 10 s.
  const double deadline = 300.0 + 0.5 * double(parts.size());
  const ChildRun child = run_in_child([&](int fd) {
    try {
      Surface s;
      for (const auto& p : parts) add_to_surface(p, s);
      const bool fixed = CGAL::Polygon_mesh_processing::experimental::autorefine_and_remove_self_intersections(s);
      // Rounded to doubles, a few of the pieces cut along intersection curves collapse to zero
      // area (4ins balls-and-sticks: 16): their edges are collapsed and flipped away, on the
      // rounded positions.
      s.collect_garbage();
      SurfaceD d;
      for (const auto v : s.vertices()) {
        const KE::Point_3& p = s.point(v);
        d.add_vertex(K::Point_3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())));
      }
      for (const auto f : s.faces()) {
        std::vector<SurfaceD::Vertex_index> corners;
        for (const auto v : CGAL::vertices_around_face(s.halfedge(f), s)) corners.emplace_back(v.idx());
        if (d.add_face(corners) == SurfaceD::null_face()) return 5;  // a face the copy cannot link: the parts stay
      }
      // (false where some stay: they are counted in the mesh's report as degenerate triangles)
      CGAL::Polygon_mesh_processing::remove_degenerate_faces(d);
      d.collect_garbage();
      std::vector<double> xyz;
      xyz.reserve(3 * d.number_of_vertices());
      std::vector<std::uint32_t> id(d.number_of_vertices());
      for (const auto v : d.vertices()) {
        id[v.idx()] = static_cast<std::uint32_t>(xyz.size() / 3);
        const K::Point_3& p = d.point(v);
        xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
      }
      std::vector<std::uint32_t> tri;
      tri.reserve(3 * d.number_of_faces());
      for (const auto f : d.faces())
        for (const auto v : CGAL::vertices_around_face(d.halfedge(f), d)) tri.push_back(id[v.idx()]);
      if (tri.size() != 3 * d.number_of_faces()) return 3;  // not triangles
      const std::uint64_t head[3] = {xyz.size() / 3, tri.size() / 3, fixed ? 1u : 0u};
      if (!write_all(fd, head, sizeof head) || !write_all(fd, xyz.data(), xyz.size() * sizeof(double)) ||
          !write_all(fd, tri.data(), tri.size() * sizeof(std::uint32_t)))
        return 3;
      return 0;
    } catch (const std::exception& e) {
      const std::string what = e.what();
      const std::uint64_t n = what.size();
      if (write_all(fd, &n, sizeof n)) write_all(fd, what.data(), what.size());
      return 2;
    }
  }, deadline);
  const std::string& buffer = child.output;
  if (!child.ran()) return as_they_were(child.how());
  if (!child.succeeded()) {
    std::string why = "CGAL's autorefinement " + child.how();
    std::uint64_t n = 0;
    if (child.exit_code() == 2 && buffer.size() >= sizeof n) {
      std::memcpy(&n, buffer.data(), sizeof n);
      if (buffer.size() >= sizeof n + n) why += ": " + buffer.substr(sizeof n, n);
    }
    return as_they_were(why);
  }
  std::uint64_t head[3];
  if (buffer.size() < sizeof head) return as_they_were("CGAL's autorefinement returned nothing");
  std::memcpy(head, buffer.data(), sizeof head);
  const std::size_t bytes = sizeof head + head[0] * 3 * sizeof(double) + head[1] * 3 * sizeof(std::uint32_t);
  if (buffer.size() != bytes) return as_they_were("CGAL's autorefinement returned a truncated mesh");
  out.mesh.vertices.resize(head[0]);
  const char* at = buffer.data() + sizeof head;
  for (auto& v : out.mesh.vertices) {
    std::memcpy(v.data(), at, 3 * sizeof(double));
    at += 3 * sizeof(double);
  }
  for (std::uint64_t f = 0; f < head[1]; ++f) {
    std::uint32_t t[3];
    std::memcpy(t, at, sizeof t);
    at += sizeof t;
    if (t[0] >= head[0] || t[1] >= head[0] || t[2] >= head[0]) {
      out.mesh = PolygonMesh{};
      return as_they_were("CGAL's autorefinement returned a triangle with a vertex it did not send");
    }
    out.mesh.add_face(std::array<int, 3>{int(t[0]), int(t[1]), int(t[2])});
  }
  out.failed = head[2] ? 0 : 1;
  if (!head[2]) out.why = "CGAL's autorefinement left some self-intersections";
  return out;
}

}  // namespace quadrix
