// quadrix convert curvature-glyphs MESH -o FILE: one ellipsoid per vertex along the principal
// curvature directions ([Toledo04] Fig. 1, 9). Registered under `convert` by add_convert_curvature.
#include <optional>

#include <fmt/format.h>

#include "convert/curvature_glyphs.h"
#include "core/log.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "tools/cli.h"

namespace quadrix::cli {

void add_convert_curvature(CLI::App& convert, Commands& commands) {
  auto* app = convert.add_subcommand("curvature-glyphs", "Mesh (OBJ, OFF, PLY, STL) to curvature-tensor ellipsoids, one per vertex");
  struct Args {
    std::string mesh, out;
    CurvatureGlyphOptions options;
  };
  auto a = std::make_shared<Args>();
  app->add_option("MESH", a->mesh, "Input polygon mesh")->required();
  app->add_option("-o,--out", a->out, "Output .qxm file")->required()->check(qxm_output());
  app->add_option("--jet-degree", a->options.jet_degree, "Degree of the fitted jet")
      ->check(number({.lo = 2, .hi = 4}))
      ->capture_default_str();
  app->add_option("--neighbours", a->options.neighbours, "Vertices per fit (the nearest rings)")
      ->check(number({.lo = 6, .hi = 1000}))
      ->capture_default_str();
  app->add_option("--size", a->options.size, "Largest semi-axis in mean edge lengths")
      ->check(number({.lo = 0.001, .hi = 100.0}))
      ->capture_default_str();
  app->add_option("--thickness", a->options.thickness, "Semi-axis along the normal in mean edge lengths")
      ->check(number({.lo = 0.001, .hi = 100.0}))
      ->capture_default_str();
  commands.push_back({app, [a](const CommonOptions& common, Report& report) {
                        const double t0 = report.elapsed();
                        const PolygonMesh mesh = read_mesh(a->mesh);
                        std::optional<Progress> progress(std::in_place, "curvature glyphs", progress_allowed(common), Progress::Indeterminate{});
                        CurvatureGlyphs g = curvature_glyphs(mesh, a->options);
                        progress.reset();
                        g.model.metadata["producer"] = fmt::format(
                            "quadrix convert curvature-glyphs {} -o {} --jet-degree {} --neighbours {} --size {} --thickness {}",
                            a->mesh, a->out, a->options.jet_degree, a->options.neighbours, a->options.size,
                            a->options.thickness);
                        g.model.metadata["source"] = a->mesh;
                        write_model(g.model, a->out);
                        report.json["convert"] = {{"kind", "curvature-glyphs"}, {"input", a->mesh},
                                                  {"out", a->out},          {"vertices", mesh.vertices.size()},
                                                  {"glyphs", g.model.glyphs.size()}, {"skipped", g.skipped},
                                                  {"mean_edge", g.mean_edge}, {"seconds", report.elapsed() - t0}};
                        report.summary = fmt::format("wrote {}: {} ellipsoids ({} vertices skipped)", a->out, g.model.glyphs.size(), g.skipped);
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
