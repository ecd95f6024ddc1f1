// quadrix tetrahedralize CLOSED_MESH -o solid.mesh: the volume a closed surface bounds as
// tetrahedra (TetGen in its own process, convert/tetrahedralize.h), with a per-vertex field —
// the distance to the boundary, or values sampled from a volume — written beside it, the pair
// `convert volume --tets solid.mesh --values solid.values --iso V` turns into iso-surface patches.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>

#include <fmt/format.h>

#include "convert/tetmesh_io.h"
#include "convert/tetrahedralize.h"
#include "convert/volume.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "core/mesh_io.h"
#include "fit/data_surface.h"
#include "tools/cli.h"

namespace quadrix::cli {
namespace {

// Trilinear interpolation of the volume at world point x. \throws InvalidInput outside the grid.
double sample_trilinear(const Volume& v, const Eigen::Vector3d& x, std::size_t vertex) {
  const Eigen::Vector3d g = (x - v.origin).cwiseQuotient(v.spacing);
  std::array<int, 3> i{};
  std::array<double, 3> f{};
  for (int a = 0; a < 3; ++a) {
    const double hi = v.dims[a] - 1;
    if (!(g[a] >= -1e-9 * hi && g[a] <= hi * (1 + 1e-9)))
      throw InvalidInput(fmt::format("{}: vertex {} ({:g}, {:g}, {:g}) lies outside the volume's grid", v.source,
                                     vertex, x.x(), x.y(), x.z()));
    i[a] = std::clamp(static_cast<int>(std::floor(g[a])), 0, v.dims[a] - 2);
    f[a] = std::clamp(g[a] - i[a], 0.0, 1.0);
  }
  double s = 0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
    if (w > 0) s += w * v.at(i[0] + dx, i[1] + dy, i[2] + dz);
  }
  return s;
}

// The default largest tetrahedron: the enclosed volume over this many.
constexpr double kDefaultVolumeCells = 4096;

}  // namespace

