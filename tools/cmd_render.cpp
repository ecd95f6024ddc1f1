// quadrix render MODEL --out img.png: ray-cast a model with the OpenGL renderer (contexts osmesa,
// egl, glfw) or the double-precision CPU reference.
#include <algorithm>
#include <filesystem>
#include <cmath>
#include <numbers>
#include <optional>

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
  std::string shading = "phong", mesh, up = "+y", view, background = "255,255,255";
  double azimuth = 30, elevation = 20, fov = 40, zoom = 1, fill = 0.9;
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
  // The view: about the chosen up axis, distance fitted for a 40° lens on the visible geometry
  // (a low-resolution CPU pass, or the mesh's vertices), then --fov and --zoom as the lens.
  double azimuth = a.azimuth, elevation = a.elevation;
  if (a.view == "front") azimuth = 0, elevation = 0;
  else if (a.view == "side") azimuth = 90, elevation = 0;
  else if (a.view == "top") azimuth = 0, elevation = 90;
  else if (a.view == "iso") azimuth = 45, elevation = 35.264389682754654;
  constexpr double kFitFov = 40.0;
  Camera camera = frame_view(box, {.up = parse_axis(a.up), .azimuth_deg = azimuth, .elevation_deg = elevation,
                                   .fov_y_deg = kFitFov, .fit_fov_y_deg = kFitFov, .zoom = 1.0, .margin = 1.05,
                                   .width = w, .height = h});
  if (a.fill > 0) {
    std::vector<Eigen::Vector3d> visible;
    if (!model.empty()) {
      const ReferenceScene scene(model);
      Camera probe = camera;
      const double s = 160.0 / std::max(w, h);
      probe.width = std::max(8, static_cast<int>(std::lround(w * s)));
      probe.height = std::max(8, static_cast<int>(std::lround(h * s)));
      ReferenceRenderOptions po;
      po.trace.cull_backfaces = !a.no_cull;
      po.trace.slim.offset = a.slim_offset >= 0 ? a.slim_offset : slim_offset_of(model);
      const ReferenceImage img = render_reference(scene, probe, po);
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
          if (const std::size_t i = std::size_t(y) * img.width + x; img.coverage[i]) {
            // Pixel corners too, so the bounds are those of the covered pixels, not their centres.
            for (const double dx : {0.0, 1.0})
              for (const double dy : {0.0, 1.0})
                visible.push_back(probe.pixel_ray(x + dx, y + dy).at(img.distance[i]));
          }
    }
    if (mesh) {
      const std::size_t step = std::max<std::size_t>(1, mesh->vertices.size() / 200000);
      for (std::size_t v = 0; v < mesh->vertices.size(); v += step) visible.push_back(mesh->vertices[v]);
    }
    camera = fit_points(camera, visible, a.fill);
  }
  camera.fov_y_deg = 2.0 * std::atan(std::tan(a.fov * std::numbers::pi / 360.0) / a.zoom) * 180.0 / std::numbers::pi;
  const Rgb background = a.background == "none" ? Rgb{255, 255, 255} : parse_rgb(a.background, "--background");
  const bool transparent = a.background == "none";
  nlohmann::json& j = report.json["render"];
  j = {{"model", a.model}, {"primitives", model.size()}, {"width", w}, {"height", h}, {"camera", camera_json(camera)},
       {"framing", {{"up", a.up}, {"view", a.view.empty() ? nlohmann::json(nullptr) : nlohmann::json(a.view)},
                    {"azimuth_deg", azimuth}, {"elevation_deg", elevation}, {"fill", a.fill}, {"zoom", a.zoom}}},
       {"background", a.background}};

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
    Image8 colour = shade_phong(img, camera, {.background = background});
    if (transparent)
      for (std::size_t i = 0; i < img.coverage.size(); ++i) colour.rgba[4 * i + 3] = img.coverage[i] ? 255 : 0;
    write_png(colour, a.out);
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
  Image8 colour = renderer.read_colour();
  std::optional<render::GBuffer> gbuffer;
  if (transparent || a.background != "255,255,255") gbuffer = renderer.read_gbuffer();
  if (gbuffer)
    for (std::size_t i = 0; i < gbuffer->coverage.size(); ++i)
      if (!gbuffer->coverage[i]) {
        std::uint8_t* p = colour.rgba.data() + 4 * i;
        p[0] = background[0], p[1] = background[1], p[2] = background[2];
        p[3] = transparent ? 0 : 255;
      }
  write_png(colour, a.out);
  if (!a.depth_out.empty() || !a.normal_out.empty()) {
    const render::GBuffer g = gbuffer ? *gbuffer : renderer.read_gbuffer();
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
  app->add_option("--azimuth", a->azimuth, "Camera azimuth in degrees about the up axis, from the front")
      ->check(number({.lo = -3600.0, .hi = 3600.0}))
      ->capture_default_str();
  app->add_option("--elevation", a->elevation, "Camera elevation in degrees above the plane normal to up")
      ->check(number({.lo = -90.0, .hi = 90.0}))
      ->capture_default_str();
  app->add_option("--up", a->up, "World up axis: +x -x +y -y +z -z")
      ->check(CLI::IsMember({"+x", "-x", "+y", "-y", "+z", "-z", "x", "y", "z"}))
      ->capture_default_str();
  app->add_option("--view", a->view, "Named view (overrides --azimuth/--elevation): front, side, top, iso")
      ->check(CLI::IsMember({"front", "side", "top", "iso"}));
  app->add_option("--fov", a->fov, "Vertical field of view in degrees: the lens (the distance is fitted for 40, so a "
                                   "narrower lens zooms in)")
      ->check(number({.lo = 0.001, .hi = 179.0}))
      ->capture_default_str();
  app->add_option("--zoom", a->zoom, "Magnification of the framed view")->check(number({.lo = 0.01, .hi = 1000.0}))->capture_default_str();
  app->add_option("--fill", a->fill, "Fraction of the smaller image side the visible geometry fills (0: frame the "
                                     "bounding sphere instead)")
      ->check(number({.lo = 0.0, .hi = 1.0}))
      ->capture_default_str();
  app->add_option("--background", a->background, "Background R,G,B, or none (transparent PNG)")->capture_default_str();
  app->add_option("--shading", a->shading, "phong, envmap (line map) or npr (cel + outlines)")
      ->check(CLI::IsMember({"phong", "envmap", "npr"}));
  app->add_option("--mesh", a->mesh, "Also draw this triangle/polygon mesh (OBJ/OFF/PLY), depth-correct");
  app->add_option("--frames", a->frames, "Frames to time (GL); the report holds medians")->check(number({.lo = 1, .hi = 10000}));
  app->add_option("--depth-out", a->depth_out, "Eye-space depth as PFM (+inf background)");
  app->add_option("--normal-out", a->normal_out, "World-space normals as 3-channel PFM");
  app->add_flag("--no-cull", a->no_cull, "No backface culling (two-sided surfaces)");
  app->add_option("--slim-offset", a->slim_offset, "SLIM blend band, relative to the ball radius (default: the model's slim_offset, else 0.5)")
      ->check(number({.lo = 0, .hi = 10}));
  commands.push_back({app, [a](const CommonOptions& c, Report& r) { return run_render(*a, c, r); }});
}

}  // namespace quadrix::cli
