// `quadrix tetrahedralize` (TetGen on a closed mesh, a per-vertex field beside it) and the
// `--encoding` option of the commands that write models.
#include <gtest/gtest.h>

#include "tests/support.h"
#include "tests/tools/cli_support.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "convert/tetmesh_io.h"
#include "core/model_io.h"

using namespace quadrix;
using test_support::CmdResult;
using test_support::q;
using test_support::quadrix_run;
using test_support::read_json;

namespace {

/// The cube [−h, h]³ as an OFF file of 6 outward quads; drop removes faces (by index), flip
/// reverses one face's winding (−1: none).
std::string cube_off(double h, std::vector<int> drop = {}, int flip = -1) {
  const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3}};
  std::ostringstream s;
  s << "OFF\n8 " << 6 - drop.size() << " 0\n";
  const double v[8][3] = {{-h, -h, -h}, {h, -h, -h}, {h, h, -h}, {-h, h, -h},
                          {-h, -h, h},  {h, -h, h},  {h, h, h},  {-h, h, h}};
  for (const auto& p : v) s << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
  for (int f = 0; f < 6; ++f) {
    if (std::find(drop.begin(), drop.end(), f) != drop.end()) continue;
    s << 4;
    if (f == flip)
      for (int k = 3; k >= 0; --k) s << ' ' << faces[f][k];
    else
      for (int k = 0; k < 4; ++k) s << ' ' << faces[f][k];
    s << '\n';
  }
  return s.str();
}

std::vector<double> read_values(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::vector<double> v;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') v.push_back(std::stod(line));
  return v;
}
}  // namespace

class CliTetrahedralize : public test_support::TempDir {};

TEST_F(CliTetrahedralize, ClosedCubeGivesADistanceFieldWhoseIsoSurfaceIsTheInnerCube) {
  const auto cube = write("cube.off", cube_off(1.0));
  const auto solid = dir_ / "solid.mesh", report = dir_ / "r.json";
  const CmdResult r = quadrix_run("tetrahedralize " + q(cube) + " -o " + q(solid) +
                                  " --quality 1.5 --max-volume 0.004 -v --report " + q(report));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("tetrahedra"), std::string::npos) << "no summary line: " << r.out;
  const TetMesh mesh = read_tet_mesh(solid);
  const std::vector<double> values = read_values(dir_ / "solid.values");
  ASSERT_EQ(values.size(), mesh.vertices.size());
  const auto j = read_json(report)["tetrahedralize"];
  EXPECT_EQ(j["tets"].get<std::size_t>(), mesh.tets.size());
  EXPECT_GT(mesh.tets.size(), 500u);  // --max-volume 0.004 over a volume of 8
  // The tetrahedra fill the cube: their volumes sum to 8.
  double volume = 0;
  for (const auto& t : mesh.tets) {
    const auto& p = mesh.vertices;
    volume += std::abs((p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).dot(p[t[3]] - p[t[0]])) / 6;
  }
  EXPECT_NEAR(volume, 8.0, 1e-9);
  // The field is the distance to the boundary: 1 − max |coordinate| inside a cube of half-side 1.
  for (std::size_t i = 0; i < values.size(); ++i)
    ASSERT_NEAR(values[i], 1.0 - mesh.vertices[i].cwiseAbs().maxCoeff(), 1e-12) << "vertex " << i;
  for (int i = 0; i < 8; ++i) EXPECT_EQ(values[i], 0.0);  // the input vertices come first
  // convert volume --tets turns it into iso-surface patches: the inner cube [−½, ½]³.
  const auto model = dir_ / "inner.qxm";
  const CmdResult c = quadrix_run("convert volume --tets " + q(solid) + " --values " + q(dir_ / "solid.values") +
                                  " --iso 0.5 -o " + q(model));
  ASSERT_EQ(c.code, 0) << c.out;
  const Model m = read_model(model);
  ASSERT_GT(m.tets.size(), 50u);
  const Box3 box = bounds(m);
  // The patches' tetrahedra straddle the iso-surface: their box holds the inner cube and stays
  // a tetrahedron's size (edges ≲ 0.35 at this volume bound) short of the boundary at ±1.
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(box.min[a], -0.49) << a;
    EXPECT_GE(box.min[a], -0.9) << a;
    EXPECT_GE(box.max[a], 0.49) << a;
    EXPECT_LE(box.max[a], 0.9) << a;
  }
}

