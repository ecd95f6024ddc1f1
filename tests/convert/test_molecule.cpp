// Molecules through gemmi (PDB, mmCIF): atoms, waters, alternate locations, file and inferred
// bonds, glyph styles; `convert glyphs` and `render` of a molecule file on the command line.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <zlib.h>

#include "convert/balls.h"
#include "convert/ellipsoids_csv.h"
#include "convert/molecule.h"
#include "convert/molecule_glyphs.h"
#include "core/error.h"
#include "core/io/file.h"
#include "core/model_io.h"
#include "tests/support.h"

using namespace quadrix;
namespace fs = std::filesystem;
using test_support::TempDir;

namespace {

const fs::path kMolecules = fs::path(QUADRIX_DATASETS) / "molecules";

// Glycine fragment with an alternate location, a water and a zinc linked by LINK.
const char* kPdb =
    "HEADER    TEST\n"
    "ATOM      1  N   GLY A   1       0.000   0.000   0.000  1.00  0.00           N  \n"
    "ATOM      2  CA  GLY A   1       1.458   0.000   0.000  1.00  0.00           C  \n"
    "ATOM      3  C   GLY A   1       2.009   1.420   0.000  1.00  0.00           C  \n"
    "ATOM      4  O  AGLY A   1       1.251   2.390   0.000  0.60  0.00           O  \n"
    "ATOM      5  O  BGLY A   1       1.351   2.290   0.300  0.40  0.00           O  \n"
    "HETATM    6 ZN    ZN A 101       1.000   4.500   0.000  1.00  0.00          ZN  \n"
    "HETATM    7  O   HOH A 201       8.000   8.000   8.000  1.00  0.00           O  \n"
    "CONECT    6    4\n"
    "END\n";

// The same atoms (first alternate location only) as mmCIF, the zinc link in struct_conn.
const char* kCif =
    "data_TEST\n"
    "loop_\n"
    "_atom_site.group_PDB\n_atom_site.id\n_atom_site.type_symbol\n_atom_site.label_atom_id\n"
    "_atom_site.label_alt_id\n_atom_site.label_comp_id\n_atom_site.label_asym_id\n_atom_site.label_seq_id\n"
    "_atom_site.Cartn_x\n_atom_site.Cartn_y\n_atom_site.Cartn_z\n_atom_site.occupancy\n"
    "_atom_site.B_iso_or_equiv\n_atom_site.auth_seq_id\n_atom_site.auth_asym_id\n_atom_site.pdbx_PDB_model_num\n"
    "ATOM 1 N N . GLY A 1 0.000 0.000 0.000 1.00 0.00 1 A 1\n"
    "ATOM 2 C CA . GLY A 1 1.458 0.000 0.000 1.00 0.00 1 A 1\n"
    "ATOM 3 C C . GLY A 1 2.009 1.420 0.000 1.00 0.00 1 A 1\n"
    "ATOM 4 O O A GLY A 1 1.251 2.390 0.000 0.60 0.00 1 A 1\n"
    "ATOM 5 O O B GLY A 1 1.351 2.290 0.300 0.40 0.00 1 A 1\n"
    "HETATM 6 ZN ZN . ZN B . 1.000 4.500 0.000 1.00 0.00 101 A 1\n"
    "HETATM 7 O O . HOH C . 8.000 8.000 8.000 1.00 0.00 201 A 1\n"
    "loop_\n"
    "_struct_conn.id\n_struct_conn.conn_type_id\n"
    "_struct_conn.ptnr1_label_asym_id\n_struct_conn.ptnr1_label_comp_id\n_struct_conn.ptnr1_label_seq_id\n"
    "_struct_conn.ptnr1_label_atom_id\n_struct_conn.pdbx_ptnr1_label_alt_id\n_struct_conn.ptnr1_auth_asym_id\n"
    "_struct_conn.ptnr1_auth_seq_id\n"
    "_struct_conn.ptnr2_label_asym_id\n_struct_conn.ptnr2_label_comp_id\n_struct_conn.ptnr2_label_seq_id\n"
    "_struct_conn.ptnr2_label_atom_id\n_struct_conn.pdbx_ptnr2_label_alt_id\n_struct_conn.ptnr2_auth_asym_id\n"
    "_struct_conn.ptnr2_auth_seq_id\n"
    "metalc1 metalc B ZN . ZN . A 101 A GLY 1 O A A 1\n";

class Molecules : public TempDir {};

std::set<std::pair<std::string, std::string>> named(const Molecule& m, const std::vector<Bond>& bonds) {
  std::set<std::pair<std::string, std::string>> s;
  for (const auto& [i, j] : bonds) s.insert(std::minmax(m.atoms[i].name, m.atoms[j].name));
  return s;
}

}  // namespace

