// quadrix bench render INPUT: frame time and fragment work of the GL renderer, side by side in
// one run: quadrics with per-quadric culling, without it, SLIM with ball splats (the baseline of
// the tight ones), and (for a quad mesh input) the same mesh drawn as flat triangles by the same
// renderer ([Stoll06] Table 2); for glyphs, the same glyphs tessellated finely enough that
// silhouettes stay within half a pixel.
#include <algorithm>
#include <cmath>
#include <ctime>
#include <numbers>
#include <filesystem>
#include <fstream>

#include <optional>

#include <fmt/format.h>

#include "convert/quads.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "core/slim.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tools/cli.h"

namespace quadrix::cli {
namespace {

struct Row {
  std::string name;
  double ms_cpu_median = 0;  // CPU time of the process per frame (all of llvmpipe's threads): steadier under load
  double ms_median = 0, ms_min = 0, ms_clear = 0, ms_geometry = 0, ms_slim = 0, ms_shading = 0, ms_shadows = 0;
  std::uint64_t primitives = 0, culled = 0, fragments = 0, covered = 0;
  std::uint64_t chunks = 0, chunks_culled = 0, culled_in_chunks = 0;  // tetrahedron chunks
  std::uint64_t chunks_occluded = 0, occluded_in_chunks = 0;
  double slim_waste = 0;
  // SLIM fragment shader runs of passes 1 and 2, and those that ray-cast their patch (the rest
  // returned after a depth test in the shader or outside the ball's disc).
  std::uint64_t slim_runs = 0, slim_casts = 0;
  double glyph_waste = 0;  // glyph proxy fragments outside their glyph over those run
  // SLIM level of detail (models with a hierarchy): the bound, the cut, its image error.
  double pixel_error = 0;
  std::uint64_t slim_balls = 0;
  std::string level_mix{};            // "level:balls …", level 0 the leaves
  double symmetric_difference = 0;   // covered pixels differing from full detail / those covered there
  double depth_p99 = 0;              // |depth − full detail's| where both covered, p99, / model diagonal
  std::vector<std::uint8_t> coverage{};
  std::vector<float> depth{};
  double invocations_per_covered() const { return covered ? double(fragments) / covered : 0; }
};

double cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

Row measure(const std::string& name, render::Renderer& r, const Camera& cam, bool cull, int frames,
            const SlimBlendOptions& blend = {}, bool tight_splats = true, bool effects = false,
            bool tet_early_depth = true, bool tet_occlusion = true, int shadow_map_size = 0, double pixel_error = 0,
            std::optional<bool> glyph_early_depth = std::nullopt,
            std::optional<int> slim_splat_sides = std::nullopt) {
  render::RenderOptions o;
  o.slim_splat_sides = slim_splat_sides;
  o.shadow_map_size = shadow_map_size;
  o.slim_pixel_error = pixel_error;
  o.tet_occlusion = tet_occlusion;
  o.cull = cull;
  o.shadows = o.outlines = effects;  // as [Sigg06] Table 1's second row
  o.tet_early_depth = tet_early_depth;
  // Glyphs: the platform's way unless asked (render/passes/glyph_pass.h); the hit-depth rows draw
  // each glyph's polygon writing its hit's depth.
  o.glyph_early_depth = glyph_early_depth;
  if (!tet_early_depth) o.glyph_early_depth = false, o.glyph_rectangles = false;
  o.slim_early_depth = tet_early_depth;   // SLIM: splats at conservative depths, nearest chunks first (slim_pass.h)
  o.slim_tight_splats = tight_splats;
  o.set_slim_blend(blend);
  o.statistics = true;
  const auto st = r.draw(cam, o);
  const auto g = r.read_gbuffer();
  Row row;
  row.name = name;
  row.primitives = st.primitives;
  row.culled = st.culled;
  row.chunks = st.chunks;
  row.chunks_culled = st.chunks_culled;
  row.culled_in_chunks = st.culled_in_chunks;
  row.chunks_occluded = st.chunks_occluded;
  row.occluded_in_chunks = st.occluded_in_chunks;
  row.fragments = st.fragments;
  row.slim_waste = st.slim_waste();
  row.slim_runs = st.slim_splat_fragments + st.slim_accumulate_fragments;
  row.slim_casts = st.slim_cast_fragments;
  row.glyph_waste = st.glyph_waste();
  row.covered = std::count(g.coverage.begin(), g.coverage.end(), 1);
  row.pixel_error = pixel_error;
  row.slim_balls = st.slim_balls;
  for (std::size_t k = 0; k < st.slim_level_counts.size(); ++k)
    if (st.slim_level_counts[k]) row.level_mix += fmt::format("{}{}:{}", row.level_mix.empty() ? "" : " ", k, st.slim_level_counts[k]);
  row.coverage = g.coverage;
  row.depth = g.depth;
  o.statistics = false;
  r.draw(cam, o);  // warm-up
  std::vector<double> ms;
  std::vector<double> cpu;
  for (int f = 0; f < frames; ++f) {
    const double c0 = cpu_ms();
    ms.push_back(r.draw(cam, o).ms_total);
    cpu.push_back(cpu_ms() - c0);
  }
  std::sort(cpu.begin(), cpu.end());
  row.ms_cpu_median = cpu[cpu.size() / 2];
  std::sort(ms.begin(), ms.end());
  row.ms_median = ms[ms.size() / 2];
  row.ms_min = ms.front();
  // Per-pass split, from separate frames with a glFinish after each pass.
  o.time_passes = true;
  std::vector<double> c, geo, sl, s, shadow;
  for (int f = 0; f < std::max(3, frames / 2); ++f) {
    const auto st = r.draw(cam, o);
    c.push_back(st.ms_clear), geo.push_back(st.ms_geometry), sl.push_back(st.ms_slim), s.push_back(st.ms_shading);
    shadow.push_back(st.ms_shadows);
  }
  const auto med = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  row.ms_clear = med(c), row.ms_geometry = med(geo), row.ms_slim = med(sl), row.ms_shading = med(s);
  row.ms_shadows = med(shadow);
  return row;
}

// Glyphs as triangles whose silhouettes deviate at most `max_px` pixels from the true ones in
// this view: per glyph n segments around with R(1 − cos(π/n)) ≤ max_px, R its projected radius
// in pixels at its nearest point (UV spheres and ellipsoids with n/2 rings; cylinders with caps).
PolygonMesh tessellate_glyphs(const Model& m, const Camera& cam, double max_px, std::size_t& triangles) {
  PolygonMesh mesh;
  const double focal = 0.5 * cam.height / std::tan(0.5 * cam.fov_y_deg * std::numbers::pi / 180.0);
  const double pi = std::numbers::pi;
  triangles = 0;
  for (const Glyph& g : m.glyphs) {
    Eigen::Matrix3d M;
    if (g.kind == GlyphKind::sphere) M = g.radius * Eigen::Matrix3d::Identity();
    else if (g.kind == GlyphKind::ellipsoid) M = g.axes;
    else {
      const Eigen::Vector3d a = g.axes.col(0), an = a.normalized();
      const Eigen::Vector3d e1 = an.cross(std::abs(an.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).normalized();
      M.col(0) = g.radius * e1, M.col(1) = g.radius * an.cross(e1), M.col(2) = a;
    }
    const double size = g.kind == GlyphKind::cylinder ? g.radius : M.colwise().norm().maxCoeff();
    const double reach = M.colwise().norm().sum();
    const double dist = std::max((g.centre - cam.eye).norm() - reach, cam.near_plane);
    const double r_px = size * focal / dist;
    int n = r_px <= max_px ? 6 : static_cast<int>(std::ceil(pi / std::acos(1.0 - max_px / r_px)));
    n = std::clamp(n + (n & 1), 6, 512);
    const int base = static_cast<int>(mesh.vertices.size());
    if (g.kind != GlyphKind::cylinder) {
      const int rings = n / 2;
      mesh.vertices.push_back(g.centre + M * Eigen::Vector3d(0, 0, -1));
      for (int i = 1; i < rings; ++i) {
        const double th = pi * i / rings - pi / 2;
        for (int j = 0; j < n; ++j) {
          const double ph = 2 * pi * j / n;
          mesh.vertices.push_back(g.centre + M * Eigen::Vector3d(std::cos(th) * std::cos(ph), std::cos(th) * std::sin(ph), std::sin(th)));
        }
      }
      mesh.vertices.push_back(g.centre + M * Eigen::Vector3d(0, 0, 1));
      const int top = static_cast<int>(mesh.vertices.size()) - 1;
      const auto v = [&](int ring, int j) { return base + 1 + (ring - 1) * n + (j % n); };
      for (int j = 0; j < n; ++j) {
        const int bottom_tri[3] = {base, v(1, j + 1), v(1, j)};
        mesh.add_face(bottom_tri);
        const int top_tri[3] = {top, v(rings - 1, j), v(rings - 1, j + 1)};
        mesh.add_face(top_tri);
        for (int i = 1; i + 1 < rings; ++i) {
          const int quad[4] = {v(i, j), v(i, j + 1), v(i + 1, j + 1), v(i + 1, j)};
          mesh.add_face(quad);
        }
      }
      triangles += 2 * n * (rings - 1);
    } else {
      for (const double z : {-1.0, 1.0})
        for (int j = 0; j < n; ++j) {
          const double ph = 2 * pi * j / n;
          mesh.vertices.push_back(g.centre + M * Eigen::Vector3d(std::cos(ph), std::sin(ph), z));
        }
      std::vector<int> bottom(n), top(n);
      for (int j = 0; j < n; ++j) {
        const int quad[4] = {base + j, base + (j + 1) % n, base + n + (j + 1) % n, base + n + j};
        mesh.add_face(quad);
        bottom[n - 1 - j] = base + j;
        top[j] = base + n + j;
      }
      mesh.add_face(bottom);
      mesh.add_face(top);
      triangles += 2 * n + 2 * (n - 2);
    }
  }
  return mesh;
}

// The image error of a row against the full-detail row: symmetric difference of the covered
// pixels (over those covered at full detail) and the p99 of the depth difference where both cover.
void image_error(Row& row, const Row& full, double diagonal) {
  std::size_t diff = 0, covered = 0;
  std::vector<double> dd;
  for (std::size_t i = 0; i < full.coverage.size() && i < row.coverage.size(); ++i) {
    covered += full.coverage[i];
    diff += full.coverage[i] != row.coverage[i];
    if (full.coverage[i] && row.coverage[i]) dd.push_back(std::abs(double(row.depth[i]) - double(full.depth[i])));
  }
  row.symmetric_difference = covered ? double(diff) / double(covered) : 0.0;
  if (!dd.empty()) {
    const auto p = dd.begin() + static_cast<std::ptrdiff_t>(dd.size() * 99 / 100);
    std::nth_element(dd.begin(), p, dd.end());
    row.depth_p99 = *p / std::max(diagonal, 1e-300);
  }
}

}  // namespace

void add_bench_render(CLI::App& bench, Commands& commands) {
  auto* app = bench.add_subcommand("render", "GL frame time: culling on/off, SLIM tight vs ball splats, quads vs flat triangles");
  struct Args {
    std::string input, out = "out/bench", context = "auto", size = "1024x1024", baseline, baseline_model;
    int frames = 10;
    int shadow_map = 0;
    double azimuth = 30, elevation = 20;
    std::vector<double> pixel_errors{0.25, 0.5, 1, 2, 4};
  };
  auto a = std::make_shared<Args>();
  app->add_option("INPUT", a->input, "A quad mesh (.obj/.off/.ply: converted here) or a .qxm/.slim2t model")->required();
  app->add_option("--out", a->out, "Folder for bench_render.json and bench_render.csv");
  app->add_option("--baseline-mesh", a->baseline,
                  "A triangle mesh drawn as the baseline row (e.g. a decimated mesh of the same error)");
  app->add_option("--baseline-model", a->baseline_model,
                  "A .qxm drawn as the row 'baseline model' with the same camera (e.g. a coarser fit of the same "
                  "data), its image error against full detail, and each LOD row's frame time over it");
  app->add_option("--context", a->context, "GL context")->check(CLI::IsMember(render::context_names()));
  app->add_option("--size", a->size, "Image size WxH, or N for N×N");
  app->add_option("--frames", a->frames, "Timed frames per configuration (median reported)")->check(number({.lo = 1, .hi = 1000}));
  app->add_option("--azimuth", a->azimuth, "Camera azimuth (degrees)")->check(finite());
  app->add_option("--shadow-map", a->shadow_map, "Shadow map side of the shadows+outlines rows (0: as render)")
      ->check(number({.lo = 0, .hi = 16384}));
  app->add_option("--elevation", a->elevation, "Camera elevation (degrees)")->check(number({.lo = -89.9, .hi = 89.9}));
  app->add_option("--pixel-errors", a->pixel_errors, "For a SLIM hierarchy: the --pixel-error levels of the LOD rows "
                                                     "(the other rows draw full detail)")
      ->delimiter(',')
      ->check(number({.lo = 0, .hi = 1000}))
      ->capture_default_str();
  commands.push_back({app, [a](const CommonOptions& common, Report& report) {
                        const auto [w, h] = parse_size(a->size);
                        const std::string ext = std::filesystem::path(a->input).extension().string();
                        const bool is_mesh = ext != ".qxm" && ext != ".slim2t";
                        std::optional<PolygonMesh> mesh;
                        Model model;
                        if (is_mesh) {
                          mesh = read_mesh(a->input);
                          model = convert_quads(*mesh, {}).model;
                        } else {
                          model = read_model(a->input);
                        }
                        const Camera cam = frame_box(bounds(model), {.azimuth_deg = a->azimuth,
                                                                     .elevation_deg = a->elevation,
                                                                     .width = w,
                                                                     .height = h});
                        auto context = render::create_context(a->context, {.width = w, .height = h});
                        std::vector<Row> rows;
                        std::optional<Progress> progress(std::in_place, "bench render", progress_allowed(common),
                                                         Progress::Indeterminate{});
                        {
                          render::Renderer r(*context);
                          r.set_model(model);
                          rows.push_back(measure("quadrics, culling on", r, cam, true, a->frames, slim_blend_of(model)));
                          rows.push_back(measure("quadrics, culling off", r, cam, false, a->frames, slim_blend_of(model)));
                          if (!model.glyphs.empty()) {
                            rows.push_back(measure("quadrics, shadows+outlines", r, cam, true, a->frames,
                                                   slim_blend_of(model), true, true, true, true, a->shadow_map));
                            // Occluders, nearest hits, one ray per pixel (the default where triangles are cheap).
                            rows.push_back(measure("quadrics, early depth", r, cam, true, a->frames, slim_blend_of(model),
                                                   true, false, true, true, 0, 0, true));
                            // Each polygon fragment writing its hit's depth (no early depth test on llvmpipe).
                            rows.push_back(measure("quadrics, hit depth", r, cam, true, a->frames,
                                                   slim_blend_of(model), true, false, false));
                            rows.push_back(measure("quadrics, hit depth, shadows+outlines", r, cam, true, a->frames,
                                                   slim_blend_of(model), true, true, false, true, a->shadow_map));
                          }
                          if (!model.tets.empty()) {  // without chunk occlusion; with each fragment writing its hit's depth
                            rows.push_back(measure("quadrics, no occlusion", r, cam, true, a->frames,
                                                   slim_blend_of(model), true, false, true, false));
                            rows.push_back(measure("quadrics, hit depth", r, cam, true, a->frames,
                                                   slim_blend_of(model), true, false, false, false));
                          }
                          if (!model.slims.empty()) {  // the baseline splat: the ball's screen rectangle
                            rows.push_back(measure("quadrics, ball splats", r, cam, true, a->frames,
                                                   slim_blend_of(model), false));
                            // The tight splat as the octagon (RenderOptions::slim_splat_sides: the
                            // default on a GPU, the rectangle on software rasterizers).
                            rows.push_back(measure("quadrics, octagon splats", r, cam, true, a->frames,
                                                   slim_blend_of(model), true, false, true, true, 0, 0,
                                                   std::nullopt, 8));
                            // Each splat fragment ray-casts and writes its hit's depth (no early depth test).
                            if (model.glyphs.empty() && model.tets.empty())  // else that row is there
                              rows.push_back(measure("quadrics, hit depth", r, cam, true, a->frames,
                                                   slim_blend_of(model), true, false, false));
                          }
                          // SLIM level of detail: time against image error, each against full detail (row 0).
                          if (!model.slim_hierarchy.empty())
                            for (const double P : a->pixel_errors) {
                              rows.push_back(measure(fmt::format("LOD {:g} px", P), r, cam, true, a->frames,
                                                     slim_blend_of(model), true, false, true, true, 0, P));
                              image_error(rows.back(), rows.front(), bounds(model).diagonal());
                            }
                        }
                        if (!a->baseline_model.empty()) {
                          const Model other = read_model(a->baseline_model);
                          render::Renderer r(*context);
                          r.set_model(other);
                          rows.push_back(measure("baseline model", r, cam, true, a->frames, slim_blend_of(other)));
                          image_error(rows.back(), rows.front(), bounds(model).diagonal());
                        }
                        std::size_t triangles = 0;
                        if (!model.glyphs.empty() && !mesh && a->baseline.empty()) {
                          // The baseline of glyphs: the same glyphs as triangles, silhouettes within 0.5 px.
                          mesh = tessellate_glyphs(model, cam, 0.5, triangles);
                          render::Renderer r(*context);
                          r.set_mesh(*mesh);
                          rows.push_back(measure("tessellated glyphs", r, cam, false, a->frames));
                          rows.push_back(measure("tessellated, shadows+outlines", r, cam, false, a->frames,
                                                 SlimBlendOptions{}, true, true, true, true, a->shadow_map));
                          mesh.reset();
                        }
                        if (!a->baseline.empty()) mesh = read_mesh(a->baseline);
                        if (mesh) {
                          render::Renderer r(*context);
                          r.set_mesh(*mesh);
                          rows.push_back(measure(a->baseline.empty() ? "flat triangles" : "baseline mesh", r, cam,
                                                 false, a->frames));
                          for (std::size_t f = 0; f < mesh->face_count(); ++f) triangles += mesh->face(f).size() - 2;
                        }
                        progress.reset();
                        nlohmann::json j = {{"input", a->input}, {"width", w}, {"height", h},
                                            {"frames", a->frames}, {"context", context->description()},
                                            {"primitives", model.size()}, {"baseline_triangles", triangles},
                                            {"camera", camera_json(cam)}};
                        const std::string model_name = std::filesystem::path(a->input).stem().string();
                        std::string csv = "model,configuration,ms_median,ms_min,primitives,culled,fragment_invocations,"
                                          "covered_pixels,invocations_per_covered_pixel,slim_splat_waste,glyph_proxy_waste,chunks,chunks_culled,"
                                          "culled_in_chunks,chunks_occluded,occluded_in_chunks,pixel_error,slim_balls,level_mix,"
                                          "symmetric_difference,depth_p99_over_diagonal\n";
                        for (const auto& r : rows) {
                          j["rows"].push_back({{"configuration", r.name}, {"ms_median", r.ms_median},
                                               {"ms_cpu_median", r.ms_cpu_median},
                                               {"ms_min", r.ms_min}, {"ms_clear", r.ms_clear},
                                               {"ms_geometry", r.ms_geometry}, {"ms_slim", r.ms_slim},
                                               {"ms_shading", r.ms_shading}, {"ms_shadows", r.ms_shadows},
                                               {"primitives", r.primitives},
                                               {"culled", r.culled}, {"fragment_invocations", r.fragments},
                                               {"covered_pixels", r.covered},
                                               {"invocations_per_covered_pixel", r.invocations_per_covered()},
                                               {"slim_splat_waste", r.slim_waste},
                                               {"slim_runs_per_covered_pixel", r.covered ? double(r.slim_runs) / r.covered : 0.0},
                                               {"slim_casts_per_covered_pixel", r.covered ? double(r.slim_casts) / r.covered : 0.0},
                                               {"glyph_proxy_waste", r.glyph_waste}, {"chunks", r.chunks},
                                               {"chunks_culled", r.chunks_culled},
                                               {"culled_in_chunks", r.culled_in_chunks},
                                               {"chunks_occluded", r.chunks_occluded},
                                               {"occluded_in_chunks", r.occluded_in_chunks},
                                               {"pixel_error", r.pixel_error}, {"slim_balls", r.slim_balls},
                                               {"level_mix", r.level_mix},
                                               {"symmetric_difference", r.symmetric_difference},
                                               {"depth_p99_over_diagonal", r.depth_p99}});
                          csv += fmt::format("{},\"{}\",{:.3f},{:.3f},{},{},{},{},{:.3f},{:.4f},{:.4f},{},{},{},{},{},{:g},{},{},{:.5f},{:.3g}\n", model_name,
                                             r.name, r.ms_median, r.ms_min, r.primitives, r.culled, r.fragments,
                                             r.covered, r.invocations_per_covered(), r.slim_waste, r.glyph_waste,
                                             r.chunks, r.chunks_culled, r.culled_in_chunks, r.chunks_occluded,
                                             r.occluded_in_chunks, r.pixel_error, r.slim_balls, r.level_mix,
                                             r.symmetric_difference, r.depth_p99);
                          std::printf("%-24s %8.2f ms/frame (min %.2f, CPU %.2f; clear %.1f, tets+mesh %.1f, slim %.1f, "
                                      "shading %.1f, shadow map %.1f)  %7llu culled  %6.2f invocations/covered px",
                                      r.name.c_str(), r.ms_median, r.ms_min, r.ms_cpu_median, r.ms_clear, r.ms_geometry, r.ms_slim,
                                      r.ms_shading, r.ms_shadows, (unsigned long long)r.culled, r.invocations_per_covered());
                          if (!model.slims.empty())
                            std::printf("  waste %.1f %%, SLIM shader runs %.2f, ray casts %.2f /covered px", 100.0 * r.slim_waste,
                                        r.covered ? double(r.slim_runs) / r.covered : 0.0,
                                        r.covered ? double(r.slim_casts) / r.covered : 0.0);
                          if (!model.glyphs.empty()) std::printf("  glyph waste %.1f %%", 100 * r.glyph_waste);
                          if (!model.slim_hierarchy.empty())
                            std::printf("  %llu balls, sym. diff %.2f %%, depth p99 %.2g", (unsigned long long)r.slim_balls,
                                        100 * r.symmetric_difference, r.depth_p99);
                          if (r.chunks)
                            std::printf("  chunks %llu: %llu outside, %llu hidden", (unsigned long long)r.chunks,
                                        (unsigned long long)r.chunks_culled, (unsigned long long)r.chunks_occluded);
                          std::printf("\n");
                        }
                        j["ratio_culling_off_over_on"] = rows[1].ms_median / rows[0].ms_median;
                        const auto row_named = [&](std::string_view n) -> const Row* {
                          for (const auto& r : rows)
                            if (r.name == n) return &r;
                          return nullptr;
                        };
                        const Row* tri = row_named(a->baseline.empty() ? "flat triangles" : "baseline mesh");
                        const Row* ball = row_named("quadrics, ball splats");
                        if (tri) j["ratio_quadrics_culled_over_triangles"] = rows[0].ms_median / tri->ms_median;
                        if (ball) j["ratio_ball_over_tight_splats"] = ball->ms_median / rows[0].ms_median;
                        if (const Row* oct = row_named("quadrics, octagon splats"))
                          j["ratio_octagon_splats_over_default"] = oct->ms_median / rows[0].ms_median;
                        const Row* hit_depth = row_named("quadrics, hit depth");
                        const Row* no_occ = row_named("quadrics, no occlusion");
                        if (hit_depth) {
                          j["ratio_hit_depth_over_early_depth"] = hit_depth->ms_median / rows[0].ms_median;
                          j["ratio_hit_depth_over_early_depth_cpu"] = hit_depth->ms_cpu_median / rows[0].ms_cpu_median;
                        }
                        if (tri) j["ratio_quadrics_culled_over_triangles_cpu"] = rows[0].ms_cpu_median / tri->ms_cpu_median;
                        if (no_occ) j["ratio_no_occlusion_over_occlusion"] = no_occ->ms_median / rows[0].ms_median;
                        // Glyphs against the same glyphs tessellated (issue 13's target: ≤ 0.5), plain and with effects.
                        const Row* tess = row_named("tessellated glyphs");
                        const Row* tess_fx = row_named("tessellated, shadows+outlines");
                        const Row* glyph_fx = row_named("quadrics, shadows+outlines");
                        const Row* hit_fx = row_named("quadrics, hit depth, shadows+outlines");
                        if (tess) j["ratio_glyphs_over_tessellated"] = rows[0].ms_median / tess->ms_median;
                        if (tess_fx && glyph_fx)
                          j["ratio_glyphs_over_tessellated_shadows_outlines"] = glyph_fx->ms_median / tess_fx->ms_median;
                        if (tess && hit_depth) j["ratio_glyphs_hit_depth_over_tessellated"] = hit_depth->ms_median / tess->ms_median;
                        if (const Row* early = row_named("quadrics, early depth"); tess && early)
                          j["ratio_glyphs_early_depth_over_tessellated"] = early->ms_median / tess->ms_median;
                        if (tess_fx && hit_fx)
                          j["ratio_glyphs_hit_depth_over_tessellated_shadows_outlines"] = hit_fx->ms_median / tess_fx->ms_median;
                        if (const Row* base = row_named("baseline model"))
                          for (const auto& r : rows)
                            if (r.name.starts_with("LOD ")) {
                              j["ratio_lod_over_baseline_model"][r.name] = r.ms_median / base->ms_median;
                              std::printf("%s / baseline model: %.2f (min %.2f)\n", r.name.c_str(), r.ms_median / base->ms_median,
                                          r.ms_min / base->ms_min);
                            }
                        std::printf("culling off/on %.2f", rows[1].ms_median / rows[0].ms_median);
                        if (tri) std::printf(", quadrics (culled)/triangles %.2f", rows[0].ms_median / tri->ms_median);
                        if (ball) std::printf(", ball/tight splats %.2f", ball->ms_median / rows[0].ms_median);
                        if (const Row* oct = row_named("quadrics, octagon splats"))
                          std::printf(", octagon splats/default %.2f", oct->ms_median / rows[0].ms_median);
                        if (no_occ) std::printf(", no occlusion/occlusion %.2f", no_occ->ms_median / rows[0].ms_median);
                        // Row 0 draws each kind the default way: early depth and occlusion for tetrahedra
                        // and SLIM; for glyphs the platform's way (one pass with rectangles on llvmpipe).
                        if (hit_depth) std::printf(", hit depth/default %.2f", hit_depth->ms_median / rows[0].ms_median);
                        if (const Row* early = row_named("quadrics, early depth"))
                          std::printf(", glyph early depth/default %.2f", early->ms_median / rows[0].ms_median);
                        if (tess) std::printf(", glyphs/tessellated %.2f", rows[0].ms_median / tess->ms_median);
                        if (tess_fx && glyph_fx)
                          std::printf(", with shadows+outlines %.2f", glyph_fx->ms_median / tess_fx->ms_median);
                        std::printf("\n");
                        std::filesystem::create_directories(a->out);
                        write_file_atomically(std::filesystem::path(a->out) / "bench_render.json",
                                              [&](std::ostream& o) { o << j.dump(2) << "\n"; });
                        write_file_atomically(std::filesystem::path(a->out) / "bench_render.csv",
                                              [&](std::ostream& o) { o << csv; });
                        report.json["bench_render"] = j;
                        report.summary = fmt::format("wrote {}/bench_render.{{json,csv}} ({} configurations)", a->out, rows.size());
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
