#include "convert/molecule_glyphs.h"

#include <functional>
#include <map>

#include <fmt/format.h>

#include "convert/balls.h"
#include "core/error.h"

namespace quadrix {
namespace {

// Chain and residue colours: a qualitative palette (Okabe–Ito, then Tableau).
constexpr Rgb kPalette[] = {{230, 159, 0},  {86, 180, 233}, {0, 158, 115},   {240, 228, 66}, {0, 114, 178},
                            {213, 94, 0},   {204, 121, 167}, {78, 121, 167}, {242, 142, 43}, {225, 87, 89},
                            {118, 183, 178}, {89, 161, 79},  {237, 201, 72}, {176, 122, 161}, {255, 157, 167},
                            {156, 117, 95}};
constexpr std::size_t kPaletteSize = std::size(kPalette);

}  // namespace

MoleculeStyle parse_molecule_style(std::string_view s) {
  if (s == "spacefill") return MoleculeStyle::spacefill;
  if (s == "balls-sticks") return MoleculeStyle::balls_sticks;
  if (s == "licorice") return MoleculeStyle::licorice;
  throw InvalidInput(fmt::format("unknown molecule style '{}' (spacefill, balls-sticks, licorice)", s));
}

ColourBy parse_colour_by(std::string_view s) {
  if (s == "element") return ColourBy::element;
  if (s == "chain") return ColourBy::chain;
  if (s == "residue") return ColourBy::residue;
  throw InvalidInput(fmt::format("unknown colouring '{}' (element, chain, residue)", s));
}

MoleculeStyle default_molecule_style(std::size_t atoms) {
  return atoms < 20000 ? MoleculeStyle::balls_sticks : MoleculeStyle::spacefill;
}

MoleculeGlyphs molecule_glyphs(const Molecule& mol, const MoleculeGlyphOptions& o) {
  if (!(o.ball_scale > 0) || !(o.stick_radius > 0) || !(o.licorice_radius > 0))
    throw InvalidInput("molecule glyphs: ball scale and stick radii must be > 0");
  MoleculeGlyphs out;
  Model& m = out.model;
  // Colours: chains in order of appearance; residues by name (the same residue type, the same
  // colour, as VMD's ResName).
  std::map<std::string, std::size_t> chains;
  std::vector<Rgb> colour(mol.atoms.size());
  for (std::size_t i = 0; i < mol.atoms.size(); ++i) {
    const Atom& a = mol.atoms[i];
    switch (o.colour_by) {
      case ColourBy::element: colour[i] = cpk_colour(a.element); break;
      case ColourBy::chain: {
        const auto it = chains.emplace(a.chain, chains.size()).first;
        colour[i] = kPalette[it->second % kPaletteSize];
        break;
      }
      case ColourBy::residue: colour[i] = kPalette[std::hash<std::string>{}(a.residue) % kPaletteSize]; break;
    }
  }
  const bool sticks = o.style != MoleculeStyle::spacefill;
  m.glyphs.reserve(mol.atoms.size());
  for (std::size_t i = 0; i < mol.atoms.size(); ++i) {
    const Atom& a = mol.atoms[i];
    const double vdw = element_radius(a.element, RadiusTable::vdw);
    const double r = o.style == MoleculeStyle::spacefill      ? vdw
                     : o.style == MoleculeStyle::balls_sticks ? o.ball_scale * vdw
                                                              : o.licorice_radius;
    m.glyphs.push_back({GlyphKind::sphere, a.position, r, Eigen::Matrix3d::Identity(), colour[i]});
  }
  if (sticks) {
    const std::vector<Bond> bonds = molecule_bonds(mol, o.bonds);
    out.bonds = bonds.size();
    out.file_bonds = mol.file_bonds.size();
    const double r = o.style == MoleculeStyle::balls_sticks ? o.stick_radius : o.licorice_radius;
    m.glyphs.reserve(m.glyphs.size() + 2 * bonds.size());
    for (const auto& [i, j] : bonds) {
      const Eigen::Vector3d p = mol.atoms[i].position, q = mol.atoms[j].position, mid = 0.5 * (p + q);
      for (const auto& [end, c] : {std::pair{p, colour[i]}, std::pair{q, colour[j]}}) {
        Eigen::Matrix3d axes = Eigen::Matrix3d::Zero();
        axes.col(0) = 0.5 * (mid - end);
        m.glyphs.push_back({GlyphKind::cylinder, 0.5 * (end + mid), r, axes, c});
      }
    }
  }
  const char* style = o.style == MoleculeStyle::spacefill ? "spacefill"
                      : o.style == MoleculeStyle::balls_sticks ? "balls-sticks" : "licorice";
  const char* by = o.colour_by == ColourBy::element ? "element" : o.colour_by == ColourBy::chain ? "chain" : "residue";
  m.metadata["units"] = "angstrom";
  m.metadata["molecule"] = mol.name;
  m.metadata["style"] = style;
  m.metadata["colour_by"] = by;
  m.metadata["atoms"] = fmt::format("{}", mol.atoms.size());
  m.metadata["bonds"] = fmt::format("{}", out.bonds);
  return out;
}

Model read_molecule_glyphs(const std::filesystem::path& path, std::optional<MoleculeStyle> style, ColourBy colour_by) {
  const Molecule mol = read_molecule(path);
  return molecule_glyphs(mol, {.style = style.value_or(default_molecule_style(mol.atoms.size())), .colour_by = colour_by})
      .model;
}

}  // namespace quadrix
