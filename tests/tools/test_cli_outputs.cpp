// Honest outputs of every command: a one-line summary on stderr unless --quiet, the report
// written on failure too (with the error), `producer` as typed, JPEG by extension, the progress
// bar on a terminal (run under a pseudo-terminal) and never on a pipe.
#include <gtest/gtest.h>

#include "tests/support.h"
#include "tests/tools/cli_support.h"

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <fstream>

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "core/image.h"
#include "core/model_io.h"

using namespace quadrix;
using test_support::CmdResult;
using test_support::q;
using test_support::quadrix_run;
using test_support::read_json;

namespace {
int count_lines(const std::string& text, const std::string& prefix) {
  int n = 0;
  for (std::size_t at = 0; (at = text.find(prefix, at)) != std::string::npos; at += prefix.size())
    n += at == 0 || text[at - 1] == '\n';
  return n;
}
}  // namespace

class CliOutputs : public test_support::TempDir {};

TEST_F(CliOutputs, EveryCommandSaysWhatItWroteUnlessQuiet) {
  const auto model = dir_ / "s.qxm", quads = write("q.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0.2\nv 0 1 0\nf 1 2 3 4\n");
  const auto pdb = write("w.pdb",
                         "ATOM      1  O   HOH A   1       0.000   0.000   0.000  1.00  0.00           O\n"
                         "ATOM      2  H1  HOH A   1       0.957   0.000   0.000  1.00  0.00           H\n"
                         "ATOM      3  H2  HOH A   1      -0.240   0.927   0.000  1.00  0.00           H\n"
                         "END\n");
  const auto balls = write("b.xyzr", "0 0 0 1\n1.2 0 0 1\n0 1.1 0 0.8\n");
  std::string xyz;
  for (int i = 0; i < 400; ++i) {
    const double t = std::acos(1 - 2 * (i + 0.5) / 400), p = i * 2.399963229728653;
    xyz += fmt::format("{} {} {}\n", std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
  }
  const auto points = write("p.xyz", xyz);
  const auto cube = write("c.off", "OFF\n8 12 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
                                   "3 0 2 1\n3 0 3 2\n3 4 5 6\n3 4 6 7\n3 0 1 5\n3 0 5 4\n"
                                   "3 2 3 7\n3 2 7 6\n3 1 2 6\n3 1 6 5\n3 0 4 7\n3 0 7 3\n");
  std::string uv = "OFF\n";  // a unit sphere, 12 rings of 24, for curvature glyphs
  {
    constexpr int kRings = 12, kSegments = 24;
    std::string v, f;
    int faces = 0;
    v += "0 0 1\n";
    for (int i = 1; i < kRings; ++i)
      for (int j = 0; j < kSegments; ++j) {
        const double t = std::numbers::pi * i / kRings, p = 2 * std::numbers::pi * j / kSegments;
        v += fmt::format("{} {} {}\n", std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
      }
    v += "0 0 -1\n";
    const int south = 1 + (kRings - 1) * kSegments;
    const auto at = [](int ring, int j) { return 1 + (ring - 1) * kSegments + (j % kSegments); };
    for (int j = 0; j < kSegments; ++j, faces += 2) {
      f += fmt::format("3 0 {} {}\n", at(1, j), at(1, j + 1));
      f += fmt::format("3 {} {} {}\n", south, at(kRings - 1, j + 1), at(kRings - 1, j));
    }
    for (int i = 1; i + 1 < kRings; ++i)
      for (int j = 0; j < kSegments; ++j, faces += 2) {
        f += fmt::format("3 {} {} {}\n", at(i, j), at(i + 1, j), at(i + 1, j + 1));
        f += fmt::format("3 {} {} {}\n", at(i, j), at(i + 1, j + 1), at(i, j + 1));
      }
    uv += fmt::format("{} {} 0\n", south + 1, faces) + v + f;
  }
  const auto sphere = write("uv.off", uv);
  struct Case {
    std::string name, args, fragment;  // the summary names what was written
  };
  const std::vector<Case> cases = {
      {"synth", "synth sphere -o " + q(model), "s.qxm"},
      {"render", "render --backend cpu --size 32x32 " + q(model) + " -o " + q(dir_ / "r.png"), "r.png"},
      {"mesh", "mesh " + q(model) + " -o " + q(dir_ / "m.ply"), "m.ply"},
      {"convert quads", "convert quads " + q(quads) + " -o " + q(dir_ / "q.qxm"), "q.qxm"},
      {"convert glyphs", "convert glyphs " + q(pdb) + " -o " + q(dir_ / "g.qxm"), "g.qxm"},
      {"convert skin", "convert skin " + q(balls) + " -o " + q(dir_ / "k.qxm"), "k.qxm"},
      {"convert volume", "convert volume --synth marschner-lobb --grid 8 --iso 0.5 -o " + q(dir_ / "v.qxm"), "v.qxm"},
      {"fit", "fit " + q(points) + " -o " + q(dir_ / "f.qxm") + " --max-error 0.02 --allow-exceed", "f.qxm"},
      {"convert curvature-glyphs", "convert curvature-glyphs " + q(sphere) + " -o " + q(dir_ / "c.qxm"), "c.qxm"},
      {"tetrahedralize", "tetrahedralize " + q(cube) + " -o " + q(dir_ / "c.mesh"), "c.mesh"},
  };
  for (const Case& c : cases) {
    CmdResult r = quadrix_run(c.args);
    ASSERT_EQ(r.code, 0) << c.args << ": " << r.out;
    EXPECT_EQ(count_lines(r.out, "quadrix " + c.name + ": wrote "), 1) << c.args << ": " << r.out;
    EXPECT_NE(r.out.find(c.fragment), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(" s\n"), std::string::npos) << "no time: " << r.out;
    r = quadrix_run(c.args + " --quiet");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(r.out, "") << c.args;
  }
}

TEST_F(CliOutputs, TheReportIsWrittenOnFailureWithTheError) {
  const auto report = dir_ / "r.json";
  CmdResult r = quadrix_run("render " + q(dir_ / "missing.qxm") + " -o " + q(dir_ / "o.png") + " --report " + q(report));
  ASSERT_EQ(r.code, 5) << r.out;
  nlohmann::json j = read_json(report);
  EXPECT_EQ(j["exit_code"].get<int>(), 5);
  EXPECT_EQ(j["command"], "render");
  EXPECT_NE(j["error"].get<std::string>().find("missing.qxm"), std::string::npos) << j.dump();
  // A usage error found while parsing (after --report was read).
  std::filesystem::remove(report);
  r = quadrix_run("render " + q(dir_ / "missing.qxm") + " --report " + q(report) + " -o " + q(dir_ / "o.png") + " --fov nan");
  ASSERT_EQ(r.code, 2) << r.out;
  j = read_json(report);
  EXPECT_EQ(j["exit_code"].get<int>(), 2);
  EXPECT_NE(j["error"].get<std::string>().find("--fov"), std::string::npos) << j.dump();
  // Success: error null.
  const auto model = dir_ / "s.qxm";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model) + " --report " + q(report)).code, 0);
  j = read_json(report);
  EXPECT_EQ(j["exit_code"].get<int>(), 0);
  EXPECT_TRUE(j["error"].is_null());
  // A subcommand of a subcommand is named as typed ("quads" before), on success and on a usage error.
  const auto quads = write("q.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0.2\nv 0 1 0\nf 1 2 3 4\n");
  ASSERT_EQ(quadrix_run("convert quads " + q(quads) + " -o " + q(dir_ / "q.qxm") + " --report " + q(report)).code, 0);
  EXPECT_EQ(read_json(report)["command"], "convert quads");
  ASSERT_EQ(quadrix_run("convert quads " + q(quads) + " --report " + q(report) + " -o " + q(dir_ / "q.qxm") + " --no-such").code, 2);
  EXPECT_EQ(read_json(report)["command"], "convert quads");
}

