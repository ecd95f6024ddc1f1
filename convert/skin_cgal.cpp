// Skin surfaces through CGAL Skin_surface_3 (the only translation unit that includes CGAL's skin
// headers: ~60 s and 1.5 GB to compile). See convert/skin.h.
#include "convert/skin.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <unordered_map>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polyhedron_3.h>
#include <CGAL/Skin_surface_3.h>
#include <CGAL/Skin_surface_polyhedral_items_3.h>
#include <CGAL/mesh_skin_surface_3.h>
#include <CGAL/subdivide_skin_surface_mesh_3.h>
#include <fmt/format.h>

#include "convert/skin_detail.h"
#include "convert/tetrahedralize.h"
#include "core/bounds.h"
#include "core/error.h"
#include "core/log.h"

namespace quadrix {
namespace {

using namespace skin_detail;
using Traits = CGAL::Skin_surface_traits_3<K>;
using Skin = CGAL::Skin_surface_3<Traits>;
using Eigen::Vector3d;
using Clock = std::chrono::steady_clock;

// Weighted points for Skin_surface_3, which grows them itself (weight r²/s).
std::vector<WeightedPoint> weighted_points(const std::vector<Ball>& balls) {
  std::vector<WeightedPoint> wp;
  wp.reserve(balls.size());
  for (const auto& b : balls) wp.emplace_back(K::Point_3(b.centre.x(), b.centre.y(), b.centre.z()), b.radius * b.radius);
  return wp;
}
template <typename P>
Vector3d exact_to_eigen(const P& p) {
  return {CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())};
}

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// The weighted points of a regular-triangulation simplex (1 to 4).
std::vector<Skin::Vertex_handle> simplex_vertices(const Skin::Simplex& s) {
  std::vector<Skin::Vertex_handle> v;
  switch (s.dimension()) {
    case 0: v.push_back(Skin::Vertex_handle(s)); break;
    case 1: {
      const Skin::Edge e(s);
      v = {e.first->vertex(e.second), e.first->vertex(e.third)};
      break;
    }
    case 2: {
      const Skin::Facet f(s);
      for (int i = 1; i <= 3; ++i) v.push_back(f.first->vertex((f.second + i) & 3));
      break;
    }
    case 3: {
      const Skin::Cell_handle c(s);
      for (int i = 0; i < 4; ++i) v.push_back(c->vertex(i));
      break;
    }
    default: break;
  }
  return v;
}

struct MixedCell {
  std::vector<WeightedPoint> weighted;
  std::vector<int> balls;  // ball index per simplex vertex
  SkinQuadric quadric;
  std::vector<Vector3d> points;  // corners of its CGAL tetrahedra (distinct handles)
  std::vector<std::array<Vector3d, 4>> tets;
  bool crossed = false;
};

}  // namespace

