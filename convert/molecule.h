#pragma once
/// Molecules read from PDB and mmCIF (through gemmi): the atoms of the first model, first
/// alternate location only, and the bonds the file states; bonds inferred from covalent radii.
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

struct Atom {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< Å
  std::string element;  ///< upper-case symbol ("C", "FE"); "X" when unknown
  std::string name;     ///< atom name ("CA")
  std::string residue;  ///< residue name ("GLY", "HOH")
  std::string chain;    ///< chain name (auth_asym_id)
  int residue_number = 0;
  int serial = 0;       ///< the file's atom serial number (0 when absent)
};

using Bond = std::array<std::uint32_t, 2>;  ///< atom indices, first < second

struct Molecule {
  std::string name;          ///< the entry id, else the file's stem
  std::vector<Atom> atoms;   ///< in file order
  /// Bonds the file states: CONECT (PDB), LINK/SSBOND (PDB) and struct_conn (mmCIF) covalent,
  /// disulfide and metal links. Hydrogen bonds are not bonds here.
  std::vector<Bond> file_bonds;
  /// Per atom: a CONECT record lists it (its bonds within its residue are the file's).
  std::vector<std::uint8_t> has_conect;
  std::size_t waters_left_out = 0;      ///< atoms of water residues skipped (MoleculeReadOptions)
  std::size_t alternates_left_out = 0;  ///< atoms of second and later alternate locations
};

struct MoleculeReadOptions {
  bool water = true;  ///< keep water molecules (residues HOH, WAT, DOD, H2O)
};

/// True for the extensions read_molecule reads: .pdb, .ent, .cif, .mmcif, each optionally .gz.
bool is_molecule_file(const std::filesystem::path& path);

/// Reads a PDB or mmCIF file (optionally gzipped): the first model; of alternate locations the
/// first (as PyMOL and VMD show by default). PDB coordinate columns are checked strictly (gemmi
/// reads "42.7x4" as 42.7).
/// \throws FormatError naming the file (and line, for PDB) for a malformed record, no atoms or a
///         non-finite coordinate; IoError when unreadable; InvalidInput for another extension.
Molecule read_molecule(const std::filesystem::path& path, const MoleculeReadOptions& options = {});

struct BondOptions {
  double tolerance = 0.45;     ///< Å: bonded when d < r₁ + r₂ + tolerance (covalent radii)
  double min_distance = 0.4;   ///< Å: closer pairs are clashes, not bonds
};

/// The file's bonds, plus bonds inferred from covalent radii (Cordero et al. 2008) on a uniform
/// grid (expected O(n)): not within a residue whose CONECT records list both atoms (a ligand the
/// file describes), not between two waters, not to metals (coordination comes from the file).
/// Sorted, unique.
std::vector<Bond> molecule_bonds(const Molecule& molecule, const BondOptions& options = {});

}  // namespace quadrix
