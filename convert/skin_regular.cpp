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
// points); cells are visited in parallel chunks and only crossed tetrahedra are stored.
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
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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


  // The real simplices (no octahedron vertex), and for each real vertex the edges of its power
  // cell's faces and an interior point of it (the mean of its power centres), gathered here:
  // CGAL's incident_* queries mark cells and must not run concurrently; circulators only read.
  const auto real = [](std::initializer_list<Regular::Vertex_handle> vs) {
    return std::all_of(vs.begin(), vs.end(), [](const auto& v) { return v->info() != kBoundingVertex; });
  };
  std::vector<Regular::Vertex_handle> vertices;
  std::vector<std::size_t> vertex_edges_begin{0};
  std::vector<Regular::Edge> vertex_edges;
  std::vector<Vector3d> vertex_mean;
  {
    std::vector<Regular::Cell_handle> incident;
    for (auto v = rt.finite_vertices_begin(); v != rt.finite_vertices_end(); ++v) {
      if (v->info() == kBoundingVertex) continue;
      vertices.push_back(v);
      incident.clear();
      rt.incident_cells(v, std::back_inserter(incident));
      Vector3d mean = Vector3d::Zero();
      for (const auto& c : incident) mean += power_centre(c);
      vertex_mean.push_back(mean / static_cast<double>(incident.size()));
      rt.incident_edges(v, std::back_inserter(vertex_edges));
      vertex_edges_begin.push_back(vertex_edges.size());
    }
  }
  std::vector<Regular::Edge> edges;
  for (auto e = rt.finite_edges_begin(); e != rt.finite_edges_end(); ++e)
    if (real({e->first->vertex(e->second), e->first->vertex(e->third)})) edges.push_back(*e);
  std::vector<Regular::Facet> facets;
  for (auto f = rt.finite_facets_begin(); f != rt.finite_facets_end(); ++f) {
    const auto c = f->first;
    const int i = f->second;
    if (real({c->vertex((i + 1) & 3), c->vertex((i + 2) & 3), c->vertex((i + 3) & 3)})) facets.push_back(*f);
  }
  std::vector<Regular::Cell_handle> tetrahedra;
  for (auto c = rt.finite_cells_begin(); c != rt.finite_cells_end(); ++c)
    if (real({c->vertex(0), c->vertex(1), c->vertex(2), c->vertex(3)})) tetrahedra.push_back(c);
  out.mixed_cells = vertices.size() + edges.size() + facets.size() + tetrahedra.size();

  // The mixed cells in chunks of consecutive simplices (vertices, edges, facets, tetrahedra),
  // each chunk into its own conversion, concatenated in order: the output does not depend on
  // the number of threads.
  constexpr std::size_t kChunk = 1024;
  const std::size_t n_cells = out.mixed_cells;
  std::vector<SkinConversion> chunks((n_cells + kChunk - 1) / kChunk);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<int> simplex_balls;
    std::vector<WeightedPoint> simplex_points;
    std::vector<Vector3d> z;
    for (std::size_t chunk = r.begin(); chunk != r.end(); ++chunk) {
      SkinConversion& part = chunks[chunk];
      PatchEmitter emitter(balls, part, s);
      SkinQuadric q;
      std::size_t cell_patches = 0;
      const auto begin_cell = [&](std::initializer_list<Regular::Vertex_handle> vs) {
        simplex_balls.clear(), simplex_points.clear();
        for (const auto& v : vs) simplex_balls.push_back(v->info()), simplex_points.push_back(v->point());
        q = skin_quadric(simplex_points, s);
        cell_patches = 0;
      };
      const auto emit = [&](const std::array<Vector3d, 4>& t) {
        ++part.mixed_tets;
        cell_patches += emitter.emit(simplex_balls, q, t);
      };
      const auto end_cell = [&] { part.mixed_cells_crossed += cell_patches > 0; };
      // Prism bottom a0 a1 a2, top b0 b1 b2 (bᵢ over aᵢ): three tetrahedra.
      const auto prism = [&](const Vector3d& a0, const Vector3d& a1, const Vector3d& a2, const Vector3d& b0,
                             const Vector3d& b1, const Vector3d& b2) {
        emit(tet(a0, a1, a2, b2));
        emit(tet(a0, a1, b1, b2));
        emit(tet(a0, b0, b1, b2));
      };
      const auto scaled = [&](const Vector3d& del, const Vector3d& vor) -> Vector3d { return (1 - s) * del + s * vor; };
      // The power centres of the cells around an edge, in cyclic order.
      const auto ring = [&](const Regular::Edge& e) {
        z.clear();
        auto cc = rt.incident_cells(e), done = cc;
        do z.push_back(power_centre(cc));
        while (++cc != done);
      };

      for (std::size_t k = chunk * kChunk; k < std::min(n_cells, (chunk + 1) * kChunk); ++k) {
        std::size_t i = k;
        if (i < vertices.size()) {  // vertex × power cell: a fan over the cell's faces
          const auto v = vertices[i];
          begin_cell({v});
          const Vector3d a = to_eigen(v->point().point());
          const Vector3d inner = scaled(a, vertex_mean[i]);
          for (std::size_t j = vertex_edges_begin[i]; j < vertex_edges_begin[i + 1]; ++j) {
            ring(vertex_edges[j]);
            for (std::size_t m = 1; m + 1 < z.size(); ++m)
              emit(tet(inner, scaled(a, z[0]), scaled(a, z[m]), scaled(a, z[m + 1])));
          }
          end_cell();
          continue;
        }
        i -= vertices.size();
        if (i < edges.size()) {  // edge × polygon: prisms over a fan of the polygon
          const auto& e = edges[i];
          const auto va = e.first->vertex(e.second), vb = e.first->vertex(e.third);
          begin_cell({va, vb});
          const Vector3d a = to_eigen(va->point().point()), b = to_eigen(vb->point().point());
          ring(e);
          for (std::size_t m = 1; m + 1 < z.size(); ++m)
            prism(scaled(a, z[0]), scaled(a, z[m]), scaled(a, z[m + 1]), scaled(b, z[0]), scaled(b, z[m]),
                  scaled(b, z[m + 1]));
          end_cell();
          continue;
        }
        i -= edges.size();
        if (i < facets.size()) {  // facet × segment: one prism
          const auto c = facets[i].first;
          const int f = facets[i].second;
          const auto v0 = c->vertex((f + 1) & 3), v1 = c->vertex((f + 2) & 3), v2 = c->vertex((f + 3) & 3);
          begin_cell({v0, v1, v2});
          const Vector3d p0 = to_eigen(v0->point().point()), p1 = to_eigen(v1->point().point()),
                         p2 = to_eigen(v2->point().point());
          const Vector3d& z0 = power_centre(c);
          const Vector3d& z1 = power_centre(c->neighbor(f));
          prism(scaled(p0, z0), scaled(p1, z0), scaled(p2, z0), scaled(p0, z1), scaled(p1, z1), scaled(p2, z1));
          end_cell();
          continue;
        }
        i -= facets.size();
        {  // tetrahedron × point: the tetrahedron scaled about its power centre
          const auto c = tetrahedra[i];
          begin_cell({c->vertex(0), c->vertex(1), c->vertex(2), c->vertex(3)});
          const Vector3d& zc = power_centre(c);
          std::array<Vector3d, 4> t;
          for (int m = 0; m < 4; ++m) t[m] = scaled(to_eigen(c->vertex(m)->point().point()), zc);
          emit(t);
          end_cell();
        }
      }
    }
  });
  std::size_t total = 0;
  for (const auto& part : chunks) total += part.model.tets.size();
  out.model.tets.reserve(total);
  for (auto& part : chunks) {
    out.model.tets.insert(out.model.tets.end(), part.model.tets.begin(), part.model.tets.end());
    std::vector<TetPatch>().swap(part.model.tets);
    out.mixed_cells_crossed += part.mixed_cells_crossed;
    out.mixed_tets += part.mixed_tets;
    out.slivers_skipped += part.slivers_skipped;
    out.tets_clipped_to_box += part.tets_clipped_to_box;
  }
  out.cgal_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  log::debug("{}: regular triangulation of {} balls ({} hidden) in {:.2f} s; {} mixed cells ({} crossed), "
             "{} tetrahedra, {} patches",
             options.source, balls.size(), out.hidden_balls, out.triangulation_seconds, out.mixed_cells,
             out.mixed_cells_crossed, out.mixed_tets, out.model.tets.size());
  return out;
}

}  // namespace quadrix::skin_detail