TEST_F(Molecules, PdbAndMmcifGiveTheSameAtomsAndBonds) {
  const Molecule p = read_molecule(write("t.pdb", kPdb));
  const Molecule c = read_molecule(write("t.cif", kCif));
  for (const Molecule* m : {&p, &c}) {
    ASSERT_EQ(m->atoms.size(), 6u);  // alternate location B left out
    EXPECT_EQ(m->alternates_left_out, 1u);
    EXPECT_EQ(m->atoms[3].name, "O");
    EXPECT_EQ(m->atoms[3].position, Eigen::Vector3d(1.251, 2.390, 0.0));  // the first location, A
    EXPECT_EQ(m->atoms[4].element, "ZN");
    ASSERT_EQ(m->file_bonds.size(), 1u);  // CONECT / struct_conn: the zinc to the oxygen
    EXPECT_EQ(m->file_bonds[0], (Bond{3, 4}));
    // Inferred: N-CA, CA-C, C-O; none to the water, the metal only through the file.
    EXPECT_EQ(named(*m, molecule_bonds(*m)),
              (std::set<std::pair<std::string, std::string>>{{"CA", "N"}, {"C", "CA"}, {"C", "O"}, {"O", "ZN"}}));
  }
  const Molecule dry = read_molecule(write("d.pdb", kPdb), {.water = false});
  EXPECT_EQ(dry.atoms.size(), 5u);
  EXPECT_EQ(dry.waters_left_out, 1u);
}

TEST_F(Molecules, MalformedFilesAreFormatErrors) {
  const std::string bad = std::string(kPdb).replace(std::string(kPdb).find("1.458"), 5, "1.4x8");
  try {
    read_molecule(write("bad.pdb", bad));
    ADD_FAILURE() << "no FormatError";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.pdb:3: x (columns 31-38)"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_molecule(write("empty.pdb", "HEADER nothing\n")), FormatError);
  EXPECT_THROW(read_molecule(write("bad.cif", "data_x\nloop_\n_atom_site.id\n")), FormatError);
  EXPECT_THROW(read_molecule(write("x.xyz", "1 2 3\n")), InvalidInput);
}

// A gzip file promises no size: it inflates to at most 32 times its compressed size (at least
// 1 MiB), checked as it inflates. A PDB file (4-5 times) passes; a bomb (about 1000 times: a
// 40 MiB body of one repeated REMARK line) stops at its bound, naming the file and the limit.
TEST_F(Molecules, GzipFileInflatesToABoundFromItsSize) {
  auto gzip = [&](const std::string& name, const std::string& head, std::size_t pad_bytes) {
    const fs::path p = dir_ / name;
    gzFile f = gzopen(p.string().c_str(), "wb9");
    gzwrite(f, head.data(), static_cast<unsigned>(head.size()));
    const std::string line = "REMARK 999" + std::string(69, ' ') + "\n";
    std::string chunk;
    while (chunk.size() < (1u << 20)) chunk += line;
    for (std::size_t n = 0; n < pad_bytes; n += chunk.size()) gzwrite(f, chunk.data(), static_cast<unsigned>(chunk.size()));
    gzclose(f);
    return p;
  };
  std::ifstream in(kMolecules / "4lfq.pdb", std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(text.size(), 100000u);
  EXPECT_EQ(read_molecule(gzip("4lfq.pdb.gz", text, 0)).atoms.size(), read_molecule(kMolecules / "4lfq.pdb").atoms.size());

  const fs::path bomb = gzip("bomb.pdb.gz", kPdb, std::size_t{40} << 20);
  const auto size = fs::file_size(bomb);
  ASSERT_GT(size * io::kMaxInflateRatio, std::size_t{1} << 20) << "the ratio, not the 1 MiB floor, is the bound";
  const std::string limit = std::to_string(size * io::kMaxInflateRatio);
  try {
    read_molecule(bomb);
    ADD_FAILURE() << "a bomb was read whole";
  } catch (const FormatError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("bomb.pdb.gz: decompresses to more than the " + limit + " bytes allowed for " +
                     std::to_string(size) + " compressed bytes"),
              std::string::npos)
        << m;
    EXPECT_EQ(m.find("header"), std::string::npos) << m;
  }
  const auto r = test_support::run_command(QUADRIX_BINARY, "convert glyphs " + bomb.string() + " -o " +
                                                               (dir_ / "bomb.qxm").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("bomb.pdb.gz"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "bomb.qxm"));
  // The bound itself: the ratio, the floor and the absolute cap.
  EXPECT_EQ(io::inflate_limit(1000).bytes, std::size_t{1} << 20);
  EXPECT_EQ(io::inflate_limit(1 << 20).bytes, std::size_t{32} << 20);
  EXPECT_EQ(io::inflate_limit(std::uint64_t{1} << 40).bytes, io::kMaxInflated);
}

// Found by fuzzing (gemmi 0.5.7 reads columns 74-78 of any SSBOND/LINK record longer than 73 and
// runs past a shorter last line; a NUL cut its copy of a line): short records are padded, NUL refused.
TEST_F(Molecules, ShortLinkRecordsAndNulBytes) {
  std::string text(kPdb);
  text.erase(text.find("END\n"));
  for (const char* end : {"n", "12", "inf"}) {  // the last line, no newline: 74 to 76 columns
    const std::string link = "LINK" + std::string(69, ' ') + end;
    const Molecule m = read_molecule(write("link.pdb", text + link));
    EXPECT_EQ(m.atoms.size(), 6u) << end;
    EXPECT_EQ(read_molecule(write("link-crlf.pdb", text + link + "\r\nEND\r\n")).atoms.size(), 6u) << end;
  }
  std::string nul = text;
  nul[nul.find("1.458") + 1] = '\0';
  try {
    read_molecule(write("nul.pdb", nul));
    ADD_FAILURE() << "no FormatError";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("nul.pdb:3:35: a NUL byte"), std::string::npos) << e.what();
  }
}

