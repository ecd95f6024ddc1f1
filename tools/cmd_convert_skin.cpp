// quadrix convert skin INPUT -o FILE: skin surfaces of ball sets (PDB, .cin, .xyzr) as
// tetrahedron-clipped quadrics ([Stoll06] §5.1.2). Registered under the `convert` group by
// add_convert_skin (called from tools/cmd_convert.cpp).
#include <optional>

#include <fmt/format.h>

#include "convert/balls.h"
#include "convert/skin.h"
#include "core/culling.h"
#include "core/log.h"
#include "core/model_io.h"
#include "tools/cli.h"

namespace quadrix::cli {

void add_convert_skin(CLI::App& convert, Commands& commands) {
  auto* app = convert.add_subcommand(
      "skin", "Skin surface of a ball set (.pdb, .cif, .cin, .xyzr) to tetrahedron-clipped quadrics (CGAL + TetGen)");
  struct Args {
    WriteModelOptions write;  // --encoding
    std::string input, out, radii = "vdw", tetrahedra = "regular";
    double shrink = 0.5, radius_scale = 1.0;
    bool no_water = false;
  };
  auto a = std::make_shared<Args>();
  app->add_option("INPUT", a->input, "Balls: a molecule's atoms (PDB .pdb/.ent or mmCIF .cif/.mmcif, optionally .gz), "
                                    "weighted points (.cin: x y z r²) or .xyzr (x y z r)")
      ->required();
  app->add_option("-o,--out", a->out, "Output .qxm file")->required()->check(qxm_output());
  add_encoding_option(*app, a->write);
  app->add_option("--shrink", a->shrink, "Skin shrink factor s in (0, 1) (default 0.5)")
      ->check(number({.lo = 0, .hi = 1, .open_lo = true, .open_hi = true}));
  app->add_option("--radii", a->radii, "Atom radii of a molecule: vdw (default), covalent or unit")
      ->check(CLI::IsMember({"vdw", "covalent", "unit"}));
  app->add_option("--radius-scale", a->radius_scale, "Multiply every radius by this factor (default 1)")
      ->check(positive());
  app->add_flag("--no-water", a->no_water, "Molecule: leave out water molecules (residues HOH, WAT, DOD, H2O)");
  app->add_option("--tetrahedra", a->tetrahedra,
                  "Mixed cells and their tetrahedra: regular (our mixed complex over CGAL's regular "
                  "triangulation, each cell split directly; default), cgal (CGAL Skin_surface_3's triangulated "
                  "mixed complex as is) or tetgen (CGAL's cells re-tetrahedralised by TetGen)")
      ->check(CLI::IsMember({"regular", "tetgen", "cgal"}));
  commands.push_back({app, [a](const CommonOptions& common, Report& report) {
                        const double t0 = report.elapsed();
                        const auto balls = read_balls(
                            a->input, {.radii = parse_radius_table(a->radii), .radius_scale = a->radius_scale, .water = !a->no_water});
                        const double read_seconds = report.elapsed() - t0;
                        SkinOptions o;
                        o.shrink = a->shrink;
                        o.tetrahedra = a->tetrahedra == "cgal"      ? SkinTetrahedra::cgal
                                       : a->tetrahedra == "tetgen" ? SkinTetrahedra::tetgen
                                                                   : SkinTetrahedra::regular;
                        o.source = a->input;
                        const double t1 = report.elapsed();
                        std::optional<Progress> progress(std::in_place, "skin", progress_allowed(common), Progress::Indeterminate{});
                        SkinConversion conv = convert_skin(balls, o);
                        progress.reset();
                        const double seconds = report.elapsed() - t1;
                        auto& meta = conv.model.metadata;
                        meta["producer"] = command_line();
                        meta["source"] = a->input;
                        meta[kClosedKey] = "1";  // a skin bounds the union of its balls: cull exactly
                        meta["balls"] = fmt::format("{}", balls.size());
                        meta["shrink"] = fmt::format("{:g}", a->shrink);
                        meta["mixed_cells"] = fmt::format("{}", conv.mixed_cells);
                        meta["mixed_cells_crossed"] = fmt::format("{}", conv.mixed_cells_crossed);
                        meta["tetrahedra"] = a->tetrahedra;
                        if (o.tetrahedra != SkinTetrahedra::regular)  // checked against CGAL's value()
                          meta["quadric_disagreement"] = fmt::format("{:.3g}", conv.max_quadric_disagreement);
                        write_model(conv.model, a->out, a->write);
                        report.json["convert"] = {{"kind", "skin"},
                                                  {"input", a->input},
                                                  {"out", a->out},
                                                  {"balls", balls.size()},
                                                  {"shrink", a->shrink},
                                                  {"tetrahedra", a->tetrahedra},
                                                  {"mixed_cells", conv.mixed_cells},
                                                  {"mixed_cells_crossed", conv.mixed_cells_crossed},
                                                  {"bbox_tets_skipped", conv.bbox_cells_skipped},
                                                  {"cgal_tets", conv.cgal_tets},
                                                  {"cgal_tets_crossed", conv.cgal_tets_crossed},
                                                  {"tetgen_tets", conv.tetgen_tets},
                                                  {"mixed_tets", conv.mixed_tets},
                                                  {"hidden_balls", conv.hidden_balls},
                                                  {"triangulation_seconds", conv.triangulation_seconds},
                                                  {"tets_clipped_to_box", conv.tets_clipped_to_box},
                                                  {"slivers_skipped", conv.slivers_skipped},
                                                  {"tetgen_failed_cells", conv.tetgen_failed_cells},
                                                  {"tets", conv.model.tets.size()},
                                                  {"max_quadric_disagreement", conv.max_quadric_disagreement},
                                                  {"read_seconds", read_seconds},
                                                  {"cgal_seconds", conv.cgal_seconds},
                                                  {"tetgen_seconds", conv.tetgen_seconds},
                                                  {"convert_seconds", seconds}};
                        report.summary = fmt::format("wrote {}: {} tet patches from {} balls ({} of {} mixed cells crossed) ({:.3f} s converting)",
                                  a->out, conv.model.tets.size(), balls.size(), conv.mixed_cells_crossed,
                                  conv.mixed_cells, seconds);
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