void add_tetrahedralize(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand(
      "tetrahedralize",
      "Fill a closed triangle/polygon mesh with tetrahedra (TetGen) and a per-vertex field, for convert volume --tets");
  struct Args {
    std::string mesh, out, values;
    std::vector<std::string> field{"distance"};
    SurfaceTetrahedralizeOptions options;
    std::optional<double> max_volume;
  };
  auto a = std::make_shared<Args>();
  app->add_option("CLOSED_MESH", a->mesh, "Closed, manifold, consistently oriented mesh: PLY, OFF, OBJ, STL")
      ->required();
  app->add_option("-o,--out", a->out, "Output tetrahedral mesh (Medit .mesh)")->required();
  app->add_option("--values", a->values, "Output per-vertex values (default: the output's name with .values)");
  app->add_option("--field", a->field,
                  "Per-vertex field: distance (to the boundary, world units) or volume FILE (trilinear samples of "
                  "a .nhdr/.nrrd/.inr volume)")
      ->expected(1, 2)
      ->capture_default_str();
  app->add_option("--quality", a->options.quality,
                  "TetGen's radius-edge ratio bound (>= 1.1; smaller: rounder tetrahedra, more points; 0: none)")
      ->check(number({.lo = 0, .hi = 100}))
      ->capture_default_str();
  app->add_option("--max-volume", a->max_volume,
                  "Largest tetrahedron volume, world units^3 (0: unbounded; default: the volume the mesh encloses / "
                  "4096, so the inside has vertices for the field: a cube's 6 tetrahedra have none, and its distance "
                  "field was 0 everywhere)")
      ->check(non_negative());
  commands.push_back({app, [a](const CommonOptions& common, Report& report) {
                        const std::string kind = a->field.at(0);
                        if (!(kind == "distance" && a->field.size() == 1) && !(kind == "volume" && a->field.size() == 2))
                          throw CLI::ValidationError("--field", "expected 'distance' or 'volume FILE'");
                        if (a->options.quality != 0 && a->options.quality < 1.1)
                          throw CLI::ValidationError("--quality", fmt::format("{:g} is not 0 or >= 1.1", a->options.quality));
                        if (std::filesystem::path(a->out).extension() != ".mesh")
                          throw CLI::ValidationError("--out", fmt::format("'{}': the output is a Medit .mesh file", a->out));
                        std::filesystem::path values = a->values;
                        if (values.empty()) values = std::filesystem::path(a->out).replace_extension(".values");
                        // The volume first, so a bad FILE fails before TetGen runs.
                        std::optional<Volume> volume;
                        if (kind == "volume") volume = read_volume(a->field[1]);

                        const double t0 = report.elapsed();
                        const PolygonMesh mesh = read_mesh(a->mesh);
                        std::vector<std::array<int, 3>> triangles;
                        for (std::size_t f = 0; f < mesh.face_count(); ++f) {
                          const auto face = mesh.face(f);
                          for (std::size_t k = 1; k + 1 < face.size(); ++k) triangles.push_back({face[0], face[k], face[k + 1]});
                        }
                        SurfaceTetrahedralizeOptions o = a->options;
                        o.source = a->mesh;
                        if (a->max_volume) {
                          o.max_volume = *a->max_volume;
                        } else {
                          double enclosed = 0;  // |Σ a·(b × c)| / 6 over the triangles
                          for (const auto& t : triangles)
                            enclosed += mesh.vertices[t[0]].dot(mesh.vertices[t[1]].cross(mesh.vertices[t[2]])) / 6.0;
                          o.max_volume = std::abs(enclosed) / kDefaultVolumeCells;
                        }
                        std::optional<Progress> progress(std::in_place, "tetrahedralize", progress_allowed(common), Progress::Indeterminate{});
                        const SurfaceTetrahedralization tets = tetrahedralize_closed_surface(mesh.vertices, triangles, o);
                        const double tet_seconds = report.elapsed() - t0;

                        TetMesh out;
                        out.vertices = tets.points;
                        out.tets = tets.tets;
                        out.source = a->out;
                        validate_tet_mesh(out);
                        std::vector<double> field(out.vertices.size());
                        const double t1 = report.elapsed();
                        if (volume) {
                          for (std::size_t i = 0; i < field.size(); ++i) field[i] = sample_trilinear(*volume, out.vertices[i], i);
                        } else {
                          const DataSurface boundary = DataSurface::from_mesh(mesh);
                          for (std::size_t i = 0; i < field.size(); ++i) field[i] = boundary.distance(out.vertices[i]);
                        }
                        const double field_seconds = report.elapsed() - t1;
                        const auto [lo, hi] = std::minmax_element(field.begin(), field.end());
                        progress.reset();
                        write_medit_mesh(out, a->out);
                        write_file_atomically(values, [&](std::ostream& os) {
                          os << (volume ? fmt::format("# values of {} at the vertices of {} (trilinear)\n", a->field[1], a->out)
                                        : fmt::format("# distance to the boundary of {} at the vertices of {}\n", a->mesh, a->out));
                          for (const double v : field) os << fmt::format("{:.17g}\n", v);
                        });
                        report.json["tetrahedralize"] = {{"mesh", a->mesh},
                                                         {"out", a->out},
                                                         {"values", values.string()},
                                                         {"field", volume ? "volume" : "distance"},
                                                         {"surface_vertices", mesh.vertices.size()},
                                                         {"surface_triangles", triangles.size()},
                                                         {"vertices", out.vertices.size()},
                                                         {"tets", out.tets.size()},
                                                         {"quality", o.quality},
                                                         {"max_volume", o.max_volume},
                                                         {"value_min", *lo},
                                                         {"value_max", *hi},
                                                         {"tetrahedralize_seconds", tet_seconds},
                                                         {"field_seconds", field_seconds}};
                        report.summary = fmt::format("wrote {} ({} vertices, {} tetrahedra) and {} ({} from {:g} to {:g})", a->out,
                                                     out.vertices.size(), out.tets.size(), values.string(),
                                                     volume ? "volume samples" : "distance to the boundary", *lo, *hi);
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
