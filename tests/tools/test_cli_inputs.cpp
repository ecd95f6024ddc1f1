// What `render` and `view` open as MODEL (one loader, tools/scene_input.h: models, molecules,
// meshes), what `info` says a mesh, a point cloud or a molecule is, and the molecule options --style and
// --colour-by element|chain|residue of both commands.
#include <gtest/gtest.h>

#include "tests/support.h"
#include "tests/tools/cli_support.h"

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/image.h"
#include "core/mesh_io.h"
#include "core/model_io.h"

using namespace quadrix;
using test_support::CmdResult;
using test_support::q;
using test_support::quadrix_run;
using test_support::read_json;

namespace {

const char* const kTwoChains = test_support::kTwoChainPdb;

// `view` with no display: it reads its input and frames it, then fails to open the window (exit
// 6). Reaching that failure means the input was read; a file it cannot read exits 3 before it.
CmdResult view_without_display(const std::string& args) {
  return test_support::run_command("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(QUADRIX_BINARY),
                                   "view " + args + " --frames 1 --size 64x48 --quiet");
}

// Share of pixels whose colours differ by more than 2 in some channel.
double differing_share(const Image8& a, const Image8& b) {
  if (a.width != b.width || a.height != b.height) return 1;
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.rgba.size(); i += 4)
    for (int c = 0; c < 3; ++c)
      if (std::abs(int(a.rgba[i + c]) - int(b.rgba[i + c])) > 2) {
        ++differ;
        break;
      }
  return double(differ) / double(a.rgba.size() / 4);
}

}  // namespace

class CliInputs : public test_support::TempDir {};

// A mesh in each format `mesh` writes (binary PLY, OBJ, OFF, binary STL) and a quad OBJ: info
// says it is a mesh, with its counts and bounds, in text and JSON; a point cloud likewise.
TEST_F(CliInputs, InfoSaysWhatAMeshOrAPointCloudIs) {
  const auto model = dir_ / "s.qxm";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  for (const char* ext : {".ply", ".obj", ".off", ".stl"}) {
    SCOPED_TRACE(ext);
    const auto mesh = dir_ / (std::string("s") + ext);
    ASSERT_EQ(quadrix_run("mesh " + q(model) + " -o " + q(mesh) + " --quiet").code, 0);
    CmdResult r = quadrix_run("info " + q(mesh));
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("a triangle mesh"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("bounding box"), std::string::npos) << r.out;
    r = quadrix_run("info --json " + q(mesh));
    ASSERT_EQ(r.code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["kind"], "mesh");
    EXPECT_GT(j["faces"].get<int>(), 100);
    EXPECT_EQ(j["face_sizes"]["triangles"], j["faces"]);
    EXPECT_GT(j["vertices"].get<int>(), 50);
    for (int k = 0; k < 3; ++k) {  // the unit sphere, within the mesh's error
      EXPECT_NEAR(j["bbox"]["min"][k].get<double>(), -1.0, 0.01);
      EXPECT_NEAR(j["bbox"]["max"][k].get<double>(), 1.0, 0.01);
    }
  }
  const auto quad = write("q.obj", "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 3\nf 1 2 3 4\nf 1 2 3\n");
  CmdResult r = quadrix_run("info " + q(quad));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("a polygon mesh"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("faces              2 (triangles 1, quads 1, larger 0)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("vertices           4"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("[0 0 0] – [2 1 3]"), std::string::npos) << r.out;

  const auto points = write("p.xyz", "0 0 0\n1 2 3\n-1 0 0.5\n");
  r = quadrix_run("info --json " + q(points));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["kind"], "points");
  EXPECT_EQ(j["points"], 3);
  EXPECT_EQ(j["bbox"]["max"][2], 3.0);
  // A file that is none of these still gets the model reader's account of what is wrong with it.
  r = quadrix_run("info " + q(write("x.qxm", "not a model\n")));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("x.qxm"), std::string::npos) << r.out;
}

// A molecule: atoms, chains, residues, elements and bonds (computed from covalent radii), in
// text and JSON; it used to get the model reader's "bad magic".
TEST_F(CliInputs, InfoSaysWhatAMoleculeHolds) {
  const auto pdb = write("two.pdb", kTwoChains);
  CmdResult r = quadrix_run("info " + q(pdb));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("molecule"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("elements           C 2, N 2, O 2"), std::string::npos) << r.out;
  r = quadrix_run("info --json " + q(pdb));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["kind"], "molecule");
  EXPECT_EQ(j["atoms"], 6);
  EXPECT_EQ(j["chains"], 2);
  EXPECT_EQ(j["residues"], 2);
  EXPECT_EQ(j["bonds"], 4);  // N–CA and CA–O in each residue; the chains lie 4 Å apart
  EXPECT_EQ(j["bbox"]["max"][2], 4.0);
}

