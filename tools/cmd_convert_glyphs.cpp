// quadrix convert glyphs MOLECULE -o FILE: a PDB/mmCIF molecule as sphere and cylinder glyphs
// ([Sigg06], [Toledo04]); or --ellipsoids FILE.csv, a table of ellipsoid glyphs. Registered under
// the `convert` group by add_convert_glyphs.
#include <optional>

#include <fmt/format.h>

#include "convert/ellipsoids_csv.h"
#include "convert/molecule.h"
#include "convert/molecule_glyphs.h"
#include "core/error.h"
#include "core/log.h"
#include "core/model_io.h"
#include "tools/cli.h"

namespace quadrix::cli {

void add_convert_glyphs(CLI::App& convert, Commands& commands) {
  auto* app = convert.add_subcommand("glyphs", "Molecule (.pdb, .cif, optionally .gz) to sphere and cylinder glyphs");
  struct Args {
    WriteModelOptions write;  // --encoding
    std::string input, ellipsoids, out, style = "balls-sticks", colour_by = "element";
    bool no_water = false;
  };
  auto a = std::make_shared<Args>();
  // No CLI::ExistingFile check: a missing input is the readers' IoError (exit 5), as in every command.
  auto* molecule = app->add_option("MOLECULE", a->input, "PDB (.pdb, .ent) or mmCIF (.cif, .mmcif), optionally gzipped");
  auto* ellipsoids = app->add_option("--ellipsoids", a->ellipsoids,
                                     "Instead of a molecule: CSV rows cx,cy,cz,a1x,a1y,a1z,a2x,a2y,a2z,a3x,a3y,a3z[,r,g,b]");
  molecule->excludes(ellipsoids);
  ellipsoids->excludes(molecule);
  app->add_option("-o,--out", a->out, "Output .qxm file")->required()->check(qxm_output());
  add_encoding_option(*app, a->write);
  app->add_option("--style", a->style, "spacefill, balls-sticks (default) or licorice")
      ->check(CLI::IsMember({"spacefill", "balls-sticks", "licorice"}));
  app->add_option("--colour-by", a->colour_by, "element (CPK, default), chain or residue")
      ->check(CLI::IsMember({"element", "chain", "residue"}));
  app->add_flag("--no-water", a->no_water, "Leave out water molecules (residues HOH, WAT, DOD, H2O)");
  commands.push_back({app, [a](const CommonOptions& common, Report& report) {
                        const double t0 = report.elapsed();
                        if (!a->ellipsoids.empty()) {
                          Model m = read_ellipsoids_csv(a->ellipsoids);
                          m.metadata["producer"] = command_line();
                          m.metadata["source"] = a->ellipsoids;
                          write_model(m, a->out, a->write);
                          report.json["convert"] = {{"kind", "ellipsoids"}, {"input", a->ellipsoids}, {"out", a->out},
                                                    {"glyphs", m.glyphs.size()}};
                          report.summary = fmt::format("wrote {}: {} ellipsoids", a->out, m.glyphs.size());
                          return kOk;
                        }
                        if (a->input.empty()) throw InvalidInput("convert glyphs: give a MOLECULE file or --ellipsoids FILE.csv");
                        std::optional<Progress> progress(std::in_place, "glyphs", progress_allowed(common), Progress::Indeterminate{});
                        const Molecule mol = read_molecule(a->input, {.water = !a->no_water});
                        const double read_seconds = report.elapsed() - t0;
                        MoleculeGlyphs g = molecule_glyphs(
                            mol, {.style = parse_molecule_style(a->style), .colour_by = parse_colour_by(a->colour_by)});
                        progress.reset();
                        auto& meta = g.model.metadata;
                        meta["producer"] = command_line();
                        meta["source"] = a->input;
                        write_model(g.model, a->out, a->write);
                        report.json["convert"] = {{"kind", "glyphs"},
                                                  {"input", a->input},
                                                  {"out", a->out},
                                                  {"style", a->style},
                                                  {"colour_by", a->colour_by},
                                                  {"atoms", mol.atoms.size()},
                                                  {"bonds", g.bonds},
                                                  {"file_bonds", g.file_bonds},
                                                  {"waters_left_out", mol.waters_left_out},
                                                  {"alternates_left_out", mol.alternates_left_out},
                                                  {"glyphs", g.model.glyphs.size()},
                                                  {"read_seconds", read_seconds},
                                                  {"convert_seconds", report.elapsed() - t0}};
                        report.summary = fmt::format("wrote {}: {} glyphs from {} atoms and {} bonds ({} from the file)", a->out,
                                  g.model.glyphs.size(), mol.atoms.size(), g.bonds, g.file_bonds);
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
