// Skin surfaces through our own mixed complex over CGAL's Regular_triangulation_3 (no
// Skin_surface_3): SkinTetrahedra::regular. See convert/skin.h.
//
// Every simplex δ of the regular triangulation of the grown balls (weights r²/s) pairs with its
// dual face ν of the power diagram, and the mixed cell (1−s)δ + sν carries δ's skin quadric
// (convert/skin_detail.h). δ and ν span orthogonal complementary affine spaces, so the mixed cell
// is the product of the scaled simplex and the scaled dual face and splits into tetrahedra
// without a convex hull:
//   vertex  × power cell: a fan from an interior point over the cell's polygons (one per edge
//                         at the vertex, its corners the power centres of the cells around it);
//   edge    × polygon:    the polygon fanned into triangles, each triangle × the edge a prism;
//   facet   × segment:    one prism;
//   tetrahedron × point:  the tetrahedron itself, scaled by (1−s) about its power centre.
// Three tetrahedra per prism. CGAL's Skin_surface_3 builds the same cells but triangulates all of
// them (with its own Triangulation_3 of anchor points) before we can skip those the surface does
// not cross: 5.8 GB for 5,684 atoms. Here only the regular triangulation is kept (Discard hidden
// points); cells are visited one at a time and only crossed tetrahedra are stored.
//
// Like CGAL, six far vertices of weight −1 (an octahedron) bound the power cells of the outer
// balls; simplices with one of them are not skin cells and are skipped.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>

#include <CGAL/Regular_triangulation_3.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <fmt/format.h>

#include "convert/skin_detail.h"
#include "core/error.h"
#include "core/log.h"

