// The window path: `quadrix view` under Xvfb renders a few frames through GLFW, reads the image
// back, and must match the headless render of the same model and view.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>

#include "core/image.h"
#include "tests/core/malformed_corpus.h"

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
  // The viewer frames the bounding sphere; render frames tightly unless --fill 0.
  ASSERT_EQ(sh(q + " render " + model + " -o " + headless + view_args + " --fill 0 --quiet"), 0);
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
