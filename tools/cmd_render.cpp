// quadrix render MODEL --out img.png: ray-cast a model with the OpenGL renderer (contexts osmesa,
// egl, glfw) or the double-precision CPU reference.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <limits>
#include <span>
#include <optional>

#include <fmt/format.h>

#include "convert/molecule.h"
#include "convert/molecule_glyphs.h"
#include "core/colour_map.h"
#include "core/culling.h"
#include "core/error.h"
#include "core/image.h"
#include "core/implicit/gallery.h"
#include "core/implicit/surface.h"
#include "core/log.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "core/overlay.h"
#include "core/points_io.h"
#include "core/reference.h"
#include "core/slim.h"
#include "core/shade.h"
#include "fit/patch_error.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tools/cli.h"

namespace quadrix::cli {
namespace {

struct RenderArgs {
  std::string model, out, depth_out, normal_out, backend = "auto", context = "auto", size = "512x512";
  std::string shading = "phong", mesh, up = "+y", view, background = "255,255,255";
  double azimuth = 30, elevation = 20, fov = 40, zoom = 1, fill = 0.9;
  bool no_cull = false, shadows = false, outlines = false;
  int frames = 1, shadow_map = 2048;
  double slim_offset = -1;  // < 0: the model's own (core/slim.h slim_offset_of)
  // Implicit surfaces ([Singh10]): an expression or a gallery surface, added to the model.
  std::string implicit, surface, bounds, amp_test = "auto";
  std::vector<std::string> params;
  double radius = 0, amp_step = 0, amp_tau1 = 0, amp_tau2 = 0, amp_tau3 = 0;
  // Seeing the error: --colour-by, its range, and a point cloud drawn over the model.
  std::string colour_by = "none", colour_range, points;
  double point_size = 1.5;
};

// "LO,HI" → a range with LO < HI. \throws CLI::ValidationError.
ValueRange parse_range(const std::string& text) {
  double lo = 0, hi = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf%c", &lo, &hi, &tail) != 2 || !std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi))
    throw CLI::ValidationError("--colour-range", fmt::format("expected LO,HI with finite LO < HI, got '{}'", text));
  return {lo, hi};
}

// --colour-by error|patch: the model recoloured per primitive (both backends draw its colours).
// error: the patches' measured_error column (written by fit), or measured against --points.
Model colour_model(const Model& model, ColourMode mode, const std::optional<PointCloud>& points, const RenderArgs& a,
                   nlohmann::json& j, ValueRange& range) {
  if (mode == ColourMode::patch) return colour_by_patch(model);
  if (mode != ColourMode::error) return model;
  std::vector<std::optional<double>> values(model.slims.size());
  std::string source;
  if (points) {
    if (model.slims.empty())
      throw CLI::ValidationError("--colour-by", "error against --points is measured for SLIM patches; the model has none");
    const PatchErrors pe = slim_patch_errors(model, *points);
    values = pe.per_patch;
    source = "points";
    j["misses"] = pe.misses;
  } else {
    for (std::size_t i = 0; i < model.slims.size(); ++i) values[i] = model.slims[i].measured_error;
    source = "measured_error";
    if (std::none_of(values.begin(), values.end(), [](const auto& v) { return v.has_value(); }))
      throw CLI::ValidationError("--colour-by", fmt::format("'{}' has no per-patch measured_error (written by quadrix "
                                                            "fit); give --points to measure against", a.model));
  }
  range = {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const auto& v : values)
    if (v) range.lo = std::min(range.lo, *v), range.hi = std::max(range.hi, *v);
  if (!(range.lo <= range.hi)) range = {0, 0};
  if (!a.colour_range.empty()) range = parse_range(a.colour_range);
  j["source"] = source;
  return colour_by_values(model, values, range);
}

// "xmin,xmax,ymin,ymax,zmin,zmax" → a box. \throws CLI::ValidationError.
Box3 parse_bounds(const std::string& text) {
  double v[6];
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &tail) != 6 ||
      !std::all_of(v, v + 6, [](double d) { return std::isfinite(d); }) || !(v[0] < v[1] && v[2] < v[3] && v[4] < v[5]))
    throw CLI::ValidationError("--bounds", fmt::format("expected xmin,xmax,ymin,ymax,zmin,zmax with min < max, got '{}'", text));
  return {Eigen::Vector3d(v[0], v[2], v[4]), Eigen::Vector3d(v[1], v[3], v[5])};
}

// --param NAME=VALUE pairs. \throws CLI::ValidationError for a malformed one.
std::map<std::string, double> parameters_from_options(const RenderArgs& a) {
  std::map<std::string, double> out;
  for (const std::string& p : a.params) {
    const auto eq = p.find('=');
    char* end = nullptr;
    const std::string value = eq == std::string::npos ? "" : p.substr(eq + 1);
    const double v = std::strtod(value.c_str(), &end);
    if (eq == std::string::npos || eq == 0 || value.empty() || *end != '\0' || !std::isfinite(v))
      throw CLI::ValidationError("--param", fmt::format("expected NAME=VALUE with a finite number, got '{}'", p));
    out[p.substr(0, eq)] = v;
  }
  return out;
}

