// PDB and mmCIF through gemmi (the only file that includes it: its CIF grammar is heavy to
// compile). CONECT records, which gemmi 0.5.7 skips, and the strict check of PDB coordinate
// columns are read here.
#include <gemmi/gz.hpp>
#include <gemmi/mmread.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <unordered_map>

#include <fmt/format.h>

#include "convert/molecule.h"
#include "core/error.h"
#include "core/io/file.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;

std::string lower_extension(const fs::path& path, fs::path& stem) {
  fs::path p = path;
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".gz") {
    p = p.stem();
    ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  }
  stem = p.stem();
  return ext;
}

std::string trim(std::string_view s) {
  const auto a = s.find_first_not_of(' ');
  if (a == std::string_view::npos) return {};
  return std::string(s.substr(a, s.find_last_not_of(' ') - a + 1));
}

// A fixed-column number of a PDB record, strictly (the whole field, finite).
double pdb_number(std::string_view line, std::size_t first, std::size_t width, const std::string& where,
                  const char* name) {
  const std::string text = trim(line.substr(first, width));
  double v = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || r.ec != std::errc() || r.ptr != text.data() + text.size() || !std::isfinite(v))
    throw FormatError(fmt::format("{}: {} (columns {}-{}) '{}' is not a number", where, name, first + 1,
                                  first + width, io::echo(line.substr(first, width))));
  return v;
}

// PDB text as gemmi 0.5.7's reader can take it without reading past its buffers (found by fuzzing):
// - a NUL byte is refused: gemmi copies each line as a C string, so a NUL cuts it, and the part it
//   skips to reach the end of an overlong line then swallows the next line's first bytes;
// - lines are cut at 120 columns (gemmi reads no further: it skips the rest, but stops skipping at
//   a byte >= 0x80 and reads what follows as a new record);
// - SSBOND, LINK and CISPEP records (gemmi keeps them as strings and reads columns 74-78 of any
//   longer than 73) are padded with blanks to 80 columns, so those reads stay inside the string.
// Neither change alters what a well-formed file (80-column ASCII records) means.
std::string gemmi_safe_pdb(const fs::path& path, std::string_view text) {
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  std::size_t pos = 0;
  int line_no = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    const bool has_newline = end != std::string_view::npos;
    if (!has_newline) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (const auto nul = line.find('\0'); nul != std::string_view::npos)
      throw FormatError(io::text_message(path, line_no, nul + 1, "a NUL byte: not a PDB text file"));
    const bool cr = !line.empty() && line.back() == '\r';
    if (cr) line.remove_suffix(1);
    line = line.substr(0, 120);
    out.append(line);
    // gemmi compares the first four characters with case folded (bit 5 cleared).
    std::string head(line.substr(0, 4));
    for (char& c : head) c = static_cast<char>(c & ~0x20);
    if ((head == "LINK" || head == "SSBO" || head == "CISP") && line.size() < 80) out.append(80 - line.size(), ' ');
    if (cr) out.push_back('\r');
    if (has_newline) out.push_back('\n');
  }
  return out;
}

// PDB text (gunzipped when needed): coordinate columns checked, CONECT pairs by serial.
std::vector<std::pair<int, int>> scan_pdb(const fs::path& path, const std::string& text) {
  std::vector<std::pair<int, int>> conect;
  std::size_t pos = 0;
  int line_no = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.substr(0, 6) == "ENDMDL") break;  // the first model's records only
    const std::string where = fmt::format("{}:{}", path.string(), line_no);
    if (line.substr(0, 6) == "ATOM  " || line.substr(0, 6) == "HETATM") {
      if (line.size() < 54)
        throw FormatError(fmt::format("{}: {} record has {} columns, coordinates need 54", where, line.substr(0, 6),
                                      line.size()));
      pdb_number(line, 30, 8, where, "x");
      pdb_number(line, 38, 8, where, "y");
      pdb_number(line, 46, 8, where, "z");
    } else if (line.substr(0, 6) == "CONECT" && line.size() >= 16) {
      const auto serial = [&](std::size_t first) {
        const std::string t = trim(line.substr(first, std::min<std::size_t>(5, line.size() - first)));
        int v = 0;
        const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
        return t.empty() || r.ec != std::errc() ? -1 : v;
      };
      const int a = serial(6);
      if (a < 0) continue;
      for (std::size_t c = 11; c + 1 <= line.size() && c < 31; c += 5)
        if (const int b = serial(c); b >= 0) conect.emplace_back(a, b);
    }
  }
  return conect;
}

// The whole text through the I/O kit. A gzip file has no header promising its size: it inflates
// to at most io::inflate_limit of its compressed size (PDB text compresses 4–5 times; the
// largest entries are a few hundred MB of text), checked as the bytes arrive.
std::string read_text(const fs::path& path) {
  gemmi::MaybeGzipped input(path.string());
  return input.is_compressed() ? io::read_gzip(path, io::inflate_limit(fs::file_size(path))) : io::read_file(path);
}

}  // namespace

