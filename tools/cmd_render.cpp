// quadrix render MODEL --out img.png: ray-cast a model with the OpenGL renderer (contexts osmesa,
// egl, glfw) or the double-precision CPU reference.
#include <algorithm>
#include <filesystem>
#include <cmath>

#include <fmt/format.h>

#include "convert/molecule.h"
#include "convert/molecule_glyphs.h"
#include "core/culling.h"
#include "core/error.h"
#include "core/image.h"
#include "core/log.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "core/reference.h"
#include "core/slim.h"
#include "core/shade.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tools/cli.h"

namespace quadrix::cli {
namespace {

struct RenderArgs {
  std::string model, out, depth_out, normal_out, backend = "auto", context = "auto", size = "512x512";
  std::string shading = "phong", mesh;
  double azimuth = 30, elevation = 20, fov = 40;
  bool no_cull = false;
  int frames = 1;
  double slim_offset = -1;  // < 0: the model's own (core/slim.h slim_offset_of)
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

FloatImage depth_of(const render::GBuffer& g) { return {g.width, g.height, 1, g.depth}; }
FloatImage normals_of(const render::GBuffer& g) {
  FloatImage f{g.width, g.height, 3, {}};
  for (const auto& n : g.normal) f.data.insert(f.data.end(), {n.x(), n.y(), n.z()});
  return f;
}

int run_render(const RenderArgs& a, const CommonOptions& common, Report& report) {
  const auto [w, h] = parse_size(a.size);
  // A mesh file as MODEL draws just that mesh as flat triangles (the baseline of the benchmarks).
  // A molecule file (PDB, mmCIF) is converted to glyphs on the fly (convert/molecule_glyphs.h).
  const bool model_is_molecule = is_molecule_file(a.model);
  const bool model_is_mesh = !model_is_molecule && detect_file_kind(a.model) == FileKind::mesh;
  const Model model = model_is_mesh ? Model{} : model_is_molecule ? read_molecule_glyphs(a.model) : read_model(a.model);
  std::optional<PolygonMesh> mesh;
  if (!a.mesh.empty()) mesh = read_mesh(a.mesh);
  if (model_is_mesh) {
    if (mesh) throw InvalidInput("give either a mesh as MODEL or --mesh, not both");
    mesh = read_mesh(a.model);
  }
  if (model.empty() && !mesh) throw InvalidInput(fmt::format("{}: the model holds no primitives", a.model));
  Box3 box = bounds(model);
  if (mesh)
    for (const auto& v : mesh->vertices) box.extend(v);
  const Camera camera = frame_box(
      box, {.azimuth_deg = a.azimuth, .elevation_deg = a.elevation, .fov_y_deg = a.fov, .width = w, .height = h});
  nlohmann::json& j = report.json["render"];
  j = {{"model", a.model}, {"primitives", model.size()}, {"width", w}, {"height", h}, {"camera", camera_json(camera)}};

  std::string backend = a.backend;
  if (backend == "auto") backend = "gl";
  if (model_is_mesh && backend == "cpu") throw InvalidInput("a mesh MODEL needs the GL backend");
  j["backend"] = backend;
  const double slim_offset = a.slim_offset >= 0 ? a.slim_offset : slim_offset_of(model);
  j["slim_offset"] = slim_offset;

  if (backend == "cpu") {
    if (mesh) throw InvalidInput("--mesh needs the GL backend");
    const double t0 = report.elapsed();
    const ReferenceScene scene(model);
    Progress progress("render", progress_allowed(common));
    ReferenceRenderOptions ro;
    ro.trace.cull_backfaces = !a.no_cull;
    ro.trace.slim.offset = slim_offset;
    ro.progress = progress.callback();
    const double t1 = report.elapsed();
    const ReferenceImage img = render_reference(scene, camera, ro);
    const double t2 = report.elapsed();
    write_png(shade_phong(img, camera), a.out);
    if (!a.depth_out.empty()) write_pfm(depth_image(img), a.depth_out);
    if (!a.normal_out.empty()) write_pfm(normal_image(img), a.normal_out);
    j["covered_pixels"] = std::count(img.coverage.begin(), img.coverage.end(), 1);
    j["bvh_nodes"] = scene.bvh_node_count();
    j["seconds_bvh"] = t1 - t0;
    j["seconds_trace"] = t2 - t1;
    log::info("cpu: {}x{} in {:.3f} s", w, h, t2 - t1);
    return kOk;
  }

  auto context = render::create_context(a.context, {.width = w, .height = h});
  render::Renderer renderer(*context);
  renderer.set_model(model);
  if (mesh) renderer.set_mesh(*mesh);
  render::RenderOptions ro;
  ro.cull = !a.no_cull;
  ro.slim_offset = static_cast<float>(slim_offset);
  ro.shading = a.shading == "envmap" ? render::Shading::envmap
               : a.shading == "npr"  ? render::Shading::npr
                                     : render::Shading::phong;
  // One frame with statistics (counted separately: the counters cost time), then N timed frames.
  ro.statistics = true;
  const render::FrameStats stats = renderer.draw(camera, ro);
  ro.statistics = false;
  std::vector<double> total;
  for (int f = 0; f < a.frames; ++f) total.push_back(renderer.draw(camera, ro).ms_total);
  write_png(renderer.read_colour(), a.out);
  if (!a.depth_out.empty() || !a.normal_out.empty()) {
    const render::GBuffer g = renderer.read_gbuffer();
    if (!a.depth_out.empty()) write_pfm(depth_of(g), a.depth_out);
    if (!a.normal_out.empty()) write_pfm(normals_of(g), a.normal_out);
  }
  const bool has_fs = stats.fragments != static_cast<std::uint64_t>(-1);
  j["context"] = context->description();
  j["frames"] = a.frames;
  j["culling"] = ro.cull;
  // Back sides of tetrahedron patches and glyphs are culled only where exact (core/culling.h).
  j["backface_culling_exact"] = backface_culling_is_exact(model, camera);
  j["shading"] = a.shading;
  j["primitives_drawn"] = stats.primitives - stats.culled;
  j["primitives_culled"] = stats.culled;
  j["fragment_shader_invocations"] = has_fs ? nlohmann::json(stats.fragments) : nlohmann::json(nullptr);
  j["fragments_hit"] = stats.fragments_hit;
  if (!model.slims.empty()) j["slim_splat_waste"] = stats.slim_waste();
  j["ms_frame_median"] = median(total);
  log::info("{}: {}x{}, {:.2f} ms/frame (median of {}), {} drawn, {} culled", context->name(), w, h, median(total),
            a.frames, stats.primitives - stats.culled, stats.culled);
  return kOk;
}

}  // namespace

void add_render(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand("render", "Ray-cast a model into a PNG (and depth/normal PFM)");
  auto a = std::make_shared<RenderArgs>();
  app->add_option("MODEL", a->model, "Model file (.qxm or .slim2t), or a mesh (.ply/.obj/.off/.stl) drawn as flat triangles")->required();
  app->add_option("-o,--out", a->out, "Output PNG")->required();
  app->add_option("--backend", a->backend, "auto (gl), gl, or cpu (the reference)")
      ->check(CLI::IsMember({"auto", "gl", "cpu"}));
  app->add_option("--context", a->context, "GL context: auto, osmesa, egl, glfw")
      ->check(CLI::IsMember(render::context_names()));
  app->add_option("--size", a->size, "Image size WxH");
  app->add_option("--azimuth", a->azimuth, "Camera azimuth in degrees about +y");
  app->add_option("--elevation", a->elevation, "Camera elevation in degrees")->check(CLI::Range(-89.9, 89.9));
  app->add_option("--fov", a->fov, "Vertical field of view in degrees")->check(CLI::Range(0.001, 179.0));
  app->add_option("--shading", a->shading, "phong, envmap (line map) or npr (cel + outlines)")
      ->check(CLI::IsMember({"phong", "envmap", "npr"}));
  app->add_option("--mesh", a->mesh, "Also draw this triangle/polygon mesh (OBJ/OFF/PLY), depth-correct");
  app->add_option("--frames", a->frames, "Frames to time (GL); the report holds medians")->check(CLI::Range(1, 10000));
  app->add_option("--depth-out", a->depth_out, "Eye-space depth as PFM (+inf background)");
  app->add_option("--normal-out", a->normal_out, "World-space normals as 3-channel PFM");
  app->add_flag("--no-cull", a->no_cull, "No backface culling (two-sided surfaces)");
  app->add_option("--slim-offset", a->slim_offset, "SLIM blend band, relative to the ball radius (default: the model's slim_offset, else 0.5)")
      ->check(CLI::Range(0.0, 10.0));
  commands.push_back({app, [a](const CommonOptions& c, Report& r) { return run_render(*a, c, r); }});
}

}  // namespace quadrix::cli
