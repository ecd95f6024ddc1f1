// quadrix convert quads MESH -o FILE: quad meshes to tetrahedron-clipped quadrics ([Stoll06] §4.5).
#include <optional>

#include <fmt/format.h>

#include "convert/quads.h"
#include "core/log.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "tools/cli.h"

namespace quadrix::cli {

void add_convert_volume(CLI::App& convert, Commands& commands);
void add_convert_skin(CLI::App& convert, Commands& commands);
void add_convert_glyphs(CLI::App& convert, Commands& commands);
void add_convert_curvature(CLI::App& convert, Commands& commands);

void add_convert(CLI::App& root, Commands& commands) {
  // `convert` is only a group; main runs the leaf whose app parsed (its parent parses with it).
  auto* convert = root.add_subcommand("convert", "Convert meshes into quadric models");
  convert->require_subcommand(1);
  add_convert_volume(*convert, commands);
  add_convert_skin(*convert, commands);
  add_convert_glyphs(*convert, commands);
  add_convert_curvature(*convert, commands);
  auto* app = convert->add_subcommand("quads", "Quad mesh (OBJ, OFF, PLY) to tetrahedron-clipped quadrics");
  struct Args {
    WriteModelOptions write;  // --encoding
    std::string mesh, out, colour;
    QuadConvertOptions options;
  };
  auto a = std::make_shared<Args>();
  app->add_option("MESH", a->mesh, "Input polygon mesh")->required();
  app->add_option("-o,--out", a->out, "Output .qxm file")->required()->check(qxm_output());
  add_encoding_option(*app, a->write);
  app->add_option("--colour", a->colour, "Constant colour R,G,B (0..255) for every patch");
  app->add_option("--planar-threshold", a->options.planar_threshold,
                  "Store a quad as two flat triangles when its patch is within this fraction of its diameter of them")
      ->check(number({.lo = 0, .hi = 1}));
  app->add_flag("--skip-degenerate", a->options.skip_degenerate, "Skip zero-area faces instead of failing");
  commands.push_back({app, [a](const CommonOptions& common, Report& report) {
                        if (!a->colour.empty()) a->options.colour = parse_rgb(a->colour);
                        a->options.source = a->mesh;
                        const PolygonMesh mesh = read_mesh(a->mesh);
                        const double start = report.elapsed();
                        std::optional<Progress> progress(std::in_place, "quads", progress_allowed(common), Progress::Indeterminate{});
                        QuadConversion conv = convert_quads(mesh, a->options);
                        progress.reset();
                        const double seconds = report.elapsed() - start;
                        const auto& c = conv.counts;
                        auto& meta = conv.model.metadata;
                        meta["producer"] = command_line();
                        meta["source"] = a->mesh;
                        meta["faces"] = fmt::format("{}", mesh.face_count());
                        meta["quads_quadric"] = fmt::format("{}", c.quadric_quads);
                        meta["quads_flat"] = fmt::format("{}", c.flat_quads);
                        meta["quads_split"] = fmt::format("{}", c.split_quads);
                        meta["quads_collapsed"] = fmt::format("{}", c.collapsed_quads);
                        meta["triangles"] = fmt::format("{}", c.triangles);
                        meta["polygons_triangulated"] = fmt::format("{}", c.polygons_triangulated);
                        meta["degenerate_skipped"] = fmt::format("{}", c.degenerate_skipped);
                        meta["planar_threshold"] = fmt::format("{:g}", a->options.planar_threshold);
                        meta["max_error"] = fmt::format("{:.3g}", conv.max_relative_deviation);
                        write_model(conv.model, a->out, a->write);
                        report.json["convert"] = {{"kind", "quads"},
                                                  {"mesh", a->mesh},
                                                  {"out", a->out},
                                                  {"faces", mesh.face_count()},
                                                  {"tets", conv.model.tets.size()},
                                                  {"quads_quadric", c.quadric_quads},
                                                  {"quads_flat", c.flat_quads},
                                                  {"quads_split", c.split_quads},
                                                  {"quads_collapsed", c.collapsed_quads},
                                                  {"triangles", c.triangles},
                                                  {"polygons_triangulated", c.polygons_triangulated},
                                                  {"degenerate_skipped", c.degenerate_skipped},
                                                  {"max_relative_deviation", conv.max_relative_deviation},
                                                  {"convert_seconds", seconds}};
                        report.summary = fmt::format("wrote {}: {} tet patches from {} faces ({} quadric, {} flat, {} split quads, "
                                  "{} triangles) ({:.3f} s converting)",
                                  a->out, conv.model.tets.size(), mesh.face_count(), c.quadric_quads, c.flat_quads,
                                  c.split_quads, c.triangles, seconds);
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