TEST_F(CliOutputs, ProducerRecordsTheCommandAsTyped) {
  const auto model = dir_ / "a model.qxm";
  ASSERT_EQ(quadrix_run("synth glyphs --count 5 -o " + q(model)).code, 0);
  EXPECT_EQ(read_model(model).metadata.at("producer"), "quadrix synth glyphs --count 5 -o " + q(model));
  // Options left at their defaults are not recorded.
  const auto quads = write("q.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0.2\nv 0 1 0\nf 1 2 3 4\n"), out = dir_ / "q.qxm";
  ASSERT_EQ(quadrix_run("convert quads " + q(quads) + " -o " + q(out) + " -q").code, 0);
  EXPECT_EQ(read_model(out).metadata.at("producer"), "quadrix convert quads " + quads.string() + " -o " + out.string() + " -q");
}

TEST_F(CliOutputs, JpegByExtensionOtherNamesRefused) {
  const auto model = dir_ / "s.qxm", png = dir_ / "a.png", jpg = dir_ / "a.jpg";
  ASSERT_EQ(quadrix_run("synth ellipsoid -o " + q(model)).code, 0);
  const std::string args = "render --backend cpu --size 80x60 --quiet " + q(model) + " -o ";
  ASSERT_EQ(quadrix_run(args + q(png)).code, 0);
  CmdResult r = quadrix_run(args + q(jpg));
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(jpg, std::ios::binary);
  unsigned char magic[3] = {0, 0, 0};
  in.read(reinterpret_cast<char*>(magic), 3);
  EXPECT_EQ(magic[0], 0xFF);
  EXPECT_EQ(magic[1], 0xD8);
  EXPECT_EQ(magic[2], 0xFF);
  const Image8 a = read_png(png), b = read_jpeg(jpg);
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  double diff = 0;
  for (std::size_t i = 0; i < a.rgba.size(); ++i) diff += std::abs(int(a.rgba[i]) - int(b.rgba[i]));
  EXPECT_LT(diff / a.rgba.size(), 3.0);  // quality 92: a few levels per channel on average
  EXPECT_EQ(quadrix_run(args + q(dir_ / "b.JPEG")).code, 0);
  r = quadrix_run(args + q(dir_ / "t.jpg") + " --background none");
  EXPECT_EQ(r.code, 2) << r.out;
  r = quadrix_run(args + q(dir_ / "t.bmp"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "t.bmp"));
}

