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

#include "convert/tetrahedralize.h"
#include "core/bounds.h"
#include "core/error.h"
#include "core/log.h"

namespace quadrix {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Traits = CGAL::Skin_surface_traits_3<K>;
using Skin = CGAL::Skin_surface_3<Traits>;
using WeightedPoint = K::Weighted_point_3;
using Eigen::Vector3d;
using Clock = std::chrono::steady_clock;

Vector3d to_eigen(const K::Point_3& p) { return {p.x(), p.y(), p.z()}; }
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

// The skin quadric of a simplex in world coordinates as (centre p, symmetric Q, constant c):
// value(x) = (x − p)ᵀQ(x − p) + c, the closed forms of CGAL's Skin_surface_quadratic_surface_3.h.
struct SkinQuadric {
  Vector3d p = Vector3d::Zero();
  Eigen::Matrix3d Q = Eigen::Matrix3d::Zero();
  double c = 0;

  double value(const Vector3d& x) const { return (x - p).dot(Q * (x - p)) + c; }
  // The quadric relative to the point g: f(y) = value(y + g).
  Quadric relative_to(const Vector3d& g) const {
    const Vector3d d = g - p;
    Quadric q;
    q.A = Q;
    q.b = Q * d;
    q.c = d.dot(Q * d) + c;
    return q;
  }
};

SkinQuadric skin_quadric(const std::vector<WeightedPoint>& w, double s) {
  const K k;
  SkinQuadric q;
  const auto I = Eigen::Matrix3d::Identity();
  switch (w.size()) {
    case 1:
      q.p = to_eigen(w[0].point());
      q.Q = (1 - s) * I;
      q.c = -s * (1 - s) * w[0].weight();
      break;
    case 2: {
      q.p = to_eigen(k.construct_weighted_circumcenter_3_object()(w[0], w[1]));
      q.c = s * (1 - s) * k.compute_squared_radius_smallest_orthogonal_sphere_3_object()(w[0], w[1]);
      const Vector3d t = (to_eigen(w[0].point()) - to_eigen(w[1].point())).normalized();
      q.Q = (1 - s) * I - t * t.transpose();
      break;
    }
    case 3: {
      q.p = to_eigen(k.construct_weighted_circumcenter_3_object()(w[0], w[1], w[2]));
      q.c = s * (1 - s) * k.compute_squared_radius_smallest_orthogonal_sphere_3_object()(w[0], w[1], w[2]);
      const Vector3d a = to_eigen(w[0].point()), b = to_eigen(w[1].point()), cc = to_eigen(w[2].point());
      const Vector3d t = (b - a).cross(cc - a).normalized();
      q.Q = t * t.transpose() - s * I;
      break;
    }
    case 4:
      q.p = to_eigen(k.construct_weighted_circumcenter_3_object()(w[0], w[1], w[2], w[3]));
      q.c = s * (1 - s) * k.compute_squared_radius_smallest_orthogonal_sphere_3_object()(w[0], w[1], w[2], w[3]);
      q.Q = -s * I;
      break;
    default: throw SolverError("skin: a simplex with no vertices");
  }
  return q;
}

// Bézier net of a quadric (relative to the centroid) over a tetrahedron: can it change sign?
bool can_cross(const std::array<Vector3d, 4>& corners, const Quadric& q, const Vector3d& centroid) {
  const Eigen::Matrix4d M = q.matrix();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) {
      const Eigen::Vector4d a = (Eigen::Vector4d() << corners[i] - centroid, 1.0).finished();
      const Eigen::Vector4d b = (Eigen::Vector4d() << corners[j] - centroid, 1.0).finished();
      const double v = a.dot(M * b);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  return lo <= 0 && hi >= 0;
}

struct MixedCell {
  std::vector<WeightedPoint> weighted;
  std::vector<int> balls;  // ball index per simplex vertex
  SkinQuadric quadric;
  std::vector<Vector3d> points;  // corners of its CGAL tetrahedra (distinct handles)
  std::vector<std::array<Vector3d, 4>> tets;
  bool crossed = false;
};

std::vector<WeightedPoint> weighted_points(const std::vector<Ball>& balls) {
  std::vector<WeightedPoint> wp;
  wp.reserve(balls.size());
  for (const auto& b : balls) wp.emplace_back(K::Point_3(b.centre.x(), b.centre.y(), b.centre.z()), b.radius * b.radius);
  return wp;
}

}  // namespace