namespace quadrix::skin_detail {
namespace {

using Eigen::Vector3d;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<int, K, CGAL::Regular_triangulation_vertex_base_3<K>>;
using Cb = CGAL::Triangulation_cell_base_with_info_3<
    std::int64_t, K, CGAL::Regular_triangulation_cell_base_3<K, CGAL::Triangulation_cell_base_3<K>,
                                                             CGAL::Discard_hidden_points>>;
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
using Regular = CGAL::Regular_triangulation_3<K, Tds>;
using Clock = std::chrono::steady_clock;

constexpr int kBoundingVertex = -1;

std::array<Vector3d, 4> tet(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  return {a, b, c, d};
}

}  // namespace

SkinConversion convert_skin_regular(const std::vector<Ball>& balls, const SkinOptions& options) {
  const double s = options.shrink;
  SkinConversion out;
  const auto t0 = Clock::now();

  // The grown balls with their index, and CGAL's bounding octahedron (Skin_surface_base_3.h):
  // weight −1 at distance (dx + dy + dz + √wmax + 0.001)/s from the box centre.
  const std::vector<WeightedPoint> grown = grown_weighted_points(balls, s);
  std::vector<std::pair<WeightedPoint, int>> points;
  points.reserve(balls.size() + 6);
  Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double wmax = 0;
  for (std::size_t i = 0; i < balls.size(); ++i) {
    points.emplace_back(grown[i], static_cast<int>(i));
    lo = lo.cwiseMin(balls[i].centre), hi = hi.cwiseMax(balls[i].centre);
    wmax = std::max(wmax, grown[i].weight());
  }
  const Vector3d mid = 0.5 * (lo + hi);
  const double dr = ((hi - lo).sum() + std::sqrt(wmax) + 0.001) / s;
  for (int axis = 0; axis < 3; ++axis)
    for (const double sign : {1.0, -1.0}) {
      Vector3d p = mid;
      p[axis] += sign * dr;
      points.emplace_back(WeightedPoint(K::Point_3(p.x(), p.y(), p.z()), -1.0), kBoundingVertex);
    }
  Regular rt;
  rt.insert(points.begin(), points.end());
  out.hidden_balls = balls.size() + 6 - rt.number_of_vertices();

  // Power centres (weighted circumcentres) of the finite cells.
  std::vector<Vector3d> centre;
  centre.reserve(rt.number_of_finite_cells());
  const auto weighted_circumcentre = K().construct_weighted_circumcenter_3_object();
  for (auto c = rt.all_cells_begin(); c != rt.all_cells_end(); ++c) c->info() = -1;
  for (auto c = rt.finite_cells_begin(); c != rt.finite_cells_end(); ++c) {
    c->info() = static_cast<std::int64_t>(centre.size());
    centre.push_back(to_eigen(weighted_circumcentre(c->vertex(0)->point(), c->vertex(1)->point(),
                                                    c->vertex(2)->point(), c->vertex(3)->point())));
  }
  out.triangulation_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  const auto power_centre = [&](Regular::Cell_handle c) -> const Vector3d& {
    if (c->info() < 0)  // only the octahedron's vertices are on the hull
      throw SolverError(fmt::format("{}: skin: a ball's power cell is unbounded", options.source));
    return centre[static_cast<std::size_t>(c->info())];
  };
  // The power centres of the cells around an edge, in cyclic order.
  const auto ring = [&](const Regular::Edge& e, std::vector<Vector3d>& z) {
    z.clear();
    auto cc = rt.incident_cells(e), done = cc;
    do z.push_back(power_centre(cc));
    while (++cc != done);
  };

  PatchEmitter emitter(balls, out);
  std::vector<int> simplex_balls;
  std::vector<WeightedPoint> simplex_points;
  std::vector<Vector3d> z, x;
  // One mixed cell: its simplex from vertex handles; false for a bounding-octahedron simplex.
  const auto begin_cell = [&](std::initializer_list<Regular::Vertex_handle> vs) {
    simplex_balls.clear(), simplex_points.clear();
    for (const auto& v : vs) {
      if (v->info() == kBoundingVertex) return false;
      simplex_balls.push_back(v->info());
      simplex_points.push_back(v->point());
    }
    ++out.mixed_cells;
    return true;
  };
  std::size_t cell_patches = 0;
  SkinQuadric q;
  const auto emit = [&](const std::array<Vector3d, 4>& t) {
    ++out.mixed_tets;
    cell_patches += emitter.emit(simplex_balls, q, t);
  };
  const auto end_cell = [&] {
    if (cell_patches > 0) ++out.mixed_cells_crossed;
    cell_patches = 0;
  };
  // Prism bottom a0 a1 a2, top b0 b1 b2 (bᵢ over aᵢ): three tetrahedra.
  const auto prism = [&](const Vector3d& a0, const Vector3d& a1, const Vector3d& a2, const Vector3d& b0,
                         const Vector3d& b1, const Vector3d& b2) {
    emit(tet(a0, a1, a2, b2));
    emit(tet(a0, a1, b1, b2));
    emit(tet(a0, b0, b1, b2));
  };
  const auto scaled = [&](const Vector3d& del, const Vector3d& vor) -> Vector3d { return (1 - s) * del + s * vor; };

  // Vertices × power cells.
  std::vector<Regular::Edge> edges;
  std::vector<Regular::Cell_handle> cells;
  for (auto v = rt.finite_vertices_begin(); v != rt.finite_vertices_end(); ++v) {
    if (!begin_cell({v})) continue;
    q = skin_quadric(simplex_points, s);
    const Vector3d a = to_eigen(v->point().point());
    cells.clear();
    rt.incident_cells(v, std::back_inserter(cells));
    Vector3d mean = Vector3d::Zero();
    for (const auto& c : cells) mean += power_centre(c);
    const Vector3d inner = scaled(a, mean / static_cast<double>(cells.size()));
    edges.clear();
    rt.incident_edges(v, std::back_inserter(edges));
    for (const auto& e : edges) {
      ring(e, z);
      for (std::size_t i = 1; i + 1 < z.size(); ++i) emit(tet(inner, scaled(a, z[0]), scaled(a, z[i]), scaled(a, z[i + 1])));
    }
    end_cell();
  }
  // Edges × polygons.
  for (auto e = rt.finite_edges_begin(); e != rt.finite_edges_end(); ++e) {
    const auto va = e->first->vertex(e->second), vb = e->first->vertex(e->third);
    if (!begin_cell({va, vb})) continue;
    q = skin_quadric(simplex_points, s);
    const Vector3d a = to_eigen(va->point().point()), b = to_eigen(vb->point().point());
    ring(*e, z);
    for (std::size_t i = 1; i + 1 < z.size(); ++i)
      prism(scaled(a, z[0]), scaled(a, z[i]), scaled(a, z[i + 1]), scaled(b, z[0]), scaled(b, z[i]), scaled(b, z[i + 1]));
    end_cell();
  }
  // Facets × segments.
  for (auto f = rt.finite_facets_begin(); f != rt.finite_facets_end(); ++f) {
    const auto c = f->first;
    const int i = f->second;
    const auto v0 = c->vertex((i + 1) & 3), v1 = c->vertex((i + 2) & 3), v2 = c->vertex((i + 3) & 3);
    if (!begin_cell({v0, v1, v2})) continue;
    q = skin_quadric(simplex_points, s);
    const Vector3d p0 = to_eigen(v0->point().point()), p1 = to_eigen(v1->point().point()),
                   p2 = to_eigen(v2->point().point());
    const Vector3d& z0 = power_centre(c);
    const Vector3d& z1 = power_centre(c->neighbor(i));
    prism(scaled(p0, z0), scaled(p1, z0), scaled(p2, z0), scaled(p0, z1), scaled(p1, z1), scaled(p2, z1));
    end_cell();
  }
  // Tetrahedra × points.
  for (auto c = rt.finite_cells_begin(); c != rt.finite_cells_end(); ++c) {
    if (!begin_cell({c->vertex(0), c->vertex(1), c->vertex(2), c->vertex(3)})) continue;
    q = skin_quadric(simplex_points, s);
    const Vector3d& zc = power_centre(c);
    std::array<Vector3d, 4> t;
    for (int k = 0; k < 4; ++k) t[k] = scaled(to_eigen(c->vertex(k)->point().point()), zc);
    emit(t);
    end_cell();
  }
  out.cgal_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  log::debug("{}: regular triangulation of {} balls ({} hidden) in {:.2f} s; {} mixed cells ({} crossed), "
             "{} tetrahedra, {} patches",
             options.source, balls.size(), out.hidden_balls, out.triangulation_seconds, out.mixed_cells,
             out.mixed_cells_crossed, out.mixed_tets, out.model.tets.size());
  return out;
}

}  // namespace quadrix::skin_detail
