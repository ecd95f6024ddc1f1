// Curvature glyphs from CGAL's jet fitting (Cazals & Pouget's Monge_via_jet_fitting): the only
// file that includes it.
#include "convert/curvature_glyphs.h"

#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix {
namespace {

using K = CGAL::Simple_cartesian<double>;
using Fitting = CGAL::Monge_via_jet_fitting<K>;

Eigen::Vector3d to_eigen(const K::Vector_3& v) { return {v.x(), v.y(), v.z()}; }

// Blue (concave) → green (saddle) → red (convex) over the shape index s ∈ [−1, 1].
Rgb shape_colour(double s) {
  const double t = std::clamp(0.5 * (s + 1.0), 0.0, 1.0);
  const auto mix = [](double a, double b, double u) { return static_cast<std::uint8_t>(std::lround(a + (b - a) * u)); };
  if (t < 0.5) return Rgb{mix(40, 60, 2 * t), mix(80, 190, 2 * t), mix(220, 70, 2 * t)};
  return Rgb{mix(60, 225, 2 * t - 1), mix(190, 60, 2 * t - 1), mix(70, 45, 2 * t - 1)};
}

}  // namespace

CurvatureGlyphs curvature_glyphs(const PolygonMesh& mesh, const CurvatureGlyphOptions& o) {
  if (mesh.vertices.empty() || mesh.face_count() == 0) throw InvalidInput("curvature glyphs: the mesh has no faces");
  if (o.jet_degree < 2 || o.jet_degree > 4)
    throw InvalidInput(fmt::format("curvature glyphs: jet degree {} is not in 2..4", o.jet_degree));
  const int min_points = (o.jet_degree + 1) * (o.jet_degree + 2) / 2;
  if (o.neighbours < min_points)
    throw InvalidInput(fmt::format("curvature glyphs: {} neighbours are too few for a degree-{} jet (at least {})",
                                   o.neighbours, o.jet_degree, min_points));
  if (!(o.size > 0) || !(o.thickness > 0) || !(o.min_axis > 0 && o.min_axis <= 1))
    throw InvalidInput("curvature glyphs: size and thickness must be > 0, min_axis in (0, 1]");

  const std::size_t n = mesh.vertices.size();
  std::vector<std::vector<int>> adjacent(n);
  std::vector<Eigen::Vector3d> normal(n, Eigen::Vector3d::Zero());
  double edge_sum = 0;
  std::size_t edges = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto face = mesh.face(f);
    Eigen::Vector3d newell = Eigen::Vector3d::Zero();  // area-weighted face normal
    for (std::size_t k = 0; k < face.size(); ++k) {
      const int a = face[k], b = face[(k + 1) % face.size()];
      adjacent[a].push_back(b);
      adjacent[b].push_back(a);
      edge_sum += (mesh.vertices[a] - mesh.vertices[b]).norm();
      ++edges;
      newell += mesh.vertices[a].cross(mesh.vertices[b]);
    }
    for (const int v : face) normal[v] += newell;
  }
  for (auto& a : adjacent) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  CurvatureGlyphs out;
  out.mean_edge = edge_sum / static_cast<double>(std::max<std::size_t>(edges, 1));

  // Per vertex: rings around it until enough points, then the jet fit.
  struct Fit {
    std::size_t vertex;
    Eigen::Vector3d d_max, d_min, n;
    double k_max, k_min;
  };
  std::vector<Fit> fits;
  std::vector<int> mark(n, -1);
  std::vector<K::Point_3> points;
  std::vector<int> ring, next;
  for (std::size_t v = 0; v < n; ++v) {
    if (!(normal[v].norm() > 0)) {
      ++out.skipped;
      continue;
    }
    points.clear();
    ring.assign(1, static_cast<int>(v));
    mark[v] = static_cast<int>(v);
    const auto add = [&](int u) { points.emplace_back(mesh.vertices[u].x(), mesh.vertices[u].y(), mesh.vertices[u].z()); };
    add(static_cast<int>(v));  // the fit's Monge form is taken at the first point
    while (static_cast<int>(points.size()) < o.neighbours && !ring.empty()) {
      next.clear();
      for (const int r : ring)
        for (const int u : adjacent[r])
          if (mark[u] != static_cast<int>(v)) {
            mark[u] = static_cast<int>(v);
            next.push_back(u);
            add(u);
          }
      ring.swap(next);
    }
    if (static_cast<int>(points.size()) < min_points) {
      ++out.skipped;
      continue;
    }
    Fitting fitting;
    const Fitting::Monge_form m = fitting(points.begin(), points.end(), o.jet_degree, 2);
    Fitting::Monge_form oriented = m;
    const Eigen::Vector3d nv = normal[v].normalized();
    oriented.comply_wrt_given_normal(K::Vector_3(nv.x(), nv.y(), nv.z()));
    const double k1 = oriented.principal_curvatures(0), k2 = oriented.principal_curvatures(1);
    if (!std::isfinite(k1) || !std::isfinite(k2) || !(fitting.condition_number() < 1e12)) {
      ++out.skipped;
      continue;
    }
    // CGAL's height grows along the normal: a sphere with outward normals has k < 0 there.
    fits.push_back({v, to_eigen(oriented.minimal_principal_direction()), to_eigen(oriented.maximal_principal_direction()),
                    to_eigen(oriented.normal_direction()), -k2, -k1});
  }
  if (fits.empty()) throw InvalidInput("curvature glyphs: no vertex could be fitted");

  // |k| relative to the mesh's 95th percentile, so a few sharp vertices do not flatten the rest.
  std::vector<double> magnitudes;
  for (const Fit& f : fits) magnitudes.insert(magnitudes.end(), {std::abs(f.k_max), std::abs(f.k_min)});
  std::nth_element(magnitudes.begin(), magnitudes.begin() + magnitudes.size() * 95 / 100, magnitudes.end());
  const double k_ref = std::max(magnitudes[magnitudes.size() * 95 / 100], 1e-300);
  const double size = o.size * out.mean_edge;
  for (const Fit& f : fits) {
    const auto axis = [&](double k) { return size * std::clamp(std::abs(k) / k_ref, o.min_axis, 1.0); };
    Glyph g;
    g.kind = GlyphKind::ellipsoid;
    g.centre = mesh.vertices[f.vertex];
    g.axes.col(0) = f.d_max.normalized() * axis(f.k_max);
    g.axes.col(1) = f.d_min.normalized() * axis(f.k_min);
    g.axes.col(2) = f.n.normalized() * (o.thickness * out.mean_edge);
    // Shape index ([Koenderink92]): −1 cup, 0 saddle, +1 cap.
    const double s = f.k_max == f.k_min ? (f.k_max > 0 ? 1.0 : f.k_max < 0 ? -1.0 : 0.0)
                                        : 2.0 / std::numbers::pi * std::atan((f.k_max + f.k_min) / (f.k_max - f.k_min));
    g.colour = shape_colour(s);
    out.model.glyphs.push_back(g);
    out.k_max.push_back(f.k_max);
    out.k_min.push_back(f.k_min);
    out.vertex.push_back(f.vertex);
  }
  out.model.metadata["closed"] = "1";  // ellipsoids bound solids
  return out;
}

}  // namespace quadrix
