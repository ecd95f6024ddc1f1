#pragma once
/// Molecules as glyphs ([Sigg06], [Toledo04]): space-filling spheres, balls and sticks, or
/// licorice; atoms coloured by element (CPK), chain or residue.
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string_view>

#include "convert/molecule.h"
#include "core/model.h"

namespace quadrix {

enum class MoleculeStyle { spacefill, balls_sticks, licorice };
enum class ColourBy { element, chain, residue };

/// Parse "spacefill" | "balls-sticks" | "licorice" and "element" | "chain" | "residue".
/// \throws InvalidInput naming the value and the choices.
MoleculeStyle parse_molecule_style(std::string_view name);
ColourBy parse_colour_by(std::string_view name);

/// The style `quadrix render` and `view` pick for a molecule file: balls and sticks below
/// 20,000 atoms, space filling from there on.
MoleculeStyle default_molecule_style(std::size_t atoms);

struct MoleculeGlyphOptions {
  MoleculeStyle style = MoleculeStyle::balls_sticks;
  ColourBy colour_by = ColourBy::element;
  double ball_scale = 0.25;     ///< balls-sticks: ball radius = ball_scale · van der Waals radius
  double stick_radius = 0.15;   ///< Å, balls-sticks sticks
  double licorice_radius = 0.3; ///< Å, licorice sticks and the spheres that round their joints
  BondOptions bonds{};          ///< bond inference
};

struct MoleculeGlyphs {
  Model model;  ///< spheres (atoms), then cylinders (half bonds, each in its atom's colour)
  std::size_t bonds = 0, file_bonds = 0;
};

/// Spheres per atom (space filling: van der Waals radii, Bondi 1964) and, with sticks, two
/// cylinders per bond (one half in each atom's colour); metadata names the style and counts.
MoleculeGlyphs molecule_glyphs(const Molecule& molecule, const MoleculeGlyphOptions& options = {});

/// A molecule file (is_molecule_file) as glyphs: what `render` and `view` draw when given one.
/// style: default_molecule_style of the atom count when unset.
/// \throws as read_molecule.
Model read_molecule_glyphs(const std::filesystem::path& path, std::optional<MoleculeStyle> style = std::nullopt,
                           ColourBy colour_by = ColourBy::element);

}  // namespace quadrix
