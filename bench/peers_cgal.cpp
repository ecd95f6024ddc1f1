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
#include <CGAL/IO/facets_in_complex_2_to_triangle_mesh.h>
#include <CGAL/Implicit_surface_3.h>
#include <CGAL/Poisson_reconstruction_function.h>
#include <CGAL/Surface_mesh_default_triangulation_3.h>
#include <CGAL/make_surface_mesh.h>
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
  // CGAL's poisson_surface_reconstruction_delaunay, step by step with its defaults (angle 20°,
  // radius 30 and distance 0.375 spacings), so that a surface mesher that finds no facet is a
  // failure: the convenience function converts the empty complex anyway and dereferences its
  // first facet (800 points of a sphere: a segfault in 5 of 8 runs of bench fit).
  using Function = CGAL::Poisson_reconstruction_function<Kernel>;
  using Tr = CGAL::Surface_mesher::Surface_mesh_default_triangulation_3_generator<Kernel>::Type;
  using C2t3 = CGAL::Surface_mesh_complex_2_in_triangulation_3<Tr>;
  const auto failed = [&](const char* why) {
    return SolverError(fmt::format("CGAL Poisson reconstruction failed on {} points (spacing {:.3g}): {}", input.size(),
                                   out.spacing, why));
  };
  Function function(input.begin(), input.end(), point_map, normal_map);
  if (!function.compute_implicit_function()) throw failed("no implicit function (its linear solver failed)");
  const Point inner = function.get_inner_point();
  const Kernel::Sphere_3 bsphere = function.bounding_sphere();
  const double sphere_radius = 5.0 * std::sqrt(bsphere.squared_radius());
  const double sm_angle = 20.0, sm_radius = 30.0, sm_distance = 0.375;
  CGAL::Implicit_surface_3<Kernel, Function> surface(function, Kernel::Sphere_3(inner, sphere_radius * sphere_radius),
                                                     sm_distance * out.spacing / 1000.0 / sphere_radius);
  CGAL::Surface_mesh_default_criteria_3<Tr> criteria(sm_angle, sm_radius * out.spacing, sm_distance * out.spacing);
  Tr tr;
  C2t3 c2t3(tr);
  CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Manifold_with_boundary_tag());
  if (tr.number_of_vertices() == 0 || c2t3.number_of_facets() == 0) throw failed("the surface mesher found no facet");
  Mesh mesh;
  CGAL::facets_in_complex_2_to_triangle_mesh(c2t3, mesh);
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
