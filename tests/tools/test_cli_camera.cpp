// `quadrix render` camera options: tight framing, --up, --view, --fov as a lens, --zoom,
// --background none. CPU backend (the reference), so they run everywhere.
#include <gtest/gtest.h>

#include "tests/support.h"

#include <cmath>
#include <fstream>

#include <Eigen/Geometry>

#include <nlohmann/json.hpp>

#include "core/image.h"

using namespace quadrix;
using test_support::CmdResult;

namespace {
CmdResult quadrix_run(const std::string& args) { return test_support::run_command(QUADRIX_BINARY, args); }
std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }
nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}
Eigen::Vector3d vec(const nlohmann::json& v) { return {v.at(0).get<double>(), v.at(1).get<double>(), v.at(2).get<double>()}; }

struct Mask {
  int w = 0, h = 0, x0 = 1 << 30, x1 = -1, y0 = 1 << 30, y1 = -1, covered = 0;
  std::vector<bool> on;
};
Mask alpha_mask(const Image8& img) {
  Mask m{img.width, img.height};
  m.on.resize(std::size_t(img.width) * img.height);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (img.pixel(x, y)[3] > 0) {
        m.on[std::size_t(y) * img.width + x] = true;
        ++m.covered;
        m.x0 = std::min(m.x0, x), m.x1 = std::max(m.x1, x), m.y0 = std::min(m.y0, y), m.y1 = std::max(m.y1, y);
      }
  return m;
}
}  // namespace

class CliCamera : public test_support::TempDir {
protected:
  /// Renders with the CPU reference, a transparent background and the given options.
  std::pair<Mask, nlohmann::json> render(const std::filesystem::path& model, const std::string& options,
                                         const std::string& name) {
    const auto png = dir_ / (name + ".png"), report = dir_ / (name + ".json");
    const CmdResult r = quadrix_run("render --backend cpu " + q(model) + " -o " + q(png) + " --size 160x120 " +
                                    "--background none --quiet --report " + q(report) + " " + options);
    EXPECT_EQ(r.code, 0) << options << ": " << r.out;
    if (r.code != 0) return {};
    return {alpha_mask(read_png(png)), read_json(report)["render"]};
  }
};

TEST_F(CliCamera, TightFramingFillsTheFrameFromEveryViewAndUp) {
  const auto model = dir_ / "c.qxm";
  ASSERT_EQ(quadrix_run("synth cylinder -o " + q(model)).code, 0);
  for (const char* up : {"+y", "+z", "-x"})
    for (const char* view : {"front", "side", "top", "iso"}) {
      const auto [m, j] = render(model, std::string("--up ") + up + " --view " + view, std::string("v") + up + view);
      ASSERT_GT(m.covered, 0);
      // Filling: the larger of the spans against width and height (the smaller side is 120).
      const double fill = std::max(double(m.x1 - m.x0 + 1) / m.w, double(m.y1 - m.y0 + 1) / m.h);
      EXPECT_GE(fill, 0.85) << up << " " << view;
      EXPECT_LE(fill, 0.95) << up << " " << view;
      // Centred, not clipped.
      EXPECT_GT(m.x0, 0);
      EXPECT_GT(m.y0, 0);
      EXPECT_LT(m.x1, m.w - 1);
      EXPECT_LT(m.y1, m.h - 1);
      EXPECT_EQ(m.covered, j["covered_pixels"].get<int>());
    }
}

TEST_F(CliCamera, UpAxisTurnsTheImage) {
  const auto model = dir_ / "c.qxm";
  ASSERT_EQ(quadrix_run("synth cylinder -o " + q(model)).code, 0);
  const auto [a, ja] = render(model, "--up +y --view front", "a");
  const auto [b, jb] = render(model, "--up -y --view front", "b");
  EXPECT_TRUE(vec(ja["camera"]["up"]).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE(vec(jb["camera"]["up"]).isApprox(-Eigen::Vector3d::UnitY()));
  // Seen from the same front (+z) with up flipped: the picture turned by 180°.
  int same = 0;
  for (int y = 0; y < a.h; ++y)
    for (int x = 0; x < a.w; ++x) same += a.on[std::size_t(y) * a.w + x] == b.on[std::size_t(a.h - 1 - y) * a.w + (a.w - 1 - x)];
  EXPECT_GE(same, 0.995 * a.w * a.h);
  // Up +z: looking from −y, the camera's up is +z.
  const auto [c, jc] = render(model, "--up +z --view front", "c");
  const Eigen::Vector3d dir = (vec(jc["camera"]["eye"]) - vec(jc["camera"]["target"])).normalized();
  EXPECT_TRUE(dir.isApprox(-Eigen::Vector3d::UnitY(), 1e-9)) << dir.transpose();
  EXPECT_TRUE(vec(jc["camera"]["up"]).isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_NE(c.covered, a.covered);  // a different silhouette: the cylinder's axis is mostly +y
}

TEST_F(CliCamera, FovAndZoomMagnifyWithoutMovingTheCamera) {
  const auto model = dir_ / "s.qxm";
  ASSERT_EQ(quadrix_run("synth ellipsoid -o " + q(model)).code, 0);
  // A small fill, so the magnified view stays inside the frame.
  const auto [a, ja] = render(model, "--fill 0.3", "a");
  const auto [b, jb] = render(model, "--fill 0.3 --fov 20", "b");
  const auto [c, jc] = render(model, "--fill 0.3 --zoom 0.5", "c");
  EXPECT_TRUE(vec(ja["camera"]["eye"]).isApprox(vec(jb["camera"]["eye"])));
  EXPECT_TRUE(vec(ja["camera"]["eye"]).isApprox(vec(jc["camera"]["eye"])));
  // tan(20°/2)/tan(40°/2) ≈ 0.48: about 4.3× the area; zoom ½: a quarter.
  EXPECT_GT(b.covered, 3 * a.covered);
  EXPECT_NEAR(double(c.covered) / a.covered, 0.25, 0.05);
  EXPECT_NEAR(jc["camera"]["fov_y_deg"].get<double>(), 2 * std::atan(2 * std::tan(20 * M_PI / 180)) * 180 / M_PI, 1e-9);
}

TEST_F(CliCamera, BackgroundColourOrTransparent) {
  const auto model = dir_ / "s.qxm", png = dir_ / "bg.png";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  ASSERT_EQ(quadrix_run("render --backend cpu " + q(model) + " -o " + q(png) + " --size 64x64 --background 10,20,30").code, 0);
  const Image8 img = read_png(png);
  const std::uint8_t* corner = img.pixel(0, 0);
  EXPECT_EQ(corner[0], 10);
  EXPECT_EQ(corner[1], 20);
  EXPECT_EQ(corner[2], 30);
  EXPECT_EQ(corner[3], 255);
  EXPECT_EQ(quadrix_run("render --backend cpu " + q(model) + " -o " + q(png) + " --background 1,2").code, 2);
}