// With the defaults the inside has vertices (the largest tetrahedron a 4096th of the enclosed
// volume): TetGen alone fills a cube with 6 tetrahedra on its 8 corners, whose distance field was
// 0 everywhere, and `convert volume --tets` then found no iso value ("constant data").
TEST_F(CliTetrahedralize, DefaultsGiveTheInsideVerticesSoTheFieldHasAnIsoSurface) {
  const auto cube = write("cube.off", cube_off(1.0));
  const auto solid = dir_ / "solid.mesh";
  const CmdResult r = quadrix_run("tetrahedralize " + q(cube) + " -o " + q(solid));
  ASSERT_EQ(r.code, 0) << r.out;
  const TetMesh mesh = read_tet_mesh(solid);
  EXPECT_GE(mesh.tets.size(), 4096u);
  const std::vector<double> values = read_values(dir_ / "solid.values");
  ASSERT_EQ(values.size(), mesh.vertices.size());
  EXPECT_GT(*std::max_element(values.begin(), values.end()), 0.5);  // a vertex within ½ of the centre
  // No --iso: the suggested one is used, and the patches lie inside the cube.
  const auto model = dir_ / "inner.qxm";
  const CmdResult c = quadrix_run("convert volume --tets " + q(solid) + " --values " + q(dir_ / "solid.values") +
                                  " -o " + q(model));
  ASSERT_EQ(c.code, 0) << c.out;
  const Model m = read_model(model);
  EXPECT_GT(m.tets.size(), 20u);
  const Box3 box = bounds(m);
  for (int a = 0; a < 3; ++a) {
    EXPECT_GE(box.min[a], -1.0) << a;
    EXPECT_LE(box.max[a], 1.0) << a;
  }
  // --max-volume 0 keeps TetGen's own: no vertex inside.
  ASSERT_EQ(quadrix_run("tetrahedralize " + q(cube) + " -o " + q(solid) + " --max-volume 0 --quality 0").code, 0);
  const std::vector<double> bare = read_values(dir_ / "solid.values");
  EXPECT_EQ(*std::max_element(bare.begin(), bare.end()), 0.0);
}

TEST_F(CliTetrahedralize, OpenOrDegenerateMeshesAreRefusedBeforeTetGenAndMisWoundFacesTurned) {
  const auto out = dir_ / "solid.mesh";
  struct Case {
    std::string name, off, message;
  };
  const std::vector<Case> cases = {
      {"open.off", cube_off(1.0, {1}), "has no face on its other side: the surface is open"},
      {"flat.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0.5 0 0\n3 0 1 2\n3 0 3 1\n3 1 3 2\n3 2 3 0\n", "zero area"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto in = write(c.name, c.off);
    const CmdResult r = quadrix_run("tetrahedralize " + q(in) + " -o " + q(out));
    EXPECT_EQ(r.code, 3) << r.out;
    EXPECT_NE(r.out.find(c.name), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(c.message), std::string::npos) << r.out;
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_FALSE(std::filesystem::exists(dir_ / "solid.values"));
  }
  // A face wound against its neighbours is turned when the mesh is read (with a warning), so
  // TetGen gets a consistent surface.
  {
    const auto in = write("flipped.off", cube_off(1.0, {}, 2));
    const CmdResult r = quadrix_run("tetrahedralize " + q(in) + " -o " + q(out));
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("1 of 6 faces were wound against their neighbours"), std::string::npos) << r.out;
    EXPECT_TRUE(std::filesystem::exists(out));
    std::filesystem::remove(out);
    std::filesystem::remove(dir_ / "solid.values");
  }
  // Usage errors: exit 2.
  const auto cube = write("cube.off", cube_off(1.0));
  EXPECT_EQ(quadrix_run("tetrahedralize " + q(cube) + " -o " + q(dir_ / "s.txt")).code, 2);
  EXPECT_EQ(quadrix_run("tetrahedralize " + q(cube) + " -o " + q(out) + " --field temperature").code, 2);
  EXPECT_EQ(quadrix_run("tetrahedralize " + q(cube) + " -o " + q(out) + " --quality 0.5").code, 2);
}

