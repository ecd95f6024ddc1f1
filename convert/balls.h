#pragma once
/// Ball sets for skin surfaces: the atoms of PDB and mmCIF files (convert/molecule.h) with element
/// radii and CPK colours, CGAL weighted-point files (`.cin`: x y z w, w the squared radius) and
/// `.xyzr` (x y z r). Coordinates in the file's units (Å for molecules).
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "core/model.h"

namespace quadrix {

struct Ball {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 1.0;  ///< > 0
  Rgb colour{200, 200, 200};
  std::string element;  ///< upper-case element symbol ("C", "FE"); empty for .cin/.xyzr
};

/// Radius tables for PDB atoms.
enum class RadiusTable {
  vdw,       ///< van der Waals (Bondi 1964; Rowland–Taylor for H; 1.8 Å for unknown elements)
  covalent,  ///< single-bond covalent radii (Cordero et al. 2008)
  unit,      ///< 1 for every atom
};

/// Parses vdw|covalent|unit. \throws InvalidInput.
RadiusTable parse_radius_table(std::string_view name);

struct BallReadOptions {
  RadiusTable radii = RadiusTable::vdw;  ///< molecules only
  double radius_scale = 1.0;             ///< multiplies every radius (PDB, .cin, .xyzr)
  bool water = true;                     ///< molecules: keep water molecules (residues HOH, WAT, DOD, H2O)
};

/// Radius and CPK colour of an element (upper-case symbol); unknown elements get the table's
/// default radius and pink.
double element_radius(std::string_view element, RadiusTable table);
Rgb cpk_colour(std::string_view element);

/// Reads a molecule (read_molecule: `.pdb`, `.ent`, `.cif`, `.mmcif`, optionally gzipped; first
/// model, first alternate location), `.cin` or `.xyzr` by extension.
/// \throws FormatError naming the file and line for a malformed record (short line, coordinates
///         that are not numbers, a non-finite value), a zero or negative radius or weight, and for
///         duplicate balls (two centres closer than 1e-6 of the set's extent; both lines, or both
///         atoms' serial numbers, named);
///         InvalidInput for an empty set or an unknown extension; IoError when unreadable.
std::vector<Ball> read_balls(const std::filesystem::path& path, const BallReadOptions& options = {});

/// Rejects non-finite or non-positive data and duplicate centres (as read_balls).
/// \throws InvalidInput naming `source` and the ball indices.
void validate_balls(const std::vector<Ball>& balls, std::string_view source);

}  // namespace quadrix
