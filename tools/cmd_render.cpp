// quadrix render MODEL --out img.png: ray-cast a model with the OpenGL renderer (contexts osmesa,
// egl, glfw) or the double-precision CPU reference.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <limits>
#include <optional>
#include <span>

#include <fmt/format.h>

#include "core/colour_map.h"
#include "core/culling.h"
#include "core/error.h"
#include "core/limits.h"
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
#include "core/slim_lod.h"
#include "core/shade.h"
#include "fit/patch_error.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tools/cli.h"
#include "tools/scene_input.h"
#include "tools/view_options.h"

namespace quadrix::cli {
namespace {

struct RenderArgs {
  std::string model, out, depth_out, normal_out, backend = "auto", context = "auto", size = "512x512";
  std::string shading = "phong", mesh, background = "255,255,255";
  std::string style;  // a molecule MODEL's glyph style (empty: by atom count)
  ViewArgs view;  // camera options shared with `view`
  bool no_cull = false, contact_sheet = false, shadows = false, outlines = false;
  int frames = 1, supersample = 1, turntable = 0, shadow_map = 0;
  double slim_offset = -1;  // < 0: the model's own (core/slim.h slim_offset_of)
  double pixel_error = SlimLodOptions{}.pixel_error;  // SLIM level of detail (core/slim_lod.h)
  // Implicit surfaces ([Singh10]): an expression or a gallery surface, added to the model.
  std::string implicit, surface, bounds, amp_test = "auto";
  std::vector<std::string> params;
  double radius = 0, amp_step = 0, amp_tau1 = 0, amp_tau2 = 0, amp_tau3 = 0;
  double amp_remainder = render::AmpOptions{}.remainder;
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

// Lower-cased extension of a file name.
std::string extension_of(const std::string& file) {
  std::string e = std::filesystem::path(file).extension().string();
  for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

// out.png → out-0001.png: the name of turntable frame i (from 0).
std::string frame_name(const std::string& out, int i) {
  const std::filesystem::path p(out);
  return (p.parent_path() / fmt::format("{}-{:04d}{}", p.stem().string(), i + 1, p.extension().string())).string();
}

// Writes a colour image in the format its name asks for (checked before rendering).
void write_image(const Image8& image, const std::string& file) {
  if (extension_of(file) == ".png") write_png(image, file);
  else write_jpeg(image, file, {});
}

// The frames side by side: ceil(√n) columns, the rest of the last row background.
Image8 contact_sheet(const std::vector<Image8>& frames, const std::uint8_t fill[4]) {
  const int n = static_cast<int>(frames.size());
  const int cols = static_cast<int>(std::ceil(std::sqrt(double(n)))), rows = (n + cols - 1) / cols;
  const int w = frames[0].width, h = frames[0].height;
  Image8 sheet{w * cols, h * rows, {}};
  sheet.rgba.resize(std::size_t(sheet.width) * sheet.height * 4);
  for (std::size_t i = 0; i < sheet.rgba.size(); ++i) sheet.rgba[i] = fill[i % 4];
  for (int k = 0; k < n; ++k)
    for (int y = 0; y < h; ++y)
      std::copy_n(frames[k].pixel(0, y), 4 * w, sheet.pixel((k % cols) * w, (k / cols) * h + y));
  return sheet;
}

int run_render(const RenderArgs& a, const CommonOptions& common, Report& report) {
  if (a.out.empty()) throw CLI::ValidationError("--out", "an output PNG is required");
  // The format follows the name: PNG or JPEG images, PFM depth and normals; anything else is
  // refused rather than written as PNG bytes under another extension.
  const auto expect_extension = [](const std::string& option, const std::string& file,
                                   std::initializer_list<const char*> exts, const char* format) {
    const std::string e = extension_of(file);
    if (!file.empty() && std::none_of(exts.begin(), exts.end(), [&](const char* x) { return e == x; }))
      throw CLI::ValidationError(option, fmt::format("'{}': this output is written as {}; give a name ending in {}",
                                                     file, format, fmt::join(exts, ", ")));
  };
  expect_extension("--out", a.out, {".png", ".jpg", ".jpeg"}, "PNG or JPEG");
  expect_extension("--depth-out", a.depth_out, {".pfm"}, "PFM");
  expect_extension("--normal-out", a.normal_out, {".pfm"}, "PFM");
  const bool jpeg = extension_of(a.out) != ".png";
  if (jpeg && a.background == "none")
    throw CLI::ValidationError("--background", "JPEG has no transparency: give a .png name for --background none");
  const int turntable = a.turntable;
  if (a.contact_sheet && turntable < 2) throw CLI::ValidationError("--contact-sheet", "needs --turntable N with N ≥ 2");
  if (turntable > 0 && (!a.depth_out.empty() || !a.normal_out.empty()))
    throw CLI::ValidationError("--turntable", "writes colour frames only; render --depth-out/--normal-out as a still");
  if (a.supersample > 1 && (!a.depth_out.empty() || !a.normal_out.empty()))
    throw CLI::ValidationError("--supersample", "filters the colour image only; render --depth-out/--normal-out without it");
  const auto [w, h] = parse_size(a.size);
  const auto implicit_surface = implicit_from_options(a);
  if (a.model.empty() && !implicit_surface) throw CLI::ValidationError("MODEL", "give a MODEL, --implicit or --surface");
  // MODEL and --mesh as `view` reads them (tools/scene_input.h): a mesh file as MODEL draws just
  // that mesh as flat triangles (the baseline of the benchmarks); a molecule file is converted to
  // glyphs on the fly in --style and an atom --colour-by.
  const bool colours_atoms = is_atom_colouring(a.colour_by);
  Scene scene = read_scene({.model = a.model, .mesh = a.mesh, .style = a.style, .colour_by = colours_atoms ? a.colour_by : ""});
  Model model = std::move(scene.model);
  std::optional<PolygonMesh> mesh = std::move(scene.mesh);
  const bool model_is_mesh = scene.kind == SceneInputKind::mesh;
  if (implicit_surface) model.implicits.push_back(implicit_surface->first);
  else set_model_parameters(a, model);
  if (model.empty() && !mesh) throw InvalidInput(fmt::format("{}: the model holds no primitives", a.model));
  if (!model.empty()) {
    const Box3 box = bounds(model);
    check_drawable_extent(box.min, box.max, a.model.empty() ? std::string("the implicit surface") : std::string(a.model));
  }
  const ColourMode colour_by = colours_atoms ? ColourMode::none : parse_colour_mode(a.colour_by);
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
  const SlimBlendOptions blend = slim_blend_of(model, a.slim_offset);
  // The view (tools/view_options.h): tight framing on the visible geometry, from a
  // low-resolution CPU pass and the mesh's vertices.
  const VisibleFn visible = [&](const Camera& c) {
    return visible_points(model, mesh ? &*mesh : nullptr, c, {.cull = !a.no_cull, .slim = blend});
  };
  std::pair<double, double> angles = view_angles(a.view);
  const Camera camera = resolve_camera(a.view, box, w, h, a.view.typed("--size"), visible, turntable > 0, &angles);
  std::vector<Camera> cameras{camera};
  if (turntable > 0) {
    cameras = turntable_cameras(camera, turntable_axis(a.view, camera), turntable,
                                wants_fill(a.view) ? a.view.fill : 0.0, visible);
  }
  if (!a.view.save_camera.empty()) write_camera(cameras.front(), a.view.save_camera);
  const int width = cameras.front().width, height = cameras.front().height;
  const int ss = a.supersample;
  if (std::max(width, height) * ss > 16384)
    throw CLI::ValidationError("--supersample", fmt::format("{}x{} × {} exceeds 16384 pixels a side", width, height, ss));
  const Rgb background = a.background == "none" ? Rgb{255, 255, 255} : parse_rgb(a.background, "--background");
  const bool transparent = a.background == "none";
  nlohmann::json& j = report.json["render"];
  j = {{"model", a.model}, {"primitives", model.size()}, {"width", width}, {"height", height}, {"camera", camera_json(cameras.front())},
       {"framing", framing_json(a.view, angles)},
       {"background", a.background}, {"supersample", ss}, {"input", scene_input_name(scene.kind)}};
  if (scene.kind == SceneInputKind::molecule) j["molecule"] = molecule_json(model);

  std::string backend = a.backend;
  if (backend == "auto") backend = "gl";
  // The CPU reference draws no triangle meshes: a usage error (exit 2), as --shading npr with it.
  if (model_is_mesh && backend == "cpu")
    throw CLI::ValidationError("--backend", "cpu draws no triangle meshes: a mesh MODEL needs --backend gl (or auto)");
  j["backend"] = backend;
  j["slim_offset"] = blend.offset;
  if (std::isfinite(blend.max_push)) j["slim_max_push"] = blend.max_push;
  if (backend == "cpu") {
    if (mesh) throw CLI::ValidationError("--backend", "cpu draws no triangle meshes: --mesh needs --backend gl (or auto)");
    if (a.shading != "phong")
      throw CLI::ValidationError("--shading", fmt::format("the CPU reference shades phong only, not {}; use --backend gl", a.shading));
  }
  // The pixels of one camera at ss× its size, box-filtered down (backgrounds replaced first).
  std::vector<Image8> images;
  std::size_t covered = 0;
  Progress progress(turntable > 0 ? "turntable" : "render", progress_allowed(common));
  // The overlays every backend draws alike after the background: per-pixel colours (normal,
  // depth), the colour bar, the points depth-tested against the surface's depth.
  const auto finish = [&](Image8 colour, const Camera& c, const std::vector<std::uint8_t>& coverage,
                          std::span<const float> depth, std::span<const Eigen::Vector3f> normal) {
    for (std::size_t i = 0; i < coverage.size(); ++i) {
      std::uint8_t* p = colour.rgba.data() + 4 * i;
      if (!coverage[i]) p[0] = background[0], p[1] = background[1], p[2] = background[2];
      p[3] = !transparent || coverage[i] ? 255 : 0;
    }
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
      const PointSplatStats ps = draw_points(colour, c, depth, points->points, {.radius_px = a.point_size * ss});
      j["points"] = {{"file", a.points}, {"count", points->points.size()}, {"drawn", ps.drawn},
                     {"hidden", ps.hidden}, {"outside", ps.outside}};
    }
    if (images.empty()) covered = std::count(coverage.begin(), coverage.end(), 1);
    images.push_back(ss > 1 ? box_filter(colour, ss) : std::move(colour));
    progress.update(double(images.size()) / cameras.size());
  };
  const auto magnified = [ss](Camera c) {
    c.width *= ss, c.height *= ss;
    return c;
  };

  // SLIM level of detail: the pixel bound in the pixels rendered (supersampled ones are smaller).
  // --colour-by error|patch colours the leaves (the patches fitted): those are drawn then.
  const bool has_lod = !model.slim_hierarchy.empty();
  const bool leaves_only = has_lod && (colour_by == ColourMode::error || colour_by == ColourMode::patch);
  if (leaves_only && a.pixel_error > 0) log::info("--colour-by {} colours the leaves: drawn at full detail", a.colour_by);
  const SlimLodOptions lod_options{.pixel_error = leaves_only ? 0.0 : a.pixel_error * ss};
  j["pixel_error"] = leaves_only ? 0.0 : a.pixel_error;
  const auto lod_json = [](const SlimLodCut& c) {
    return nlohmann::json{{"balls", c.balls.size()}, {"level_counts", c.level_counts}};
  };
  if (backend == "cpu") {
    const double t0 = report.elapsed();
    // With a hierarchy, each camera's cut is drawn (the same cut the GL renderer chooses).
    std::optional<SlimLod> lod;
    if (has_lod) lod.emplace(model);
    Model cut_model;
    std::optional<ReferenceScene> scene;
    const auto scene_for = [&](const Camera& c) -> const ReferenceScene& {
      if (!lod) {
        if (!scene) scene.emplace(model);
        return *scene;
      }
      const SlimLodCut cut = lod->cut(c, lod_options);
      if (!j.contains("slim_lod")) j["slim_lod"] = lod_json(cut);
      scene.reset();
      cut_model = slim_cut_model(model, cut.balls);
      return scene.emplace(cut_model);
    };
    scene_for(magnified(cameras.front()));
    ReferenceRenderOptions ro;
    ro.trace.cull_backfaces = !a.no_cull;
    ro.trace.slim = blend;
    ro.shadows = a.shadows;
    if (cameras.size() == 1) ro.progress = progress.callback();
    const double t1 = report.elapsed();
    for (std::size_t k = 0; k < cameras.size(); ++k) {
      const Camera& c = cameras[k];
      const ReferenceImage img = render_reference(k == 0 ? *scene : scene_for(magnified(c)), magnified(c), ro);
      ShadeOptions so;
      so.background = background;
      so.outlines = a.outlines;
      finish(shade_phong(img, magnified(c), so), magnified(c), img.coverage, img.depth, img.normal);
      if (!a.depth_out.empty()) write_pfm(depth_image(img), a.depth_out);
      if (!a.normal_out.empty()) write_pfm(normal_image(img), a.normal_out);
    }
    const double t2 = report.elapsed();
    j["covered_pixels"] = covered;
    j["bvh_nodes"] = scene->bvh_node_count();
    j["seconds_bvh"] = t1 - t0;
    j["seconds_trace"] = t2 - t1;
    log::info("cpu: {}x{} in {:.3f} s", width, height, t2 - t1);
  } else {
    auto context = render::create_context(a.context, {.width = width, .height = height});
    render::Renderer renderer(*context);
    render::AmpOptions amp{.step = a.amp_step, .tau1 = a.amp_tau1, .tau2 = a.amp_tau2, .tau3 = a.amp_tau3};
    amp.remainder = a.amp_remainder;
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
    ro.set_slim_blend(blend);
    ro.shading = a.shading == "envmap" ? render::Shading::envmap
                 : a.shading == "npr"  ? render::Shading::npr
                                       : render::Shading::phong;
    ro.shadows = a.shadows;
    ro.shadow_map_size = a.shadow_map;
    ro.outlines = a.outlines;
    ro.slim_pixel_error = lod_options.pixel_error;
    // One frame with statistics (counted separately: the counters cost time), then N timed
    // frames of the first camera.
    ro.statistics = true;
    const render::FrameStats stats = renderer.draw(magnified(cameras.front()), ro);
    ro.statistics = false;
    std::vector<double> total;
    for (int f = 0; f < a.frames; ++f) total.push_back(renderer.draw(magnified(cameras.front()), ro).ms_total);
    for (std::size_t k = 0; k < cameras.size(); ++k) {
      if (k > 0) renderer.draw(magnified(cameras[k]), ro);
      const render::GBuffer g = renderer.read_gbuffer();
      finish(renderer.read_colour(), magnified(cameras[k]), g.coverage, g.depth, g.normal);
      if (!a.depth_out.empty()) write_pfm(depth_of(g), a.depth_out);
      if (!a.normal_out.empty()) write_pfm(normals_of(g), a.normal_out);
    }
    if (!model.implicits.empty()) j["ms_first_frame"] = stats.ms_total;  // includes the JIT of generated shaders
    const bool has_fs = stats.fragments != static_cast<std::uint64_t>(-1);
    j["context"] = context->description();
    j["frames"] = a.frames;
    j["culling"] = ro.cull;
    // Back sides of tetrahedron patches and glyphs are culled only where exact (core/culling.h).
    j["backface_culling_exact"] = backface_culling_is_exact(model, cameras.front());
    j["shading"] = a.shading;
    j["primitives_drawn"] = stats.primitives - stats.culled;
    j["primitives_culled"] = stats.culled;
    j["fragment_shader_invocations"] = has_fs ? nlohmann::json(stats.fragments) : nlohmann::json(nullptr);
    j["fragments_hit"] = stats.fragments_hit;
    if (!model.slims.empty()) j["slim_splat_waste"] = stats.slim_waste();
    if (has_lod) j["slim_lod"] = {{"balls", stats.slim_balls}, {"level_counts", stats.slim_level_counts}};
    j["ms_frame_median"] = median(total);
    log::info("{}: {}x{}, {:.2f} ms/frame (median of {}), {} drawn, {} culled", context->name(), width, height,
              median(total), a.frames, stats.primitives - stats.culled, stats.culled);
  }
  j["shadows"] = a.shadows;
  j["outlines"] = a.outlines;
  std::vector<std::string> written;
  std::string sheet_size;
  if (turntable > 0 && !a.contact_sheet) {
    for (std::size_t k = 0; k < images.size(); ++k) write_image(images[k], written.emplace_back(frame_name(a.out, int(k))));
  } else if (turntable > 0) {
    const std::uint8_t fill[4] = {background[0], background[1], background[2], std::uint8_t(transparent ? 0 : 255)};
    const Image8 sheet = contact_sheet(images, fill);
    sheet_size = fmt::format("a contact sheet of {}x{}, {} frames of ", sheet.width, sheet.height, images.size());
    write_image(sheet, written.emplace_back(a.out));
  } else {
    write_image(images.front(), written.emplace_back(a.out));
  }
  if (turntable > 0) {
    nlohmann::json cams = nlohmann::json::array();
    for (const Camera& c : cameras) cams.push_back(camera_json(c));
    j["turntable"] = {{"frames", turntable}, {"contact_sheet", a.contact_sheet}, {"files", written}, {"cameras", cams}};
  }
  const std::string drawn = fmt::format("{}{}", model.empty() && mesh ? "" : fmt::format("{} primitives", model.size()),
                                        mesh ? fmt::format("{}{} mesh faces", model.empty() ? "" : ", ", mesh->face_count()) : "");
  report.summary = fmt::format("wrote {}{} ({}{}x{}{}, {}, {} backend)", written.front(),
                               written.size() > 1 ? fmt::format(" … {} ({} frames)", written.back(), written.size()) : "",
                               sheet_size, width, height, ss > 1 ? fmt::format(", {}× supersampled", ss) : "", drawn, backend);
  return kOk;
}

}  // namespace

void add_render(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand("render", "Ray-cast a model into a PNG (and depth/normal PFM)");
  auto a = std::make_shared<RenderArgs>();
  app->add_option("MODEL", a->model, "Model file (.qxm or .slim2t), a molecule (.pdb/.ent/.cif/.mmcif, optionally .gz) "
                                    "drawn as glyphs, or a mesh (.ply/.obj/.off/.stl) drawn as triangles (its vertex normals and colours "
                                    "where it has them); optional "
                                    "with --implicit/--surface");
  app->add_option("-o,--out", a->out, "Output PNG (required, except for --surface list)");
  app->add_option("--backend", a->backend, "auto (gl), gl, or cpu (the reference)")
      ->check(CLI::IsMember({"auto", "gl", "cpu"}));
  app->add_option("--context", a->context, "GL context: auto, osmesa, egl, glfw")
      ->check(CLI::IsMember(render::context_names()));
  app->add_option("--size", a->size, "Image size WxH, or N for N×N");
  add_view_options(*app, a->view);
  app->add_option("--supersample", a->supersample, "Antialiasing: render N×N samples per pixel and box-filter them")
      ->check(number({.lo = 1, .hi = 16}))
      ->capture_default_str();
  app->add_option("--turntable", a->turntable, "Write N frames turning about the up axis, OUT-0001.png … (0: one still)")
      ->check(number({.lo = 0, .hi = 3600}))
      ->capture_default_str();
  app->add_flag("--contact-sheet", a->contact_sheet, "With --turntable: one image of all frames in a grid instead");
  app->add_option("--background", a->background, "Background R,G,B, or none (transparent PNG)")->capture_default_str();
  app->add_option("--shading", a->shading, "phong, envmap (line map) or npr (cel + outlines)")
      ->check(CLI::IsMember({"phong", "envmap", "npr"}));
  app->add_option("--colour-by", a->colour_by, "Colour the surface by: none (the model's colours), error (each patch's "
                                             "measured error, or measured against --points; with a colour bar), patch "
                                             "(a colour per primitive), normal (world normal as RGB), depth (eye depth; "
                                             "with a colour bar); a molecule MODEL's atoms by element (CPK), chain or "
                                             "residue, as convert glyphs")
      ->check(CLI::IsMember({"none", "error", "patch", "normal", "depth", "element", "chain", "residue"}))
      ->capture_default_str();
  app->add_option("--colour-range", a->colour_range, "LO,HI of the colour bar for error or depth (default: the values' "
                                                     "min and max)");
  app->add_option("--points", a->points, "Draw this point cloud (PLY/XYZ) over the model as small splats, depth-tested "
                                        "(points behind the surface hidden); with --colour-by error, measure against it");
  app->add_option("--point-size", a->point_size, "Splat radius of --points in pixels")
      ->check(number({.lo = 0.5, .hi = 64}))
      ->capture_default_str();
  app->add_flag("--shadows", a->shadows, "Shadows of the key light (GL: shadow map with soft edges; cpu: shadow rays)");
  app->add_option("--shadow-map", a->shadow_map,
                  "Shadow map size in pixels per side (GL); 0: two texels per view pixel at the scene's centre")
      ->check(number({.lo = 0, .hi = 16384}))
      ->capture_default_str();
  app->add_flag("--outlines", a->outlines, "Black silhouette and crease lines (depth and normal discontinuities)");
  add_molecule_style_option(*app, a->style);
  app->add_option("--mesh", a->mesh, "Also draw this triangle/polygon mesh (OBJ/OFF/PLY/STL), depth-correct");
  app->add_option("--frames", a->frames, "Frames to time (GL); the report holds medians")->check(number({.lo = 1, .hi = 10000}));
  app->add_option("--depth-out", a->depth_out, "Eye-space depth as PFM (+inf background)");
  app->add_option("--normal-out", a->normal_out, "World-space normals as 3-channel PFM");
  app->add_flag("--no-cull", a->no_cull, "No backface culling (two-sided surfaces)");
  app->add_option("--slim-offset", a->slim_offset, "SLIM blend band, relative to the ball radius (default: the model's slim_offset, else 0.5)")
      ->check(number({.lo = 0, .hi = 10}))
      ->default_str("");
  app->add_option("--pixel-error", a->pixel_error, "SLIM level of detail for models with a hierarchy: draw the "
                                                   "coarsest balls whose error projects below P pixels (0: full detail)")
      ->check(number({.lo = 0, .hi = 1000}))
      ->capture_default_str();
  app->add_option("--implicit", a->implicit, "Implicit surface S(x,y,z) = 0 to draw (with MODEL if given), e.g. \"x^4 + y^4 + z^4 - 1\"");
  app->add_option("--surface", a->surface, "Built-in implicit surface of [Singh10]'s gallery; 'list' lists them");
  app->add_option("--param", a->params, "Parameter of the implicit expression, NAME=VALUE (repeat)")->default_str("");
  app->add_option("--bounds", a->bounds, "Bounds of the implicit surface: xmin,xmax,ymin,ymax,zmin,zmax (default ±2, or the gallery's)");
  app->add_option("--radius", a->radius, "Bounds of the implicit surface: the cube ±R (default: --bounds)")
      ->check(positive())
      ->default_str("");
  app->add_option("--amp-step", a->amp_step, "AMP base step b in world units (default: bounds diagonal / 400)")->check(positive())->default_str("");
  app->add_option("--amp-tau1", a->amp_tau1, "AMP proximity threshold τ1 on |S| (default: 0.05 · median |S| over the bounds)")->check(positive())->default_str("");
  app->add_option("--amp-tau2", a->amp_tau2, "AMP far threshold τ2 on |S| (default 2·τ1)")->check(positive())->default_str("");
  app->add_option("--amp-tau3", a->amp_tau3, "AMP horizon threshold τ3 on |∇S·D| (default: 0.1 · median |∇S|)")->check(positive())->default_str("");
  app->add_option("--amp-remainder", a->amp_remainder,
                  "AMP remainder factor κ: a step whose Taylor lines come within κ·|ΔS′|·s/8 of 0 is quartered (0: off)")
      ->check(number({.lo = 0, .hi = 1e3}))
      ->capture_default_str();
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