TEST_F(Molecules, GridBondsEqualAllPairsOn1tii) {
  const fs::path path = kMolecules / "1tii.pdb";
  if (!fs::exists(path)) GTEST_SKIP() << "dataset missing: " << path;
  Molecule m = read_molecule(path);
  EXPECT_GT(m.atoms.size(), 5500u);
  const auto grid = molecule_bonds(m);
  // All pairs, the same rule, O(n²): the grid must find exactly these.
  std::vector<Bond> brute = m.file_bonds;
  const BondOptions o;
  const auto water = [](const Atom& a) { return a.residue == "HOH"; };
  for (std::uint32_t i = 0; i < m.atoms.size(); ++i)
    for (std::uint32_t j = i + 1; j < m.atoms.size(); ++j) {
      const Atom &a = m.atoms[i], &b = m.atoms[j];
      if (m.has_conect[i] && m.has_conect[j] && a.residue_number == b.residue_number && a.chain == b.chain) continue;
      const double d = (a.position - b.position).norm();
      const double r = element_radius(a.element, RadiusTable::covalent) + element_radius(b.element, RadiusTable::covalent);
      if (d < o.min_distance || d >= r + o.tolerance) continue;
      if (water(a) && water(b) && (a.residue_number != b.residue_number || a.chain != b.chain)) continue;
      if (a.element == "ZN" || b.element == "ZN" || a.element == "CA" || b.element == "CA" || a.element == "NA" ||
          b.element == "NA" || a.element == "MG" || b.element == "MG")
        continue;
      brute.push_back({i, j});
    }
  std::sort(brute.begin(), brute.end());
  brute.erase(std::unique(brute.begin(), brute.end()), brute.end());
  EXPECT_EQ(grid, brute);
  // A protein has about as many bonds as atoms (chains, rings; waters have none).
  EXPECT_GT(grid.size(), 0.9 * (m.atoms.size() - 200));
  EXPECT_LT(grid.size(), 1.2 * m.atoms.size());
}

TEST_F(Molecules, StylesAndColours) {
  const Molecule m = read_molecule(write("t.pdb", kPdb));
  const auto space = molecule_glyphs(m, {.style = MoleculeStyle::spacefill});
  EXPECT_EQ(space.model.glyphs.size(), m.atoms.size());
  EXPECT_DOUBLE_EQ(space.model.glyphs[0].radius, 1.55);                    // nitrogen, van der Waals
  EXPECT_EQ(space.model.glyphs[0].colour, (std::optional<Rgb>(Rgb{48, 80, 248})));  // CPK blue
  const auto bs = molecule_glyphs(m, {.style = MoleculeStyle::balls_sticks});
  EXPECT_EQ(bs.bonds, 4u);
  ASSERT_EQ(bs.model.glyphs.size(), m.atoms.size() + 2 * bs.bonds);
  EXPECT_DOUBLE_EQ(bs.model.glyphs[0].radius, 0.25 * 1.55);
  // The two halves of N-CA meet at the midpoint, each in its atom's colour.
  const Glyph& half = bs.model.glyphs[m.atoms.size()];
  EXPECT_EQ(half.kind, GlyphKind::cylinder);
  EXPECT_NEAR((half.centre + half.axes.col(0) - Eigen::Vector3d(0.729, 0, 0)).norm(), 0.0, 1e-12);
  const auto chains = molecule_glyphs(m, {.style = MoleculeStyle::licorice, .colour_by = ColourBy::chain});
  EXPECT_EQ(chains.model.glyphs[0].colour, chains.model.glyphs[4].colour);  // one chain, one colour
  EXPECT_EQ(default_molecule_style(19999), MoleculeStyle::balls_sticks);
  EXPECT_EQ(default_molecule_style(20000), MoleculeStyle::spacefill);
  EXPECT_THROW(parse_molecule_style("cartoon"), InvalidInput);
}

