// quadrix render MODEL --out img.png: ray-cast a model with the OpenGL renderer (contexts osmesa,
// egl, glfw) or the double-precision CPU reference.
#include <algorithm>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <optional>

#include <fmt/format.h>

#include "convert/molecule.h"
#include "convert/molecule_glyphs.h"
#include "core/culling.h"
#include "core/error.h"
#include "core/image.h"
#include "core/implicit/gallery.h"
#include "core/implicit/surface.h"
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
  // Implicit surfaces ([Singh10]): an expression or a gallery surface, added to the model.
  std::string implicit, surface, bounds, amp_test = "auto";
  std::vector<std::string> params;
  double radius = 0, amp_step = 0, amp_tau1 = 0, amp_tau2 = 0, amp_tau3 = 0;
};

// "xmin,xmax,ymin,ymax,zmin,zmax" → a box. \throws CLI::ValidationError.
Box3 parse_bounds(const std::string& text) {
  double v[6];
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &tail) != 6 ||
      !std::all_of(v, v + 6, [](double d) { return std::isfinite(d); }) || !(v[0] < v[1] && v[2] < v[3] && v[4] < v[5]))
    throw CLI::ValidationError("--bounds", fmt::format("expected xmin,xmax,ymin,ymax,zmin,zmax with min < max, got '{}'", text));
  return {Eigen::Vector3d(v[0], v[2], v[4]), Eigen::Vector3d(v[1], v[3], v[5])};
}