SkinConversion convert_skin(const std::vector<Ball>& balls, const SkinOptions& options) {
  validate_balls(balls, options.source);
  const double s = options.shrink;
  if (!(s > 0 && s < 1)) throw InvalidInput(fmt::format("{}: shrink factor {} is outside (0, 1)", options.source, s));
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
    if (!can_cross(corners, m.quadric.relative_to(centroid), centroid)) {
      m.tets.push_back(corners);  // keeps the cell's full vertex set for TetGen
      continue;
    }
    ++out.cgal_tets_crossed;
    m.crossed = true;
    m.tets.push_back(corners);
  }
  out.cgal_seconds = seconds_since(t0);

  // Colour of a tetrahedron: the simplex's ball nearest in power distance to its centroid.
  const auto colour = [&](const MixedCell& m, const Vector3d& x) {
    int best = m.balls[0];
    double bd = std::numeric_limits<double>::infinity();
    for (const int b : m.balls) {
      const double d = (x - balls[b].centre).squaredNorm() - balls[b].radius * balls[b].radius;
      if (d < bd) bd = d, best = b;
    }
    return balls[best].colour;
  };
  // The skin body lies inside the union of the balls (a convex combination of balls lies inside
  // their union and shrinking only shrinks it), and inside a mixed cell only the balls of the
  // cell's simplex take part: each tetrahedron is clipped to the box of those balls. The model's
  // bounds, automatic framing and rasterised area then follow the molecule, not CGAL's bounding
  // octahedron, and no tetrahedron is much larger than its patch (float precision on the GPU).
  double size = 0;
  {
    Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const auto& b : balls) lo = lo.cwiseMin(b.centre), hi = hi.cwiseMax(b.centre);
    size = (hi - lo).norm();
  }
  const auto emit_piece = [&](const MixedCell& m, const std::array<Vector3d, 4>& corners) {
    // Slivers (corners coplanar on a cell face) hold no surface of positive area; the .qxm
    // reader rejects them.
    if (is_degenerate_tetrahedron(corners)) {  // the reader's test (1e-12 of diameter³)
      ++out.slivers_skipped;
      return;
    }
    TetPatch t{corners, {}, std::nullopt};
    const Vector3d g = t.centroid();
    const Quadric q = m.quadric.relative_to(g);
    if (!can_cross(corners, q, g)) return;
    t.quadric = q.normalized();
    t.colour = colour(m, g);
    out.model.tets.push_back(t);
  };
  const auto emit = [&](const MixedCell& m, const std::array<Vector3d, 4>& corners) {
    Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    double rmax = 0;
    for (const int b : m.balls) {
      lo = lo.cwiseMin(balls[b].centre - Vector3d::Constant(balls[b].radius));
      hi = hi.cwiseMax(balls[b].centre + Vector3d::Constant(balls[b].radius));
      rmax = std::max(rmax, balls[b].radius);
    }
    const double margin = 1e-3 * std::max(rmax, 1e-3 * size);
    lo -= Vector3d::Constant(margin), hi += Vector3d::Constant(margin);
    bool inside = true;
    for (const auto& c : corners) inside = inside && (c.array() >= lo.array()).all() && (c.array() <= hi.array()).all();
    if (inside) return emit_piece(m, corners);
    ++out.tets_clipped_to_box;
    for (const auto& piece : clip_tetrahedron_to_box(corners, lo, hi)) emit_piece(m, piece);
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