// Runs the command under a pseudo-terminal (python3's pty), so stderr is a terminal; env: variables.
CmdResult under_pty(const std::string& args, const std::string& env = "") {
  const std::string cmd = "python3 -c \"import pty, sys; sys.exit(pty.spawn(sys.argv[1:]) >> 8)\" sh -c " +
                          q(env + " " + std::string(QUADRIX_BINARY) + " " + args);
  return test_support::run_command(cmd, "");
}

TEST_F(CliOutputs, ProgressBarOnATerminalOnlyForLongWork) {
  if (std::system("python3 -c 'import pty' > /dev/null 2>&1") != 0) GTEST_SKIP() << "python3 with pty is not available";
  const auto model = dir_ / "h.qxm";
  ASSERT_EQ(quadrix_run("synth hyperboloid1 --resolution 12 -o " + q(model)).code, 0);
  // QUADRIX_PROGRESS_DELAY=0 makes any work "long": the bar, then the summary on a clean line.
  const std::string now = "QUADRIX_PROGRESS_DELAY=0";
  const std::string render = "render --backend cpu --no-cull --size 200x200 " + q(model) + " -o " + q(dir_ / "a.png");
  CmdResult r = under_pty(render, now);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("render ["), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("100%"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\r\033[K"), std::string::npos) << "bar not cleared: " << r.out;
  EXPECT_NE(r.out.find("quadrix render: wrote"), std::string::npos) << r.out;
  // Turntables count frames; fits (no fractions) show a moving marker.
  r = under_pty("render --backend cpu --size 40x40 --turntable 4 " + q(model) + " -o " + q(dir_ / "t.png"), now);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("turntable ["), std::string::npos) << r.out;
  std::string xyz;
  for (int i = 0; i < 800; ++i) {
    const double t = std::acos(1 - 2 * (i + 0.5) / 800), p = i * 2.399963229728653;
    xyz += fmt::format("{} {} {}\n", std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), 0.5 * std::cos(t));
  }
  r = under_pty("fit " + q(write("p.xyz", xyz)) + " -o " + q(dir_ / "f.qxm") + " --allow-exceed", now);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("fit ["), std::string::npos) << r.out;
  // Conversions without fractions show the marker too (tetrahedralize showed nothing for 2.2 s).
  const auto cube = write("cube.off",
                          "OFF\n8 6 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
                          "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n");
  r = under_pty("convert quads " + q(cube) + " -o " + q(dir_ / "c.qxm"), now);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("quads ["), std::string::npos) << r.out;
  r = under_pty("tetrahedralize " + q(cube) + " -o " + q(dir_ / "c.mesh"), now);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("tetrahedralize ["), std::string::npos) << r.out;
  // --quiet on a terminal, or a pipe: no bar.
  r = under_pty(render + " --quiet", now);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("["), std::string::npos) << r.out;
  r = test_support::run_command(now + " " + std::string(QUADRIX_BINARY), render);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("render ["), std::string::npos) << r.out;
  // Short work on a terminal with the default delay (1 s): no bar.
  r = under_pty("render --backend cpu --size 16x16 " + q(model) + " -o " + q(dir_ / "b.png"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("render ["), std::string::npos) << r.out;
}
