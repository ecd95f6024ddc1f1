// quadrix bench render INPUT: frame time and fragment work of the GL renderer, side by side in
// one run: quadrics with per-quadric culling, without it, and (for a quad mesh input) the same
// mesh drawn as flat triangles by the same renderer ([Stoll06] Table 2; issue 3 benchmark).
#include <algorithm>
#include <filesystem>
#include <fstream>

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
  double ms_median = 0, ms_min = 0, ms_clear = 0, ms_geometry = 0, ms_slim = 0, ms_shading = 0;
  std::uint64_t primitives = 0, culled = 0, fragments = 0, covered = 0;
  double slim_waste = 0;
  double glyph_waste = 0;  // glyph proxy fragments outside their glyph over those run
  double invocations_per_covered() const { return covered ? double(fragments) / covered : 0; }
};

Row measure(const std::string& name, render::Renderer& r, const Camera& cam, bool cull, int frames,
            double slim_offset = SlimBlendOptions{}.offset) {
  render::RenderOptions o;
  o.cull = cull;
  o.slim_offset = static_cast<float>(slim_offset);
  o.statistics = true;
  const auto st = r.draw(cam, o);
  const auto g = r.read_gbuffer();
  Row row{name};
  row.primitives = st.primitives;
  row.culled = st.culled;
  row.fragments = st.fragments;
  row.slim_waste = st.slim_waste();
  row.glyph_waste = st.glyph_waste();
  row.covered = std::count(g.coverage.begin(), g.coverage.end(), 1);
  o.statistics = false;
  r.draw(cam, o);  // warm-up
  std::vector<double> ms;
  for (int f = 0; f < frames; ++f) ms.push_back(r.draw(cam, o).ms_total);
  std::sort(ms.begin(), ms.end());
  row.ms_median = ms[ms.size() / 2];
  row.ms_min = ms.front();
  // Per-pass split, from separate frames with a glFinish after each pass.
  o.time_passes = true;
  std::vector<double> c, geo, sl, s;
  for (int f = 0; f < std::max(3, frames / 2); ++f) {
    const auto st = r.draw(cam, o);
    c.push_back(st.ms_clear), geo.push_back(st.ms_geometry), sl.push_back(st.ms_slim), s.push_back(st.ms_shading);
  }
  const auto med = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  row.ms_clear = med(c), row.ms_geometry = med(geo), row.ms_slim = med(sl), row.ms_shading = med(s);
  return row;
}

}  // namespace

void add_bench_render(CLI::App& bench, Commands& commands) {
  auto* app = bench.add_subcommand("render", "GL frame time: culling on/off, and quads vs flat triangles");
  struct Args {
    std::string input, out = "out/bench", context = "auto", size = "1024x1024", baseline;
    int frames = 10;
    double azimuth = 30, elevation = 20;
  };
  auto a = std::make_shared<Args>();
  app->add_option("INPUT", a->input, "A quad mesh (.obj/.off/.ply: converted here) or a .qxm/.slim2t model")->required();
  app->add_option("--out", a->out, "Folder for bench_render.json and bench_render.csv");
  app->add_option("--baseline-mesh", a->baseline,
                  "A triangle mesh drawn as the baseline row (e.g. a decimated mesh of the same error)");
  app->add_option("--context", a->context, "GL context")->check(CLI::IsMember(render::context_names()));
  app->add_option("--size", a->size, "Image size WxH");
  app->add_option("--frames", a->frames, "Timed frames per configuration (median reported)")->check(CLI::Range(1, 1000));
  app->add_option("--azimuth", a->azimuth, "Camera azimuth (degrees)");
  app->add_option("--elevation", a->elevation, "Camera elevation (degrees)");
  commands.push_back({app, [a](const CommonOptions&, Report& report) {
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
                        {
                          render::Renderer r(*context);
                          r.set_model(model);
                          rows.push_back(measure("quadrics, culling on", r, cam, true, a->frames, slim_offset_of(model)));
                          rows.push_back(measure("quadrics, culling off", r, cam, false, a->frames, slim_offset_of(model)));
                        }
                        std::size_t triangles = 0;
                        if (!a->baseline.empty()) mesh = read_mesh(a->baseline);
                        if (mesh) {
                          render::Renderer r(*context);
                          r.set_mesh(*mesh);
                          rows.push_back(measure(a->baseline.empty() ? "flat triangles" : "baseline mesh", r, cam,
                                                 false, a->frames));
                          for (std::size_t f = 0; f < mesh->face_count(); ++f) triangles += mesh->face(f).size() - 2;
                        }
                        nlohmann::json j = {{"input", a->input}, {"width", w}, {"height", h},
                                            {"frames", a->frames}, {"context", context->description()},
                                            {"primitives", model.size()}, {"baseline_triangles", triangles},
                                            {"camera", camera_json(cam)}};
                        std::string csv = "configuration,ms_median,ms_min,primitives,culled,fragment_invocations,"
                                          "covered_pixels,invocations_per_covered_pixel,glyph_proxy_waste\n";
                        for (const auto& r : rows) {
                          j["rows"].push_back({{"configuration", r.name}, {"ms_median", r.ms_median},
                                               {"ms_min", r.ms_min}, {"ms_clear", r.ms_clear},
                                               {"ms_geometry", r.ms_geometry}, {"ms_slim", r.ms_slim},
                                               {"ms_shading", r.ms_shading},
                                               {"primitives", r.primitives},
                                               {"culled", r.culled}, {"fragment_invocations", r.fragments},
                                               {"covered_pixels", r.covered},
                                               {"invocations_per_covered_pixel", r.invocations_per_covered()},
                                               {"slim_splat_waste", r.slim_waste},
                                               {"glyph_proxy_waste", r.glyph_waste}});
                          csv += fmt::format("{},{:.3f},{:.3f},{},{},{},{},{:.3f},{:.4f}\n", r.name, r.ms_median,
                                             r.ms_min, r.primitives, r.culled, r.fragments, r.covered,
                                             r.invocations_per_covered(), r.glyph_waste);
                          std::printf("%-24s %8.2f ms/frame (min %.2f; clear %.1f, tets+mesh %.1f, slim %.1f, "
                                      "shading %.1f)  %7llu culled  %6.2f invocations/covered px",
                                      r.name.c_str(), r.ms_median, r.ms_min, r.ms_clear, r.ms_geometry, r.ms_slim,
                                      r.ms_shading, (unsigned long long)r.culled, r.invocations_per_covered());
                          if (model.glyphs.size()) std::printf("  glyph waste %.1f %%", 100 * r.glyph_waste);
                          std::printf("\n");
                        }
                        j["ratio_culling_off_over_on"] = rows[1].ms_median / rows[0].ms_median;
                        if (rows.size() > 2) j["ratio_quadrics_culled_over_triangles"] = rows[0].ms_median / rows[2].ms_median;
                        std::printf("culling off/on %.2f", rows[1].ms_median / rows[0].ms_median);
                        if (rows.size() > 2) std::printf(", quadrics (culled)/triangles %.2f", rows[0].ms_median / rows[2].ms_median);
                        std::printf("\n");
                        std::filesystem::create_directories(a->out);
                        write_file_atomically(std::filesystem::path(a->out) / "bench_render.json",
                                              [&](std::ostream& o) { o << j.dump(2) << "\n"; });
                        write_file_atomically(std::filesystem::path(a->out) / "bench_render.csv",
                                              [&](std::ostream& o) { o << csv; });
                        report.json["bench_render"] = j;
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
