// CGAL peers: Poisson surface reconstruction and the AABB-tree point–mesh distance. The only
// translation unit that includes CGAL (≈ 60 s and 1.5 GB to compile).
#include "bench/peers.h"

#include <chrono>
#include <cmath>
#include <utility>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/compute_average_spacing.h>
#include <CGAL/poisson_surface_reconstruction.h>
#include <CGAL/property_map.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "core/error.h"

namespace quadrix::peers {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using Triangle = Kernel::Triangle_3;
using PointWithNormal = std::pair<Point, Vector>;
using Mesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point to_cgal(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

Poisson reconstruct_poisson(const PointCloud& cloud) {
  if (!cloud.has_normals() || cloud.normals.size() != cloud.points.size())
    throw InvalidInput(fmt::format("reconstruct_poisson: {} points need as many normals, got {}", cloud.points.size(),
                                   cloud.normals.size()));
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<PointWithNormal> input;
  input.reserve(cloud.points.size());
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3d n = cloud.normals[i].normalized();
    input.emplace_back(to_cgal(cloud.points[i]), Vector(n.x(), n.y(), n.z()));
  }
  Poisson out;
  const auto point_map = CGAL::First_of_pair_property_map<PointWithNormal>();
  const auto normal_map = CGAL::Second_of_pair_property_map<PointWithNormal>();
  out.spacing = CGAL::compute_average_spacing<CGAL::Parallel_if_available_tag>(
      input, 6, CGAL::parameters::point_map(point_map));
  Mesh mesh;
  if (!CGAL::poisson_surface_reconstruction_delaunay(input.begin(), input.end(), point_map, normal_map, mesh,
                                                     out.spacing))
    throw SolverError(fmt::format("CGAL Poisson reconstruction failed on {} points (spacing {:.3g})", input.size(),
                                  out.spacing));
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const auto v : mesh.vertices()) {
    const Point& p = mesh.point(v);
    out.mesh.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  for (const auto f : mesh.faces()) {
    std::vector<int> ids;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) ids.push_back(int(v.idx()));
    out.mesh.add_face(ids);
  }
  return out;
}

MeshDistance point_mesh_distance(std::span<const Eigen::Vector3d> points, const PolygonMesh& mesh, double bound) {
  if (mesh.face_count() == 0) throw InvalidInput("point_mesh_distance: the mesh has no faces");
  std::vector<Triangle> triangles;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    for (std::size_t k = 1; k + 1 < vs.size(); ++k)  // fan polygons
      triangles.emplace_back(to_cgal(mesh.vertices[vs[0]]), to_cgal(mesh.vertices[vs[k]]),
                             to_cgal(mesh.vertices[vs[k + 1]]));
  }
  Tree tree(triangles.begin(), triangles.end());
  // Build the tree and its distance kd-tree here, before the parallel queries (CGAL builds both
  // lazily on the first query otherwise).
  tree.build();
  tree.accelerate_distance_queries();
  struct Sum {
    double max = 0, sq = 0;
    std::size_t beyond = 0;
  };
  const Sum total = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size(), 1024), Sum{},
      [&](const tbb::blocked_range<std::size_t>& r, Sum s) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const double d2 = CGAL::to_double(tree.squared_distance(to_cgal(points[i])));
          s.max = std::max(s.max, std::sqrt(d2));
          s.sq += d2;
          s.beyond += std::sqrt(d2) > bound;
        }
        return s;
      },
      [](Sum a, const Sum& b) {
        a.max = std::max(a.max, b.max);
        a.sq += b.sq;
        a.beyond += b.beyond;
        return a;
      });
  MeshDistance d;
  d.points = points.size();
  d.max = total.max;
  d.beyond = total.beyond;
  d.rms = points.empty() ? 0.0 : std::sqrt(total.sq / double(points.size()));
  return d;
}

}  // namespace quadrix::peers