// view reads MODEL through the loader render uses: every mesh format, a molecule with its
// options, a model; a point cloud is refused with a message saying what it is, by both.
TEST_F(CliInputs, ViewOpensEveryInputRenderOpens) {
  const auto model = dir_ / "s.qxm";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  std::vector<std::string> inputs = {q(model), q(write("m.pdb", kTwoChains)) + " --style licorice --colour-by chain"};
  for (const char* ext : {".ply", ".obj", ".off", ".stl"}) {
    const auto mesh = dir_ / (std::string("s") + ext);
    ASSERT_EQ(quadrix_run("mesh " + q(model) + " -o " + q(mesh) + " --quiet").code, 0);
    inputs.push_back(q(mesh));
  }
  for (const std::string& input : inputs) {
    SCOPED_TRACE(input);
    const CmdResult r = view_without_display(input);
    EXPECT_EQ(r.code, 6) << "expected the input read and only the window refused: " << r.out;
    EXPECT_EQ(r.out.find("bad input"), std::string::npos) << r.out;
    // render draws the same input.
    const CmdResult rr = quadrix_run("render " + input + " -o " + q(dir_ / "r.png") + " --size 48x40 --quiet");
    EXPECT_EQ(rr.code, 0) << rr.out;
  }
  const auto points = write("p.xyz", "0 0 0\n1 2 3\n-1 0 0.5\n");
  for (const CmdResult& r : {view_without_display(q(points)), quadrix_run("render " + q(points) + " -o " + q(dir_ / "p.png"))}) {
    EXPECT_EQ(r.code, 3) << r.out;
    EXPECT_NE(r.out.find("a point cloud"), std::string::npos) << r.out;
  }
}

// A mesh as `fit`'s input: its faces give the normals and are the surface the fit's two-sided
// check measures against (not normals estimated from its vertices); as `render --mesh`, drawn
// beside the model, its faces counted in the summary.
TEST_F(CliInputs, AMeshFeedsFitAndRenderMesh) {
  const auto model = dir_ / "s.qxm", mesh = dir_ / "s.stl", fitted = dir_ / "f.qxm", report = dir_ / "f.json";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  ASSERT_EQ(quadrix_run("mesh " + q(model) + " -o " + q(mesh) + " --max-error 0.01 --quiet").code, 0);
  const CmdResult f = quadrix_run("fit " + q(mesh) + " -o " + q(fitted) + " --max-error 0.01 --report " + q(report));
  ASSERT_EQ(f.code, 0) << f.out;
  const auto j = read_json(report)["fit"];
  EXPECT_EQ(j["normals"], "given");
  EXPECT_TRUE(j["surface"]["checked"].get<bool>());
  EXPECT_EQ(read_model(fitted).metadata.at("surface_reference"), "mesh");
  const CmdResult r = quadrix_run("render " + q(fitted) + " --mesh " + q(mesh) + " -o " + q(dir_ / "r.png") + " --size 48x40");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find(std::to_string(read_mesh(mesh).face_count()) + " mesh faces"), std::string::npos) << r.out;
}

// --style and --colour-by element|chain|residue reach the molecule reader in render (report,
// picture) and view; for any other input both commands refuse them (exit 2, naming the option).
TEST_F(CliInputs, MoleculeStyleAndColouringInRenderAndView) {
  const auto pdb = write("m.pdb", kTwoChains);
  const std::string base = "render --backend cpu --size 96x72 --quiet " + q(pdb);
  const auto render = [&](const std::string& args, const std::string& name) {
    const CmdResult r = quadrix_run(base + " " + args + " -o " + q(dir_ / (name + ".png")) + " --report " +
                                    q(dir_ / (name + ".json")));
    EXPECT_EQ(r.code, 0) << args << ": " << r.out;
    return read_json(dir_ / (name + ".json"))["render"];
  };
  const auto plain = render("", "plain");
  EXPECT_EQ(plain["input"], "molecule");
  EXPECT_EQ(plain["molecule"]["style"], "balls-sticks");  // the default below 20,000 atoms
  EXPECT_EQ(plain["molecule"]["colour_by"], "element");
  EXPECT_EQ(plain["molecule"]["atoms"], 6);
  const auto chain = render("--colour-by chain", "chain");
  EXPECT_EQ(chain["molecule"]["colour_by"], "chain");
  EXPECT_EQ(chain["molecule"]["style"], "balls-sticks");
  const auto space = render("--style spacefill --colour-by residue", "space");
  EXPECT_EQ(space["molecule"]["style"], "spacefill");
  EXPECT_EQ(space["molecule"]["colour_by"], "residue");
  EXPECT_EQ(render("--style licorice", "licorice")["molecule"]["style"], "licorice");
  // The options change the picture: chain colours are not CPK's; spacefill covers more.
  const Image8 a = read_png(dir_ / "plain.png"), b = read_png(dir_ / "chain.png");
  EXPECT_GT(differing_share(a, b), 0.05);
  EXPECT_GT(space["covered_pixels"].get<int>(), plain["covered_pixels"].get<int>());

  // Not a molecule: refused, naming the option, before anything is drawn or read.
  const auto model = dir_ / "s.qxm";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  for (const std::string option : {"--style spacefill", "--colour-by chain", "--colour-by element"}) {
    SCOPED_TRACE(option);
    CmdResult r = quadrix_run("render --backend cpu " + q(model) + " -o " + q(dir_ / "x.png") + " " + option);
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find(option.substr(0, option.find(' '))), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("molecule"), std::string::npos) << r.out;
    EXPECT_FALSE(std::filesystem::exists(dir_ / "x.png"));
    r = view_without_display(q(model) + " " + option);
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("molecule"), std::string::npos) << r.out;
  }
  CmdResult r = quadrix_run("render --implicit 'x^2 + y^2 + z^2 - 1' -o " + q(dir_ / "x.png") + " --style licorice");
  EXPECT_EQ(r.code, 2) << r.out;
  // Values outside the choices, as convert glyphs refuses them.
  r = view_without_display(q(pdb) + " --style cartoon");
  EXPECT_EQ(r.code, 2) << r.out;
  r = view_without_display(q(pdb) + " --colour-by error");
  EXPECT_EQ(r.code, 2) << r.out;
}