TEST_F(CliTetrahedralize, VolumeFieldSamplesTheVolumeAtTheVertices) {
  const auto nhdr = dir_ / "ml.nhdr";
  ASSERT_EQ(quadrix_run("synth marschner-lobb --resolution 12 -o " + q(nhdr)).code, 0);
  const auto cube = write("cube.off", cube_off(0.75));
  const auto solid = dir_ / "solid.mesh", values = dir_ / "v.txt";
  const CmdResult r = quadrix_run("tetrahedralize " + q(cube) + " -o " + q(solid) + " --values " + q(values) +
                                  " --field volume " + q(nhdr));
  ASSERT_EQ(r.code, 0) << r.out;
  const TetMesh mesh = read_tet_mesh(solid);
  const std::vector<double> v = read_values(values);
  ASSERT_EQ(v.size(), mesh.vertices.size());
  // Marschner–Lobb lies in [0, 1]; a corner of the grid cell is a sample: the cube's corners
  // (±0.75) sit between samples, so check the range and that the field is not constant.
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  EXPECT_GE(*lo, -1e-6);
  EXPECT_LE(*hi, 1 + 1e-6);
  EXPECT_GT(*hi - *lo, 0.1);
  // A mesh reaching outside the volume: exit 3, naming the vertex.
  const auto big = write("big.off", cube_off(2.0));
  const CmdResult o = quadrix_run("tetrahedralize " + q(big) + " -o " + q(solid) + " --field volume " + q(nhdr));
  EXPECT_EQ(o.code, 3) << o.out;
  EXPECT_NE(o.out.find("lies outside the volume's grid"), std::string::npos) << o.out;
}

class CliEncoding : public test_support::TempDir {};

std::string read_header(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return text.substr(0, text.find("end_header"));
}

TEST_F(CliEncoding, CompactIsTheDefaultAndDoubleIsLossless) {
  for (const char* kind : {"hyperboloid1", "slim-sphere", "glyphs"}) {
    SCOPED_TRACE(kind);
    const auto c = dir_ / "c.qxm", d = dir_ / "d.qxm", def = dir_ / "default.qxm";
    ASSERT_EQ(quadrix_run(std::string("synth ") + kind + " -o " + q(c) + " --encoding compact").code, 0);
    ASSERT_EQ(quadrix_run(std::string("synth ") + kind + " -o " + q(d) + " --encoding double").code, 0);
    ASSERT_EQ(quadrix_run(std::string("synth ") + kind + " -o " + q(def)).code, 0);
    // The default writes the compact encoding (the files differ only in the producer line, the
    // command as typed).
    EXPECT_NE(read_header(def).find("comment quadrix-encoding compact"), std::string::npos);
    EXPECT_NE(read_header(c).find("comment quadrix-encoding compact"), std::string::npos);
    const double ratio = double(std::filesystem::file_size(c)) / double(std::filesystem::file_size(d));
    EXPECT_LT(ratio, 0.6) << std::filesystem::file_size(c) << " vs " << std::filesystem::file_size(d);
    const Model mc = read_model(c), md = read_model(d);
    ASSERT_EQ(mc.size(), md.size());
    const CmdResult info = quadrix_run("info " + q(c));
    EXPECT_EQ(info.code, 0) << info.out;
  }
  // A protein's skin (tetrahedra with per-corner colours), the case: 1tii's is 41.4 MB
  // compact against 76.8 MB in double (0.54); insulin's here, with ../shared.
  const auto insulin = std::filesystem::path(QUADRIX_DATASETS) / "molecules" / "4ins.pdb";
  if (std::filesystem::exists(insulin)) {
    const auto c = dir_ / "skin_c.qxm", d = dir_ / "skin_d.qxm";
    ASSERT_EQ(quadrix_run("convert skin " + q(insulin) + " -o " + q(c) + " -q").code, 0);
    ASSERT_EQ(quadrix_run("convert skin " + q(insulin) + " -o " + q(d) + " --encoding double -q").code, 0);
    const double ratio = double(std::filesystem::file_size(c)) / double(std::filesystem::file_size(d));
    EXPECT_LE(ratio, 0.6) << std::filesystem::file_size(c) << " vs " << std::filesystem::file_size(d);
    EXPECT_GT(read_model(c).tets.size(), 1000u);
  }
  const CmdResult bad = quadrix_run("synth sphere -o " + q(dir_ / "x.qxm") + " --encoding half");
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--encoding"), std::string::npos) << bad.out;
}
