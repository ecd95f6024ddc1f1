// End-to-end tests of the `quadrix` command: exit codes, messages, outputs written atomically.
#include <gtest/gtest.h>

#include "tests/support.h"
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "core/image.h"
#include "core/model_io.h"
#include "tests/core/malformed_corpus.h"

using namespace quadrix;
using quadrix::test::ScratchDir;

namespace {
using test_support::CmdResult;
CmdResult quadrix_run(const std::string& args) { return test_support::run_command(QUADRIX_BINARY, args); }

std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }
}  // namespace

TEST(Cli, SynthInfoRenderRoundTrip) {
  ScratchDir dir("cli");
  const auto model = dir / "h.qxm";
  CmdResult r = quadrix_run("synth hyperboloid1 --resolution 6 -o " + q(model));
  ASSERT_EQ(r.code, 0) << r.out;
  r = quadrix_run("info " + q(model) + " --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["counts"]["tet"].get<std::size_t>(), read_model(model).tets.size());
  EXPECT_GT(j["counts"]["tet"].get<int>(), 0);
  EXPECT_EQ(j["metadata"]["producer"], "quadrix synth hyperboloid1");

  const auto png = dir / "h.png", depth = dir / "d.pfm", report = dir / "r.json";
  r = quadrix_run("render --backend cpu " + q(model) + " -o " + q(png) + " --size 64x48 --no-cull --depth-out " +
                  q(depth) + " --report " + q(report) + " --quiet");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(r.out.empty()) << "--quiet printed: " << r.out;
  const Image8 img = read_png(png);
  EXPECT_EQ(img.width, 64);
  EXPECT_EQ(img.height, 48);
  const FloatImage d = read_pfm(depth);
  EXPECT_EQ(d.width, 64);
  std::ifstream rep(report);
  const auto rj = nlohmann::json::parse(rep);
  EXPECT_EQ(rj["exit_code"], 0);
  EXPECT_GT(rj["render"]["covered_pixels"].get<int>(), 100);
  // Every finite depth belongs to a covered (non-background) pixel.
  int finite = 0;
  for (float v : d.data) finite += std::isfinite(v);
  EXPECT_EQ(finite, rj["render"]["covered_pixels"].get<int>());
}

TEST(Cli, EveryMalformedFileExitsThreeNamingThePlace) {
  ScratchDir dir("cli-malformed");
  const auto corpus = quadrix::test::make_malformed_corpus(dir.path());
  ASSERT_GE(corpus.size(), 20u);
  for (const auto& c : corpus) {
    const CmdResult r = quadrix_run("info " + q(c.path));
    EXPECT_EQ(r.code, 3) << c.path << ": " << r.out;
    EXPECT_NE(r.out.find(c.path.filename().string()), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(c.expected), std::string::npos) << "expected '" << c.expected << "' in: " << r.out;
  }
}

TEST(Cli, UsageErrorsExitTwo) {
  EXPECT_EQ(quadrix_run("").code, 2);
  EXPECT_EQ(quadrix_run("frobnicate").code, 2);
  EXPECT_EQ(quadrix_run("synth teapot -o x.qxm").code, 2);
  EXPECT_EQ(quadrix_run("render a.qxm -o a.png --size 12by4").code, 2);
  EXPECT_EQ(quadrix_run("render a.qxm").code, 2);  // --out missing
  EXPECT_EQ(quadrix_run("--help").code, 0);
  EXPECT_EQ(quadrix_run("render --help").code, 0);
}

TEST(Cli, MissingFilesAndUnwritableOutputsFailCleanly) {
  ScratchDir dir("cli-io");
  CmdResult r = quadrix_run("info " + q(dir / "nope.qxm"));
  EXPECT_EQ(r.code, 5) << r.out;
  EXPECT_NE(r.out.find("nope.qxm"), std::string::npos);
  // Writing into a folder that does not exist: exit 5, and nothing half-written anywhere.
  r = quadrix_run("synth sphere -o " + q(dir / "missing" / "s.qxm"));
  EXPECT_EQ(r.code, 5) << r.out;
  // An existing output survives a failed run untouched.
  const auto model = dir / "s.qxm";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  const auto png = dir / "keep.png";
  { std::ofstream(png) << "previous"; }
  r = quadrix_run("render " + q(dir / "nope.qxm") + " -o " + q(png));
  EXPECT_EQ(r.code, 5);
  std::ifstream in(png);
  std::string s;
  in >> s;
  EXPECT_EQ(s, "previous");
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}
