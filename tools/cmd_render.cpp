// quadrix render MODEL --out img.png: the CPU reference ray caster (GL backends: render/).
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"
#include "core/image.h"
#include "core/log.h"
#include "core/model_io.h"
#include "core/reference.h"
#include "core/shade.h"
#include "tools/cli.h"

namespace quadrix::cli {

void add_render(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand("render", "Ray-cast a model into a PNG (and depth/normal PFM)");
  struct Args {
    std::string model, out, depth_out, normal_out, backend = "cpu", size = "512x512";
    double azimuth = 30, elevation = 20, fov = 40;
    bool no_cull = false;
    double slim_offset = 0.5;
  };
  auto a = std::make_shared<Args>();
  app->add_option("MODEL", a->model, "Model file (.qxm or .slim2t)")->required();
  app->add_option("-o,--out", a->out, "Output PNG")->required();
  app->add_option("--backend", a->backend, "Renderer: cpu (the double-precision reference)")
      ->check(CLI::IsMember({"cpu"}));
  app->add_option("--size", a->size, "Image size WxH");
  app->add_option("--azimuth", a->azimuth, "Camera azimuth in degrees about +y");
  app->add_option("--elevation", a->elevation, "Camera elevation in degrees")->check(CLI::Range(-89.9, 89.9));
  app->add_option("--fov", a->fov, "Vertical field of view in degrees")->check(CLI::Range(0.001, 179.0));
  app->add_option("--depth-out", a->depth_out, "Eye-space depth as PFM (+inf background)");
  app->add_option("--normal-out", a->normal_out, "World-space normals as 3-channel PFM");
  app->add_flag("--no-cull", a->no_cull, "Keep back-facing roots (two-sided surfaces)");
  app->add_option("--slim-offset", a->slim_offset, "SLIM blend band, relative to the ball radius")
      ->check(CLI::Range(0.0, 10.0));
  commands.push_back({app, [a](const CommonOptions& common, Report& report) {
                        const auto [w, h] = parse_size(a->size);
                        const Model model = read_model(a->model);
                        if (model.empty()) throw InvalidInput(fmt::format("{}: the model holds no primitives", a->model));
                        const double t_load = report.elapsed();
                        const Camera camera = frame_box(bounds(model), {.azimuth_deg = a->azimuth,
                                                                        .elevation_deg = a->elevation,
                                                                        .fov_y_deg = a->fov,
                                                                        .width = w,
                                                                        .height = h});
                        const ReferenceScene scene(model);
                        const double t_bvh = report.elapsed();
                        Progress progress("render", progress_allowed(common));
                        ReferenceRenderOptions ro;
                        ro.trace.cull_backfaces = !a->no_cull;
                        ro.trace.slim.offset = a->slim_offset;
                        ro.progress = progress.callback();
                        const ReferenceImage img = render_reference(scene, camera, ro);
                        const double t_render = report.elapsed();
                        write_png(shade_phong(img, camera), a->out);
                        if (!a->depth_out.empty()) write_pfm(depth_image(img), a->depth_out);
                        if (!a->normal_out.empty()) write_pfm(normal_image(img), a->normal_out);
                        std::size_t covered = 0;
                        for (auto c : img.coverage) covered += c;
                        report.json["render"] = {{"backend", a->backend},
                                                 {"model", a->model},
                                                 {"primitives", model.size()},
                                                 {"width", w},
                                                 {"height", h},
                                                 {"covered_pixels", covered},
                                                 {"bvh_nodes", scene.bvh_node_count()},
                                                 {"seconds_load", t_load},
                                                 {"seconds_bvh", t_bvh - t_load},
                                                 {"seconds_trace", t_render - t_bvh}};
                        log::info("rendered {}x{} in {:.3f} s ({} px covered)", w, h, t_render - t_bvh, covered);
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
