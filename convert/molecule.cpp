// Bonds of a molecule: the file's, and those inferred from covalent radii on a uniform grid.
#include "convert/molecule.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "convert/balls.h"

namespace quadrix {
namespace {

bool is_metal(std::string_view e) {
  static constexpr std::string_view kMetals[] = {"LI", "NA", "K",  "MG", "CA", "MN", "FE", "CO", "NI", "CU",
                                                 "ZN", "CD", "HG", "PT", "AU", "AG", "SR", "BA", "CS", "RB",
                                                 "AL", "GA", "MO", "W",  "V",  "CR", "PB", "TL", "YB", "SM"};
  return std::find(std::begin(kMetals), std::end(kMetals), e) != std::end(kMetals);
}

bool is_water(std::string_view residue) {
  return residue == "HOH" || residue == "WAT" || residue == "DOD" || residue == "H2O";
}

}  // namespace

std::vector<Bond> molecule_bonds(const Molecule& m, const BondOptions& o) {
  std::vector<Bond> bonds = m.file_bonds;
  const std::size_t n = m.atoms.size();
  std::vector<double> radius(n);
  double max_r = 0;
  for (std::size_t i = 0; i < n; ++i) {
    radius[i] = element_radius(m.atoms[i].element, RadiusTable::covalent);
    max_r = std::max(max_r, radius[i]);
  }
  // Cells as wide as the longest possible bond: a bond's partner lies in the 27 cells around.
  const double cell = 2 * max_r + o.tolerance;
  struct Key {
    std::int64_t x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct Hash {
    std::size_t operator()(const Key& k) const {
      return std::size_t(k.x * 73856093) ^ std::size_t(k.y * 19349663) ^ std::size_t(k.z * 83492791);
    }
  };
  const auto key = [&](const Eigen::Vector3d& p) {
    return Key{std::int64_t(std::floor(p.x() / cell)), std::int64_t(std::floor(p.y() / cell)),
               std::int64_t(std::floor(p.z() / cell))};
  };
  std::unordered_map<Key, std::vector<std::uint32_t>, Hash> grid;
  grid.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i) grid[key(m.atoms[i].position)].push_back(i);
  const auto conect = [&](std::uint32_t i) { return !m.has_conect.empty() && m.has_conect[i]; };
  for (const auto& [k, atoms] : grid)
    for (const std::uint32_t i : atoms) {
      const Atom& a = m.atoms[i];
      for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy)
          for (std::int64_t dz = -1; dz <= 1; ++dz) {
            const auto it = grid.find(Key{k.x + dx, k.y + dy, k.z + dz});
            if (it == grid.end()) continue;
            for (const std::uint32_t j : it->second) {
              if (j <= i) continue;
              const Atom& b = m.atoms[j];
              const double d = (a.position - b.position).norm();
              if (d < o.min_distance || d >= radius[i] + radius[j] + o.tolerance) continue;
              if (is_water(a.residue) && is_water(b.residue) &&
                  (a.residue_number != b.residue_number || a.chain != b.chain))
                continue;
              if (is_metal(a.element) || is_metal(b.element)) continue;  // coordination: from the file
              // Within a residue whose CONECT records list both atoms, the file's bonds alone.
              if (conect(i) && conect(j) && a.residue_number == b.residue_number && a.chain == b.chain) continue;
              bonds.push_back({i, j});
            }
          }
    }
  std::sort(bonds.begin(), bonds.end());
  bonds.erase(std::unique(bonds.begin(), bonds.end()), bonds.end());
  return bonds;
}

}  // namespace quadrix