bool is_molecule_file(const fs::path& path) {
  fs::path stem;
  const std::string ext = lower_extension(path, stem);
  return ext == ".pdb" || ext == ".ent" || ext == ".cif" || ext == ".mmcif";
}

Molecule read_molecule(const fs::path& path, const MoleculeReadOptions& o) {
  fs::path stem;
  const std::string ext = lower_extension(path, stem);
  const bool is_pdb = ext == ".pdb" || ext == ".ent";
  if (!is_pdb && ext != ".cif" && ext != ".mmcif")
    throw InvalidInput(fmt::format("'{}': not a molecule file (.pdb, .ent, .cif, .mmcif, optionally .gz)", path.string()));
  io::read_file_prefix(path, 0);  // missing, a folder or unreadable: the kit's IoError naming it (exit 5)
  if (!fs::is_regular_file(path))   // a device or a pipe would be read without end (no size to check)
    throw IoError(fmt::format("{}: not a regular file (a device or a pipe)", path.string()));
  const std::string text = is_pdb ? gemmi_safe_pdb(path, read_text(path)) : read_text(path);
  std::vector<std::pair<int, int>> conect;
  if (is_pdb) conect = scan_pdb(path, text);
  gemmi::Structure st;
  try {
    if (is_pdb) st = gemmi::read_pdb_from_memory(text.data(), text.size(), path.string());
    else st = gemmi::make_structure(gemmi::cif::read_memory(text.data(), text.size(), path.string().c_str()));
  } catch (const std::exception& e) {
    throw FormatError(fmt::format("{}: {}", path.string(), e.what()));
  }
  Molecule m;
  m.name = st.name.empty() ? stem.string() : st.name;
  if (st.models.empty()) throw FormatError(fmt::format("{}: no atoms", path.string()));
  gemmi::Model& model = st.models.front();
  // Alternate locations: of each atom the first location; a residue repeated under the same
  // number with only alternate atoms (micro-heterogeneity) is a second location too. Repeated
  // records without an alternate location stay (read_balls refuses them as duplicates).
  std::unordered_map<const gemmi::Atom*, std::uint32_t> index;
  std::unordered_map<int, std::uint32_t> by_serial;
  for (const auto& ch : model.chains) {
    std::set<std::pair<int, char>> seen_residues;
    for (const auto& r : ch.residues) {
      const bool all_alternate =
          std::all_of(r.atoms.begin(), r.atoms.end(), [](const gemmi::Atom& a) { return a.altloc != '\0'; });
      if (!seen_residues.insert({r.seqid.num.value, r.seqid.icode}).second && all_alternate) {
        m.alternates_left_out += r.atoms.size();
        continue;
      }
      if (!o.water && r.is_water()) {
        m.waters_left_out += r.atoms.size();
        continue;
      }
      std::map<std::string, char> first_location;
      for (const auto& a : r.atoms) {
        if (a.altloc != '\0') {
          const char first = first_location.emplace(a.name, a.altloc).first->second;
          if (a.altloc != first) {
            ++m.alternates_left_out;
            continue;
          }
        }
        Atom x;
        x.position = {a.pos.x, a.pos.y, a.pos.z};
        if (!x.position.allFinite())
          throw FormatError(fmt::format("{}: atom {} ({} {}{} chain {}) has a non-finite coordinate", path.string(),
                                        a.serial, a.name, r.name, r.seqid.num.value, ch.name));
        x.element = a.element.uname();
        x.name = a.name;
        x.residue = r.name;
        x.chain = ch.name;
        x.residue_number = r.seqid.num.value;
        x.serial = a.serial;
        index[&a] = static_cast<std::uint32_t>(m.atoms.size());
        if (a.serial > 0) by_serial.emplace(a.serial, static_cast<std::uint32_t>(m.atoms.size()));
        m.atoms.push_back(std::move(x));
      }
    }
  }
  if (m.atoms.empty()) throw FormatError(fmt::format("{}: no atoms", path.string()));
  m.has_conect.assign(m.atoms.size(), 0);
  const auto add = [&](std::uint32_t a, std::uint32_t b) {
    if (a != b) m.file_bonds.push_back({std::min(a, b), std::max(a, b)});
  };
  for (const auto& [sa, sb] : conect) {
    const auto ia = by_serial.find(sa), ib = by_serial.find(sb);
    if (ia == by_serial.end() || ib == by_serial.end()) continue;  // waters left out, other models
    m.has_conect[ia->second] = m.has_conect[ib->second] = 1;
    add(ia->second, ib->second);
  }
  for (const gemmi::Connection& c : st.connections) {
    if (c.type == gemmi::Connection::Hydrog) continue;
    const gemmi::CRA a = model.find_cra(c.partner1, true), b = model.find_cra(c.partner2, true);
    if (!a.atom || !b.atom) continue;
    const auto ia = index.find(a.atom), ib = index.find(b.atom);
    if (ia != index.end() && ib != index.end()) add(ia->second, ib->second);
  }
  std::sort(m.file_bonds.begin(), m.file_bonds.end());
  m.file_bonds.erase(std::unique(m.file_bonds.begin(), m.file_bonds.end()), m.file_bonds.end());
  return m;
}

}  // namespace quadrix
