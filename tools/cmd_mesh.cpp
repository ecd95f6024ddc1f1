// quadrix mesh MODEL -o out.ply|obj|off|stl: any model as a triangle mesh within a measured
// distance of the surface the renderer draws (convert/to_mesh.h).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "convert/self_intersections.h"
#include "convert/to_mesh.h"
#include "core/error.h"
#include "core/io/file.h"
#include "core/log.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "tools/cli.h"
#include "tools/scene_input.h"

namespace quadrix::cli {
namespace {

constexpr double kDefaultMaxError = 1e-3;  // × the bounding-box diagonal

struct MeshArgs {
  std::string model, out;
  std::optional<double> max_error;  // relative to the bounding-box diagonal
  double max_error_abs = 0;
  bool allow_exceed = false;
  std::string style;  ///< a molecule MODEL's glyphs (--style)
  std::string union_mode = "auto";  ///< --union auto|on|off
  ToMeshOptions options;
};

nlohmann::json distance_json(const MeshDistance& d) {
  return {{"max", d.max}, {"rms", d.rms}, {"p99", d.p99}, {"samples", d.samples}, {"misses", d.misses},
          {"beyond", d.beyond}};
}

int run_mesh(const MeshArgs& a, const CommonOptions& common, Report& report) {
  const std::string ext = io::lower_extension(a.out);
  if (ext != ".ply" && ext != ".obj" && ext != ".off" && ext != ".stl")
    throw CLI::ValidationError("--out", fmt::format("{}: the extension picks the format: .ply, .obj, .off or .stl", a.out));
  // MODEL as `render` reads it (tools/scene_input.h): a model, or a molecule as glyphs; a mesh or
  // a point cloud is no model to mesh (a mesh file was refused as "bad magic: not a PLY file").
  if (is_point_cloud_file(a.model))
    throw InvalidInput(fmt::format("{}: a point cloud, not a model: fit it first (quadrix fit) and mesh the model", a.model));
  Scene scene = read_scene({.model = a.model, .mesh = {}, .style = a.style, .colour_by = {}});
  if (scene.kind == SceneInputKind::mesh)
    throw InvalidInput(fmt::format("{}: a triangle mesh already; mesh takes a model (.qxm, Kanai's .slim2t) or a molecule "
                                   "file (.pdb, .cif, …)",
                                   a.model));
  const Model model = std::move(scene.model);
  if (model.empty()) throw InvalidInput(fmt::format("{}: the model holds no primitives", a.model));
  ToMeshOptions o = a.options;
  o.union_glyphs = a.union_mode != "off";
  if (a.union_mode == "on") o.union_max_glyphs = std::numeric_limits<std::size_t>::max();
  if (a.union_mode == "auto" && model.glyphs.size() > o.union_max_glyphs && unions_glyphs(model))
    log::info("mesh: {} glyphs, over {}: meshed glyph by glyph, overlapping ones crossing (--union on makes their union, "
              "about 28 ms a sphere)", model.glyphs.size(), o.union_max_glyphs);
  // Unless given: 1e-3 of the diagonal, or a SLIM fit's own E where it is larger (a blend steps by
  // up to a few E between its sheets: a fit at 1e-2 meshed at 1e-3 ended 5.6 bounds off with open
  // edges, exit 7; at its own E, watertight and within the bound).
  const double diagonal = bounds(model).diagonal();
  o.max_error = a.max_error_abs > 0 ? a.max_error_abs : a.max_error.value_or(kDefaultMaxError) * diagonal;
  if (a.max_error_abs <= 0 && !a.max_error && !model.slims.empty())
    if (const auto fit_e = metadata_number(model, "max_error_abs"); fit_e && std::isfinite(*fit_e) && *fit_e > o.max_error) {
      log::info("mesh: the bound is the fit's own E, {:.3g} ({:.3g} of the diagonal; 1e-3 is the default for other models)",
                *fit_e, *fit_e / diagonal);
      o.max_error = *fit_e;
    }
  Progress progress("mesh", progress_allowed(common));
  o.progress = progress.callback();
  ToMeshResult r = mesh_model(model, o);
  // STL holds no vertex normals (each triangle's own) and no colours: none claimed (the summary
  // said "with colours" and the report `colours: true` for an STL file without them).
  if (io::lower_extension(a.out) == ".stl") {
    r.mesh.normals.clear();
    if (!r.mesh.colours.empty())
      log::warn("mesh: {}: STL holds no colours; the model's are left out (.ply, .obj and .off keep them)", a.out);
    r.mesh.colours.clear();
  }
  write_mesh(r.mesh, a.out);
  // Crossing triangles (convert/self_intersections.h): what a printer's slicer or a boolean
  // operation refuses, though every sample lies within the bound.
  // Measured on the positions as written: STL's are float32, which can make triangles cross.
  PolygonMesh as_written;
  if (io::lower_extension(a.out) == ".stl") {
    as_written = r.mesh;
    for (auto& v : as_written.vertices) v = v.cast<float>().cast<double>();
  }
  const SelfIntersections crossing = self_intersections(as_written.vertices.empty() ? r.mesh : as_written);
  nlohmann::json crossing_examples = nlohmann::json::array();
  for (const auto& [f, g] : crossing.examples) crossing_examples.push_back({f, g});
  report.json["mesh"] = {{"model", a.model},
                         {"input", scene_input_name(scene.kind)},
                         {"out", a.out},
                         {"vertices", r.mesh.vertices.size()},
                         {"triangles", r.mesh.face_count()},
                         {"colours", !r.mesh.colours.empty()},
                         {"normals", !r.mesh.normals.empty()},
                         {"normals_from_faces", r.normals_from_faces},
                         {"bound", r.bound},
                         {"max_error", r.max_error()},
                         {"mesh_to_surface", distance_json(r.mesh_to_surface)},
                         {"surface_to_mesh", distance_json(r.surface_to_mesh)},
                         {"open_edges", r.open_edges},
                         {"self_intersecting_pairs", crossing.pairs},
                         {"self_intersecting_examples", crossing_examples},
                         {"degenerate_triangles", crossing.degenerate},
                         {"pinched_vertices_split", r.pinched_vertices_split},
                         {"glyph_union", r.glyph_union},
                         {"glyph_unions_failed", r.glyph_unions_failed},
                         {"refinements", r.refinements},
                         {"local_rounds", r.local_rounds},
                         {"grid_rounds", r.grid_rounds},
                         {"lattice_rounds", r.lattice_rounds},
                         {"refined_cells", r.refined_cells},
                         {"view_rounds", r.view_rounds},
                         {"fin_rounds", r.fin_rounds},
                         {"on_grid", r.on_grid},
                         {"fin_triangles", r.fin_triangles},
                         {"faces_left_out", r.faces_left_out},
                         {"within_bound", r.within}};
  const bool colours = !r.mesh.colours.empty(), normals = !r.mesh.normals.empty();
  const std::string with_what = colours && normals ? " with normals and colours"
                                : colours          ? " with colours"
                                : normals          ? " with normals"
                                                   : "";
  std::string shape = r.open_edges == 0 ? "closed (no open edges)" : fmt::format("{} open edges", r.open_edges);
  shape += crossing.pairs == 0 ? ", no self-intersections"
                               : fmt::format(", {} pair{} of triangles crossing", crossing.pairs, crossing.pairs == 1 ? "" : "s");
  if (crossing.degenerate > 0) shape += fmt::format(", {} triangles of zero area", crossing.degenerate);
  report.summary = fmt::format("wrote {}: {} triangles, {} vertices{}; max error {:.3g} (bound {:.3g}; mesh->surface {:.3g}, "
                             "surface->mesh {:.3g}), {}",
                             a.out, r.mesh.face_count(), r.mesh.vertices.size(), with_what,
                             r.max_error(), r.bound, r.mesh_to_surface.max, r.surface_to_mesh.max,
                             r.mesh.face_count() == 0 ? "empty" : shape);
  if (r.within) return kOk;
  const std::string what = fmt::format(
      "{}: the mesh is outside the bound {:.3g} after {} refinements (max error {:.3g}, {} samples whose normal met no "
      "surface); the mesh was written to {}",
      a.model, r.bound, r.refinements, r.max_error(), r.mesh_to_surface.misses, a.out);
  if (a.allow_exceed) {
    log::warn("{}", what);
    return kOk;
  }
  std::cerr << "quadrix: " << what << " (--allow-exceed accepts it)\n";
  report.exceeded = what;
  return kExceeded;
}

}  // namespace

void add_mesh(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand("mesh", "Export a model as a triangle mesh (PLY, OBJ, OFF, STL) within a measured error");
  auto a = std::make_shared<MeshArgs>();
  app->add_option("MODEL", a->model, "Model file (.qxm or .slim2t), or a molecule (PDB or mmCIF, converted as render does)")
      ->required();
  add_molecule_style_option(*app, a->style);
  app->add_option("-o,--out", a->out,
                  "Output mesh; the extension picks the format: .ply (binary, normals, colours), .obj, .off, .stl")
      ->required();
  app->add_option("--max-error", a->max_error, "Bound on the distance between mesh and drawn surface, relative to the "
                                               "bounding-box diagonal (default: 1e-3, or a SLIM fit's own E where the "
                                               "model records a larger one)")
      ->check(number({.lo = 1e-7, .hi = 0.5}));
  app->add_option("--max-error-abs", a->max_error_abs, "The bound in world units (overrides --max-error; default: unset)")
      ->check(positive())->default_str("");
  app->add_option("--max-refinements", a->options.max_refinements, "Resolution doublings tried to reach the bound")
      ->check(number({.lo = 0, .hi = 8}))
      ->capture_default_str();
  app->add_option("--local-refinements", a->options.local_refinements,
                  "SLIM: rounds of local refinement per grid (longest-edge bisection, without T-junctions, of the "
                  "triangles whose samples exceed the bound or lie nearest surface points beyond it; new vertices "
                  "moved onto the drawn surface); 0: uniform doublings only")
      ->check(number({.lo = 0, .hi = 40}))
      ->capture_default_str();
  app->add_option("--grid-refinements", a->options.grid_refinements,
                  "SLIM: rounds of local grid refinement per grid (the cells holding samples still beyond the bound "
                  "cut one level finer, down to 1/8 of the grid, without cracks at the seams, and the mesh made "
                  "again; kept while it leaves fewer samples beyond and no larger maximum; none where the triangles' "
                  "refinement was undone); 0: off")
      ->check(number({.lo = 0, .hi = 8}))
      ->capture_default_str();
  app->add_option("--lattice-rounds", a->options.lattice_rounds,
                  "A volume's tetrahedra (marked 'tetrahedra tessellation', as convert volume writes): rounds per resolution cutting the pieces whose faces stay "
                  "beyond the bound (each edge about halved) and meshing again, while few faces are beyond (at most "
                  "4,096 or 1 in 200) and a round brings the maximum down; 0: off")
      ->check(number({.lo = 0, .hi = 12}))
      ->capture_default_str();
  app->add_option("--view-rounds", a->options.view_rounds,
                  "SLIM: rounds moving vertices part of the way towards what grazing views see, where the per-ray "
                  "blend shows them the surface off where a head-on view sees it (at most 0.85 of the bound off it); "
                  "kept while it leaves fewer samples beyond and no larger maximum; 0: off")
      ->check(number({.lo = 0, .hi = 8}))
      ->capture_default_str();
  app->add_flag("!--no-normals", a->options.normals,
                "Write no vertex normals (by default each vertex gets the drawn surface's normal, so other programs "
                "shade the mesh smoothly as the renderer does; .ply, .obj and .off carry them, .stl has none)");
  app->add_option("--union", a->union_mode,
                  "Overlapping glyphs (a molecule's atoms and bonds) as one closed surface, their union (CGAL), "
                  "without the parts hidden inside others, as the renderer draws them: auto (up to 10,000 glyphs: "
                  "about 28 ms a sphere, 7 ms a glyph of balls and sticks), on, off (each glyph its own closed "
                  "mesh; overlapping ones cross)")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  app->add_flag("!--no-open-parts", a->options.open_parts,
                "SLIM: keep the mesh closed: do not leave out faces over cracks or steps of the blend, nor add "
                "open sheets where a patch's rim is drawn alone (a fin no closed surface holds)");
  app->add_option("--slim-offset", a->options.slim_offset,
                  "SLIM blend band, relative to the ball radius (default: the model's slim_offset, else 0.5)")
      ->check(number({.lo = 0.0, .hi = 10.0}))->default_str("");
  app->add_flag("--allow-exceed", a->allow_exceed,
                "Exit 0 even when the mesh stays outside its bound (otherwise exit 7, the mesh still written)");
  commands.push_back({app, [a](const CommonOptions& c, Report& r) { return run_mesh(*a, c, r); }});
}

}  // namespace quadrix::cli
