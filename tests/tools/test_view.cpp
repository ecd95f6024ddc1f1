// The window path: `quadrix view` under Xvfb renders a few frames through GLFW, reads the image
// back, and must match the headless render of the same model and view.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <filesystem>

#include "core/image.h"
#include "tests/core/malformed_corpus.h"
#include "tests/support.h"

using quadrix::test::ScratchDir;

namespace {
int sh(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}
}  // namespace

TEST(View, WindowFramesMatchHeadlessRender) {
  if (sh("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  ScratchDir dir("view");
  const std::string q = QUADRIX_BINARY;
  const auto model = (dir / "h.qxm").string(), window = (dir / "window.png").string(),
             headless = (dir / "headless.png").string();
  ASSERT_EQ(sh(q + " synth hyperboloid2 --resolution 8 -o " + model), 0);
  const std::string view_args = " --size 200x150 --azimuth 40 --elevation 30 --no-cull";
  const int rc = sh("xvfb-run -a -s '-screen 0 640x480x24' " + q + " view " + model + view_args +
                    " --frames 4 --screenshot " + window + " --quiet");
  if (rc == 6) GTEST_SKIP() << "no OpenGL 4.5 context through GLFW under Xvfb";
  ASSERT_EQ(rc, 0);
  // The viewer frames like render: tightly, by default.
  ASSERT_EQ(sh(q + " render " + model + " -o " + headless + view_args + " --quiet"), 0);
  const auto a = quadrix::read_png(window), b = quadrix::read_png(headless);
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  std::size_t same = 0, covered = 0;
  for (std::size_t i = 0; i < a.rgba.size(); i += 4) {
    bool eq = true;
    for (int c = 0; c < 3; ++c) eq &= std::abs(int(a.rgba[i + c]) - int(b.rgba[i + c])) <= 2;
    same += eq;
    covered += a.rgba[i] != 255 || a.rgba[i + 1] != 255 || a.rgba[i + 2] != 255;
  }
  const std::size_t n = a.rgba.size() / 4;
  EXPECT_GE(same, n * 999 / 1000);
  EXPECT_GT(covered, n / 10);  // the model is on screen, not a blank frame
}

// A parameter animated in the window (--animate, a fixed 30 frames per second of animation under
// --frames): frame 30 of s = 0.3 → 1.2 over 1 s shows s = 1.2 exactly, as the headless render of
// that value does, and not the first frame's merged blobs.
TEST(View, AnimatedParameterReachesItsEndValue) {
  if (sh("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  ScratchDir dir("view");
  const std::string q = QUADRIX_BINARY;
  const auto window = (dir / "window.png").string(), report = (dir / "report.json").string();
  // The bounding sphere framed (--fill 0): the same camera for every value of s.
  const std::string view_args = " --size 160x120 --azimuth 20 --elevation 50 --fill 0";
  const int rc = sh("xvfb-run -a -s '-screen 0 640x480x24' " + q + " view --surface blobs-merging" + view_args +
                    " --animate s=0.3:1.2:1 --frames 31 --screenshot " + window + " --report " + report + " --quiet");
  if (rc == 6) GTEST_SKIP() << "no OpenGL 4.5 context through GLFW under Xvfb";
  ASSERT_EQ(rc, 0);
  std::ifstream in(report);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"parameters_last_frame\""), std::string::npos) << text;
  const auto agreement = [&](const std::string& s) {
    const auto headless = (dir / ("headless-" + s + ".png")).string();
    EXPECT_EQ(sh(q + " render --surface blobs-merging --param s=" + s + " -o " + headless + view_args + " --quiet"),
              0);
    const auto a = quadrix::read_png(window), b = quadrix::read_png(headless);
    EXPECT_EQ(a.rgba.size(), b.rgba.size());
    std::size_t same = 0;
    for (std::size_t i = 0; i + 3 < std::min(a.rgba.size(), b.rgba.size()); i += 4) {
      bool eq = true;
      for (int c = 0; c < 3; ++c) eq &= std::abs(int(a.rgba[i + c]) - int(b.rgba[i + c])) <= 2;
      same += eq;
    }
    return double(same) / double(a.rgba.size() / 4);
  };
  EXPECT_GE(agreement("1.2"), 0.999);
  EXPECT_LT(agreement("0.3"), 0.95);  // the first frame's surface looks different
}

TEST(View, AnimateRefusesUnknownParametersAndBadSyntax) {
  const std::string q = QUADRIX_BINARY;
  EXPECT_EQ(sh(q + " view --surface blobs-merging --animate k=0:1:1 --frames 1 --quiet 2> /dev/null"), 2);
  EXPECT_EQ(sh(q + " view --surface blobs-merging --animate s=0:1:0 --frames 1 --quiet 2> /dev/null"), 2);
  EXPECT_EQ(sh(q + " view --surface blobs-merging --animate s=0:1 --frames 1 --quiet 2> /dev/null"), 2);
}

namespace {
// Share of pixels whose colours differ by at most 2 per channel.
double same_share(const quadrix::Image8& a, const quadrix::Image8& b) {
  if (a.width != b.width || a.height != b.height) return 0;
  std::size_t same = 0;
  for (std::size_t i = 0; i < a.rgba.size(); i += 4) {
    bool eq = true;
    for (int c = 0; c < 3; ++c) eq &= std::abs(int(a.rgba[i + c]) - int(b.rgba[i + c])) <= 2;
    same += eq;
  }
  return double(same) / (a.rgba.size() / 4);
}
}  // namespace

TEST(View, CameraOptionsAndKeysSaveACameraThatRenderReproduces) {
  if (sh("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  ScratchDir dir("view-keys");
  const std::string q = QUADRIX_BINARY, d = dir.path().string();
  const std::string model = d + "/c.qxm";
  ASSERT_EQ(sh(q + " synth cylinder -o " + model), 0);
  // --up, --view, --zoom and --background as render takes them; K and P (pressed by --press) write
  // the camera and the screenshot under their default names in the working folder.
  const std::string bg = " --background 40,60,90";
  const std::string view_args = " --size 160x120 --up +z --view iso --zoom 0.8" + bg;
  const int rc = sh("cd " + d + " && xvfb-run -a -s '-screen 0 640x480x24' " + q + " view " + model + view_args +
                    " --frames 3 --press kp --quiet");
  if (rc == 6) GTEST_SKIP() << "no OpenGL 4.5 context through GLFW under Xvfb";
  ASSERT_EQ(rc, 0);
  ASSERT_TRUE(std::filesystem::exists(dir / "quadrix-camera.json"));
  ASSERT_TRUE(std::filesystem::exists(dir / "quadrix-screenshot.png"));
  const auto shot = quadrix::read_png(dir / "quadrix-screenshot.png");
  EXPECT_EQ(shot.pixel(0, 0)[0], 40);  // the top left corner: background
  EXPECT_EQ(shot.pixel(0, 0)[1], 60);
  EXPECT_EQ(shot.pixel(0, 0)[2], 90);
  // render with the same options, and render from the saved camera: the same picture.
  ASSERT_EQ(sh(q + " render " + model + " -o " + d + "/same.png" + view_args + " --quiet"), 0);
  ASSERT_EQ(sh(q + " render " + model + " -o " + d + "/saved.png --camera " + d + "/quadrix-camera.json" + bg + " --quiet"), 0);
  EXPECT_GE(same_share(shot, quadrix::read_png(dir / "same.png")), 0.999);
  EXPECT_GE(same_share(shot, quadrix::read_png(dir / "saved.png")), 0.999);
  // A different view gives a different picture (the comparison can fail).
  ASSERT_EQ(sh(q + " render " + model + " -o " + d + "/other.png --size 160x120 --view front" + bg + " --quiet"), 0);
  EXPECT_LT(same_share(shot, quadrix::read_png(dir / "other.png")), 0.95);
}

// Keys H and L turn on the shadows and the lines: the window then shows what render --shadows
// --outlines draws, and not the plain picture (the comparison can fail).
TEST(View, ShadowAndLineKeysMatchRender) {
  if (sh("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  ScratchDir dir("view-effects");
  const std::string q = QUADRIX_BINARY, d = dir.path().string();
  const std::string model = d + "/g.qxm";
  ASSERT_EQ(sh(q + " synth glyphs --count 30 -o " + model), 0);
  const std::string view_args = " --size 160x120 --azimuth 30 --elevation 25";
  const int rc = sh("xvfb-run -a -s '-screen 0 640x480x24' " + q + " view " + model + view_args +
                    " --frames 3 --press hl --screenshot " + d + "/window.png --quiet");
  if (rc == 6) GTEST_SKIP() << "no OpenGL 4.5 context through GLFW under Xvfb";
  ASSERT_EQ(rc, 0);
  ASSERT_EQ(sh(q + " render " + model + " -o " + d + "/effects.png" + view_args + " --shadows --outlines --quiet"), 0);
  ASSERT_EQ(sh(q + " render " + model + " -o " + d + "/plain.png" + view_args + " --quiet"), 0);
  const auto shot = quadrix::read_png(dir / "window.png");
  EXPECT_GE(same_share(shot, quadrix::read_png(dir / "effects.png")), 0.999);
  EXPECT_LT(same_share(shot, quadrix::read_png(dir / "plain.png")), 0.98);
}

// view opens what render opens, through the same loader: a mesh file as MODEL (flat triangles)
// and a molecule file in the given --style and --colour-by; the window shows what render draws
// for the same arguments, and the molecule options change it (the comparison can fail).
TEST(View, MeshAndMoleculeInputsMatchRender) {
  if (sh("command -v xvfb-run > /dev/null") != 0) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  ScratchDir dir("view-inputs");
  const std::string q = QUADRIX_BINARY, d = dir.path().string();
  ASSERT_EQ(sh(q + " synth ellipsoid -o " + d + "/e.qxm --quiet"), 0);
  ASSERT_EQ(sh(q + " mesh " + d + "/e.qxm -o " + d + "/e.stl --quiet"), 0);
  std::ofstream(dir / "m.pdb") << quadrix::test_support::kTwoChainPdb;
  const std::string view_args = " --size 160x120 --azimuth 30 --elevation 25";
  const auto window = [&](const std::string& input, const std::string& png) {
    return sh("xvfb-run -a -s '-screen 0 640x480x24' " + q + " view " + input + view_args + " --frames 3 --screenshot " +
              d + "/" + png + " --quiet");
  };
  const int rc = window(d + "/e.stl", "mesh-window.png");
  if (rc == 6) GTEST_SKIP() << "no OpenGL 4.5 context through GLFW under Xvfb";
  ASSERT_EQ(rc, 0);
  ASSERT_EQ(sh(q + " render " + d + "/e.stl -o " + d + "/mesh.png" + view_args + " --quiet"), 0);
  EXPECT_GE(same_share(quadrix::read_png(dir / "mesh-window.png"), quadrix::read_png(dir / "mesh.png")), 0.999);

  const std::string molecule = d + "/m.pdb --style spacefill --colour-by chain";
  ASSERT_EQ(window(molecule, "molecule-window.png"), 0);
  ASSERT_EQ(sh(q + " render " + molecule + " -o " + d + "/molecule.png" + view_args + " --quiet"), 0);
  ASSERT_EQ(sh(q + " render " + d + "/m.pdb -o " + d + "/default.png" + view_args + " --quiet"), 0);
  const auto shot = quadrix::read_png(dir / "molecule-window.png");
  EXPECT_GE(same_share(shot, quadrix::read_png(dir / "molecule.png")), 0.999);
  EXPECT_LT(same_share(shot, quadrix::read_png(dir / "default.png")), 0.95);
}