SkinConversion convert_skin(const std::vector<Ball>& balls, const SkinOptions& options) {
  validate_balls(balls, options.source);
  const double s = options.shrink;
  if (!(s > 0 && s < 1)) throw InvalidInput(fmt::format("{}: shrink factor {} is outside (0, 1)", options.source, s));
  if (options.tetrahedra == SkinTetrahedra::regular) return convert_skin_regular(balls, options);
  SkinConversion out;
  const auto t0 = Clock::now();
  const std::vector<WeightedPoint> wp = weighted_points(balls);
  Skin skin(wp.begin(), wp.end(), s);
  std::map<std::array<double, 3>, int> ball_of;
  for (int i = 0; i < static_cast<int>(balls.size()); ++i)
    ball_of[{balls[i].centre.x(), balls[i].centre.y(), balls[i].centre.z()}] = i;

  // Group CGAL's tetrahedra by the simplex of their mixed cell.
  using Key = std::array<const void*, 4>;
  std::map<Key, int> cell_of;
  std::vector<MixedCell> cells;
  auto& tmc = skin.triangulated_mixed_complex();
  for (auto ch = tmc.finite_cells_begin(); ch != tmc.finite_cells_end(); ++ch) {
    ++out.cgal_tets;
    const auto& info = ch->info();
    const auto verts = simplex_vertices(info.first);
    Key key{nullptr, nullptr, nullptr, nullptr};
    for (std::size_t i = 0; i < verts.size(); ++i) key[i] = &*verts[i];
    std::sort(key.begin(), key.begin() + verts.size());
    auto [it, fresh] = cell_of.try_emplace(key, static_cast<int>(cells.size()));
    if (fresh) {
      MixedCell m;
      bool bbox = false;
      for (const auto& v : verts) {
        const auto& w = v->point();
        const auto b = ball_of.find({w.x(), w.y(), w.z()});
        if (w.weight() < 0 || b == ball_of.end()) bbox = true;
        else m.balls.push_back(b->second);
        m.weighted.push_back(w);
      }
      if (bbox) m.balls.clear();
      else m.quadric = skin_quadric(m.weighted, s);
      cells.push_back(std::move(m));
    }
    MixedCell& m = cells[it->second];
    if (m.balls.empty()) {
      ++out.bbox_cells_skipped;
      continue;
    }
    std::array<Vector3d, 4> corners;
    for (int i = 0; i < 4; ++i) corners[i] = exact_to_eigen(ch->vertex(i)->point());
    // Check the recomputed quadric against CGAL's value() at the 10 quadratic nodes.
    double diam2 = 0, vmax = 0, dmax = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i; j < 4; ++j) {
        diam2 = std::max(diam2, (corners[i] - corners[j]).squaredNorm());
        const Vector3d x = 0.5 * (corners[i] + corners[j]);
        const double ours = m.quadric.value(x), theirs = info.second->value(K::Point_3(x.x(), x.y(), x.z()));
        vmax = std::max(vmax, std::abs(theirs));
        dmax = std::max(dmax, std::abs(ours - theirs));
      }
    out.max_quadric_disagreement = std::max(out.max_quadric_disagreement, dmax / std::max(vmax, diam2));
    const Vector3d centroid = 0.25 * ((corners[0] + corners[1]) + (corners[2] + corners[3]));
    if (!quadric_may_vanish(corners, m.quadric.relative_to(centroid), centroid)) {
      m.tets.push_back(corners);  // keeps the cell's full vertex set for TetGen
      continue;
    }
    ++out.cgal_tets_crossed;
    m.crossed = true;
    m.tets.push_back(corners);
  }
  out.cgal_seconds = seconds_since(t0);

  PatchEmitter emitter(balls, out, s);
  const auto emit = [&](const MixedCell& m, const std::array<Vector3d, 4>& corners) {
    emitter.emit(m.balls, m.quadric, corners);
  };

  std::vector<const MixedCell*> crossed;
  for (const auto& m : cells) {
    if (m.balls.empty()) continue;
    ++out.mixed_cells;
    if (m.crossed) crossed.push_back(&m);
  }
  out.mixed_cells_crossed = crossed.size();
  if (options.tetrahedra == SkinTetrahedra::cgal) {
    for (const MixedCell* m : crossed)
      for (const auto& t : m->tets) emit(*m, t);
    return out;
  }
  // TetGen: each crossed mixed cell as the convex hull of its CGAL tetrahedra's corners.
  const auto t1 = Clock::now();
  std::vector<std::vector<Vector3d>> hulls(crossed.size());
  for (std::size_t c = 0; c < crossed.size(); ++c) {
    auto& pts = hulls[c];
    for (const auto& t : crossed[c]->tets)
      for (const auto& p : t)
        if (std::find(pts.begin(), pts.end(), p) == pts.end()) pts.push_back(p);
  }
  const Tetrahedralization tets =
      tetrahedralize_convex_cells(hulls, {.source = options.source + " (mixed cells)", .skip_failed = true});
  for (std::size_t c = 0; c < crossed.size(); ++c)
    for (const auto& t : tets.cells[c]) {
      ++out.tetgen_tets;
      emit(*crossed[c], {hulls[c][t[0]], hulls[c][t[1]], hulls[c][t[2]], hulls[c][t[3]]});
    }
  // TetGen 1.5 aborts on some nearly degenerate point sets (an assertion in locate()): those
  // cells keep CGAL's tetrahedra.
  for (const std::size_t c : tets.failed)
    for (const auto& t : crossed[c]->tets) emit(*crossed[c], t);
  out.tetgen_failed_cells = tets.failed.size();
  if (!tets.failed.empty())
    log::info("{}; {} of {} crossed mixed cells keep CGAL's tetrahedra", tets.first_failure, tets.failed.size(),
              crossed.size());
  out.tetgen_seconds = seconds_since(t1);
  log::debug("{}: {} mixed cells ({} crossed), {} CGAL tetrahedra ({} crossed), {} TetGen tetrahedra, {} patches",
             options.source, out.mixed_cells, out.mixed_cells_crossed, out.cgal_tets, out.cgal_tets_crossed,
             out.tetgen_tets, out.model.tets.size());
  return out;
}

TriangleMesh cgal_skin_mesh(const std::vector<Ball>& balls, double shrink, int subdivisions) {
  validate_balls(balls, "skin mesh");
  using Polyhedron = CGAL::Polyhedron_3<K, CGAL::Skin_surface_polyhedral_items_3<Skin>>;
  const std::vector<WeightedPoint> wp = weighted_points(balls);
  const Skin skin(wp.begin(), wp.end(), shrink);
  Polyhedron p;
  CGAL::mesh_skin_surface_3(skin, p);
  if (subdivisions > 0) CGAL::subdivide_skin_surface_mesh_3(skin, p, subdivisions);
  TriangleMesh m;
  std::unordered_map<const void*, int> index;
  for (auto v = p.vertices_begin(); v != p.vertices_end(); ++v) {
    index[&*v] = static_cast<int>(m.vertices.size());
    m.vertices.push_back(to_eigen(v->point()));
  }
  for (auto f = p.facets_begin(); f != p.facets_end(); ++f) {
    auto h = f->facet_begin();
    std::vector<int> ids;
    do ids.push_back(index.at(&*h->vertex()));
    while (++h != f->facet_begin());
    for (std::size_t i = 1; i + 1 < ids.size(); ++i) m.triangles.push_back({ids[0], ids[i], ids[i + 1]});
  }
  return m;
}

}  // namespace quadrix