TEST_F(Molecules, ConvertGlyphsAndRenderAMoleculeFileOnTheCommandLine) {
  const fs::path pdb = write("t.pdb", kPdb), out = dir_ / "t.qxm", png = dir_ / "t.png";
  auto r = test_support::run_command(QUADRIX_BINARY, "convert glyphs " + pdb.string() + " --style licorice --no-water -o " +
                                                         out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const Model m = read_model(out);
  EXPECT_EQ(m.glyphs.size(), 5u + 2 * 4u);
  EXPECT_EQ(m.metadata.at("style"), "licorice");
  r = test_support::run_command(QUADRIX_BINARY, "render --backend cpu " + pdb.string() + " -o " + png.string() + " --size 64x48");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(png));
  r = test_support::run_command(QUADRIX_BINARY, "convert glyphs " + pdb.string() + " --style cartoon -o " + out.string());
  EXPECT_NE(r.code, 0);
}

TEST_F(Molecules, EllipsoidsFromCsv) {
  const Model m = read_ellipsoids_csv(write("e.csv",
                                            "cx,cy,cz,a1x,a1y,a1z,a2x,a2y,a2z,a3x,a3y,a3z,r,g,b\n"
                                            "1,2,3, 2,0,0, 0,1,0, 0,0,0.5, 255,0,10\n"
                                            "# a comment\n"
                                            "0,0,0, 1,1,0, -1,1,0, 0,0,1\n"));
  ASSERT_EQ(m.glyphs.size(), 2u);
  EXPECT_EQ(m.glyphs[0].kind, GlyphKind::ellipsoid);
  EXPECT_EQ(m.glyphs[0].centre, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(m.glyphs[0].axes.col(2), Eigen::Vector3d(0, 0, 0.5));
  EXPECT_EQ(m.glyphs[0].colour, (std::optional<Rgb>(Rgb{255, 0, 10})));
  EXPECT_FALSE(m.glyphs[1].colour);
  const auto expect_format = [&](const std::string& text, const std::string& needle) {
    try {
      read_ellipsoids_csv(write("bad.csv", text));
      ADD_FAILURE() << "no FormatError for " << text;
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expect_format("0,0,0, 1,0,0, 0,1,0\n", "bad.csv:1:");
  expect_format("0,0,0, 1,0,0, 0,1,0, 0,0,x\n", "'x' is not a finite number");
  expect_format("0,0,0, 1,0,0, 2,0,0, 0,0,1\n", "singular");
  expect_format("0,0,0, 1,0,0, 0,1,0, 0,0,1, 256,0,0\n", "0..255");
  // A first row with a typo is data, not a header (it was skipped as one, silently).
  expect_format("O,0,0, 1,0,0, 0,1,0, 0,0,1\n1,0,0, 1,0,0, 0,1,0, 0,0,1\n", "bad.csv:1:1: ellipsoid 1 value 1: 'O'");
  // Empty cells would shift the columns after them: refused where they are.
  expect_format("0,0,0, 1,0,0, 0,,0, 1,0,0,1\n", "bad.csv:1:17: empty cell");
  expect_format("0,0,0, 1,0,0, 0,1,0, 0,0,1,\n", "bad.csv:1:28: empty cell");
  expect_format("# a header comment, with commas,,\n0,0,0, 1,0,0, 0,1,0, 0,0,1\n,1,0,0, 1,0,0, 0,1,0, 0,0,1\n",
                "bad.csv:3:1: empty cell");
  // Rows are counted from 1.
  expect_format("cx,cy,cz,a,b,c,d,e,f,g,h,i\n0,0,0, 1,0,0, 0,1,0, 0,0,1\n0,0,0, 1,0,0, 0,1,0, 0,0,y\n",
                "bad.csv:3:26: ellipsoid 2 value 12: 'y'");
  const fs::path out = dir_ / "e.qxm";
  const auto r = test_support::run_command(QUADRIX_BINARY, "convert glyphs --ellipsoids " + (dir_ / "e.csv").string() +
                                                               " -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(read_model(out).glyphs.size(), 2u);
}