// The implicit surface the options describe (none without --implicit or --surface), and the
// root test its gallery entry asks for. Expression errors are usage errors (exit 2).
std::optional<std::pair<ImplicitSurface, std::string>> implicit_from_options(const RenderArgs& a) {
  if (a.implicit.empty() && a.surface.empty()) return std::nullopt;
  if (!a.implicit.empty() && !a.surface.empty()) throw CLI::ValidationError("--implicit", "give --implicit or --surface, not both");
  ImplicitSurface s;
  std::string test = "sign";
  if (!a.surface.empty()) {
    try {
      const implicit::GalleryEntry g = implicit::gallery_surface(a.surface);
      s = g.surface;
      test = g.test;
    } catch (const InvalidInput& e) {
      throw CLI::ValidationError("--surface", e.what());
    }
  } else {
    s.expression = a.implicit;
    s.bounds = {Eigen::Vector3d::Constant(-2), Eigen::Vector3d::Constant(2)};
  }
  if (!a.bounds.empty() && a.radius > 0) throw CLI::ValidationError("--bounds", "give --bounds or --radius, not both");
  if (!a.bounds.empty()) s.bounds = parse_bounds(a.bounds);
  if (a.radius > 0) s.bounds = {Eigen::Vector3d::Constant(-a.radius), Eigen::Vector3d::Constant(a.radius)};
  for (const std::string& p : a.params) {
    const auto eq = p.find('=');
    char* end = nullptr;
    const std::string value = eq == std::string::npos ? "" : p.substr(eq + 1);
    const double v = std::strtod(value.c_str(), &end);
    if (eq == std::string::npos || eq == 0 || value.empty() || *end != '\0' || !std::isfinite(v))
      throw CLI::ValidationError("--param", fmt::format("expected NAME=VALUE with a finite number, got '{}'", p));
    s.parameters[p.substr(0, eq)] = v;
  }
  try {
    implicit::compile(s);
  } catch (const InvalidInput& e) {
    throw CLI::ValidationError(a.surface.empty() ? "--implicit" : "--param", e.what());
  }
  return std::pair(s, test);
}

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
  if (a.out.empty()) throw CLI::ValidationError("--out", "an output PNG is required");
  const auto [w, h] = parse_size(a.size);
  const auto implicit_surface = implicit_from_options(a);
  if (a.model.empty() && !implicit_surface) throw CLI::ValidationError("MODEL", "give a MODEL, --implicit or --surface");
  // A mesh file as MODEL draws just that mesh as flat triangles (the baseline of the benchmarks).
  // A molecule file (PDB, mmCIF) is converted to glyphs on the fly (convert/molecule_glyphs.h).
  const bool model_is_molecule = !a.model.empty() && is_molecule_file(a.model);
  const bool model_is_mesh = !a.model.empty() && !model_is_molecule && detect_file_kind(a.model) == FileKind::mesh;
  Model model = model_is_mesh || a.model.empty() ? Model{}
                : model_is_molecule             ? read_molecule_glyphs(a.model)
                                                : read_model(a.model);
  if (implicit_surface) model.implicits.push_back(implicit_surface->first);
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
  render::AmpOptions amp{.step = a.amp_step, .tau1 = a.amp_tau1, .tau2 = a.amp_tau2, .tau3 = a.amp_tau3};
  const std::string test = a.amp_test != "auto" ? a.amp_test : implicit_surface ? implicit_surface->second : "sign";
  amp.test = test == "taylor" ? render::RootTest::taylor : render::RootTest::sign;
  renderer.set_model(model, amp);
  if (!model.implicits.empty()) {
    j["implicit_test"] = test;
    j["implicit_compile_ms"] = renderer.implicit_compile_ms();
  }
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
  if (!model.implicits.empty()) j["ms_first_frame"] = stats.ms_total;  // includes the JIT of generated shaders
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
  app->add_option("MODEL", a->model, "Model file (.qxm or .slim2t), or a mesh (.ply/.obj/.off/.stl) drawn as flat triangles; optional with --implicit/--surface");
  app->add_option("-o,--out", a->out, "Output PNG (required, except for --surface list)");
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
  app->add_option("--implicit", a->implicit, "Implicit surface S(x,y,z) = 0 to draw (with MODEL if given), e.g. \"x^4 + y^4 + z^4 - 1\"");
  app->add_option("--surface", a->surface, "Built-in implicit surface of [Singh10]'s gallery; 'list' lists them");
  app->add_option("--param", a->params, "Parameter of the implicit expression, NAME=VALUE (repeat)");
  app->add_option("--bounds", a->bounds, "Bounds of the implicit surface: xmin,xmax,ymin,ymax,zmin,zmax (default ±2, or the gallery's)");
  app->add_option("--radius", a->radius, "Bounds of the implicit surface: the cube ±R")->check(CLI::PositiveNumber);
  app->add_option("--amp-step", a->amp_step, "AMP base step b in world units (default: bounds diagonal / 400)")->check(CLI::PositiveNumber);
  app->add_option("--amp-tau1", a->amp_tau1, "AMP proximity threshold τ1 on |S| (default: 0.05 · median |S| over the bounds)")->check(CLI::PositiveNumber);
  app->add_option("--amp-tau2", a->amp_tau2, "AMP far threshold τ2 on |S| (default 2·τ1)")->check(CLI::PositiveNumber);
  app->add_option("--amp-tau3", a->amp_tau3, "AMP horizon threshold τ3 on |∇S·D| (default: 0.1 · median |∇S|)")->check(CLI::PositiveNumber);
  app->add_option("--amp-test", a->amp_test, "AMP root test: auto (the gallery's choice, else sign), sign or taylor")
      ->check(CLI::IsMember({"auto", "sign", "taylor"}));
  commands.push_back({app, [a](const CommonOptions& c, Report& r) {
                        if (a->surface == "list") {
                          for (const auto& g : implicit::gallery())
                            fmt::print("{:<18} {:<44} {}\n", g.name, g.description, g.test);
                          fmt::print("{:<18} {}\n", "chmutov-N", "Chmutov [N], power basis (also -iter-N, -trig-N)");
                          fmt::print("{:<18} {}\n", "blinn-N", "Blinn's blobby with N balls");
                          return int(kOk);
                        }
                        return run_render(*a, c, r);
                      }});
}

}  // namespace quadrix::cli