// Without --implicit/--surface, --param sets the parameter in every implicit surface of the model
// that names it; a name none of them uses is a usage error.
void set_model_parameters(const RenderArgs& a, Model& model) {
  for (const auto& [name, v] : parameters_from_options(a)) {
    bool used = false;
    for (ImplicitSurface& s : model.implicits)
      if (const std::vector<std::string> names = implicit::Expression::parse(s.expression).parameters();
          std::find(names.begin(), names.end(), name) != names.end())
        s.parameters[name] = v, used = true;
    if (!used)
      throw CLI::ValidationError("--param", fmt::format("no implicit surface of the model has a parameter '{}'", name));
  }
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
  for (const auto& [name, v] : parameters_from_options(a)) s.parameters[name] = v;
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
  // The format follows the name: PNG images, PFM depth and normals; anything else is refused
  // rather than written as PNG bytes under another extension.
  const auto expect_extension = [](const std::string& option, const std::string& file, const char* ext,
                                   const char* format) {
    std::string e = std::filesystem::path(file).extension().string();
    for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (!file.empty() && e != ext)
      throw CLI::ValidationError(option, fmt::format("'{}': this output is written as {}; give a {} name", file,
                                                     format, ext));
  };
  expect_extension("--out", a.out, ".png", "PNG");
  expect_extension("--depth-out", a.depth_out, ".pfm", "PFM");
  expect_extension("--normal-out", a.normal_out, ".pfm", "PFM");
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
  else set_model_parameters(a, model);
  std::optional<PolygonMesh> mesh;
  if (!a.mesh.empty()) mesh = read_mesh(a.mesh);
  if (model_is_mesh) {
    if (mesh) throw InvalidInput("give either a mesh as MODEL or --mesh, not both");
    mesh = read_mesh(a.model);
  }
  if (model.empty() && !mesh) throw InvalidInput(fmt::format("{}: the model holds no primitives", a.model));
  const ColourMode colour_by = parse_colour_mode(a.colour_by);
  if (!a.colour_range.empty() && colour_by != ColourMode::error && colour_by != ColourMode::depth)
    throw CLI::ValidationError("--colour-range", "applies to --colour-by error or depth");
  std::optional<PointCloud> points;
  if (!a.points.empty()) points = read_points(a.points);
  nlohmann::json colour_json = {{"mode", a.colour_by}};
  ValueRange colour_range;
  model = colour_model(model, colour_by, points, a, colour_json, colour_range);
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
  // The overlays every backend draws alike: per-pixel colours (normal, depth), the colour bar,
  // the points depth-tested against the surface's depth.
  const auto finish = [&](Image8& colour, std::span<const std::uint8_t> coverage, std::span<const float> depth,
                          std::span<const Eigen::Vector3f> normal) {
    if (colour_by == ColourMode::normal || colour_by == ColourMode::depth) {
      if (colour_by == ColourMode::depth)
        colour_range = a.colour_range.empty() ? covered_depth_range(coverage, depth) : parse_range(a.colour_range);
      colour_pixels(colour, colour_by, coverage, depth, normal, colour_range);
    }
    if (colour_by == ColourMode::error || colour_by == ColourMode::depth) {
      draw_colour_bar(colour, colour_range);
      colour_json["range"] = {colour_range.lo, colour_range.hi};
    }
    j["colour_by"] = colour_json;
    if (points) {
      const PointSplatStats ps = draw_points(colour, camera, depth, points->points, {.radius_px = a.point_size});
      j["points"] = {{"file", a.points}, {"count", points->points.size()}, {"drawn", ps.drawn},
                     {"hidden", ps.hidden}, {"outside", ps.outside}};
    }
  };

  std::string backend = a.backend;
  if (backend == "auto") backend = "gl";
  if (model_is_mesh && backend == "cpu") throw InvalidInput("a mesh MODEL needs the GL backend");
  j["backend"] = backend;
  const double slim_offset = a.slim_offset >= 0 ? a.slim_offset : slim_offset_of(model);
  j["slim_offset"] = slim_offset;

  if (backend == "cpu") {
    if (mesh) throw InvalidInput("--mesh needs the GL backend");
    if (a.shading != "phong")
      throw CLI::ValidationError("--shading", fmt::format("the CPU reference shades phong only, not {}; use --backend gl", a.shading));
    const double t0 = report.elapsed();
    const ReferenceScene scene(model);
    Progress progress("render", progress_allowed(common));
    ReferenceRenderOptions ro;
    ro.trace.cull_backfaces = !a.no_cull;
    ro.trace.slim.offset = slim_offset;
    ro.shadows = a.shadows;
    ro.progress = progress.callback();
    const double t1 = report.elapsed();
    const ReferenceImage img = render_reference(scene, camera, ro);
    const double t2 = report.elapsed();
    Image8 colour = shade_phong(img, camera, {.background = background, .outlines = a.outlines});
    if (transparent)
      for (std::size_t i = 0; i < img.coverage.size(); ++i) colour.rgba[4 * i + 3] = img.coverage[i] ? 255 : 0;
    finish(colour, img.coverage, img.depth, img.normal);
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
  ro.shadows = a.shadows;
  ro.shadow_map_size = a.shadow_map;
  ro.outlines = a.outlines;
  // One frame with statistics (counted separately: the counters cost time), then N timed frames.
  ro.statistics = true;
  const render::FrameStats stats = renderer.draw(camera, ro);
  ro.statistics = false;
  std::vector<double> total;
  for (int f = 0; f < a.frames; ++f) total.push_back(renderer.draw(camera, ro).ms_total);
  Image8 colour = renderer.read_colour();
  std::optional<render::GBuffer> gbuffer;
  if (transparent || a.background != "255,255,255" || colour_by != ColourMode::none || points)
    gbuffer = renderer.read_gbuffer();
  if (gbuffer)
    for (std::size_t i = 0; i < gbuffer->coverage.size(); ++i)
      if (!gbuffer->coverage[i]) {
        std::uint8_t* p = colour.rgba.data() + 4 * i;
        p[0] = background[0], p[1] = background[1], p[2] = background[2];
        p[3] = transparent ? 0 : 255;
      }
  if (gbuffer) finish(colour, gbuffer->coverage, gbuffer->depth, gbuffer->normal);
  else finish(colour, {}, {}, {});
  write_png(colour, a.out);
  if (!a.depth_out.empty() || !a.normal_out.empty()) {
    const render::GBuffer g = gbuffer ? *gbuffer : renderer.read_gbuffer();
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
  j["shadows"] = a.shadows;
  j["outlines"] = a.outlines;
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
  app->add_option("--colour-by", a->colour_by, "Colour the surface by: none (the model's colours), error (each patch's "
                                             "measured error, or measured against --points; with a colour bar), patch "
                                             "(a colour per primitive), normal (world normal as RGB), depth (eye depth; "
                                             "with a colour bar)")
      ->check(CLI::IsMember({"none", "error", "patch", "normal", "depth"}))
      ->capture_default_str();
  app->add_option("--colour-range", a->colour_range, "LO,HI of the colour bar for error or depth (default: the values' "
                                                     "min and max)");
  app->add_option("--points", a->points, "Draw this point cloud (PLY/XYZ) over the model as small splats, depth-tested "
                                        "(points behind the surface hidden); with --colour-by error, measure against it");
  app->add_option("--point-size", a->point_size, "Splat radius of --points in pixels")
      ->check(number({.lo = 0.5, .hi = 64}))
      ->capture_default_str();
  app->add_option("--mesh", a->mesh, "Also draw this triangle/polygon mesh (OBJ/OFF/PLY), depth-correct");
  app->add_option("--frames", a->frames, "Frames to time (GL); the report holds medians")->check(number({.lo = 1, .hi = 10000}));
  app->add_option("--depth-out", a->depth_out, "Eye-space depth as PFM (+inf background)");
  app->add_option("--normal-out", a->normal_out, "World-space normals as 3-channel PFM");
  app->add_flag("--no-cull", a->no_cull, "No backface culling (two-sided surfaces)");
  app->add_flag("--shadows", a->shadows, "Shadows of the key light (GL: shadow map with soft edges; cpu: shadow rays)");
  app->add_option("--shadow-map", a->shadow_map, "Shadow map size in pixels per side (GL)")
      ->check(number({.lo = 16, .hi = 16384}))
      ->capture_default_str();
  app->add_flag("--outlines", a->outlines, "Black silhouette and crease lines (depth and normal discontinuities)");
  app->add_option("--slim-offset", a->slim_offset, "SLIM blend band, relative to the ball radius (default: the model's slim_offset, else 0.5)")
      ->check(number({.lo = 0, .hi = 10}));
  app->add_option("--implicit", a->implicit, "Implicit surface S(x,y,z) = 0 to draw (with MODEL if given), e.g. \"x^4 + y^4 + z^4 - 1\"");
  app->add_option("--surface", a->surface, "Built-in implicit surface of [Singh10]'s gallery; 'list' lists them");
  app->add_option("--param", a->params, "Parameter of the implicit expression, NAME=VALUE (repeat)");
  app->add_option("--bounds", a->bounds, "Bounds of the implicit surface: xmin,xmax,ymin,ymax,zmin,zmax (default ±2, or the gallery's)");
  app->add_option("--radius", a->radius, "Bounds of the implicit surface: the cube ±R")->check(positive());
  app->add_option("--amp-step", a->amp_step, "AMP base step b in world units (default: bounds diagonal / 400)")->check(positive());
  app->add_option("--amp-tau1", a->amp_tau1, "AMP proximity threshold τ1 on |S| (default: 0.05 · median |S| over the bounds)")->check(positive());
  app->add_option("--amp-tau2", a->amp_tau2, "AMP far threshold τ2 on |S| (default 2·τ1)")->check(positive());
  app->add_option("--amp-tau3", a->amp_tau3, "AMP horizon threshold τ3 on |∇S·D| (default: 0.1 · median |∇S|)")->check(positive());
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
