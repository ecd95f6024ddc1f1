// `quadrix render` camera options: tight framing, --up, --view, --fov as a lens, --zoom,
// --background none. CPU backend (the reference), so they run everywhere.
#include <gtest/gtest.h>

#include "tests/support.h"
#include "tests/tools/cli_support.h"

#include <cmath>
#include <fstream>
#include <regex>

#include <fmt/format.h>

#include <Eigen/Geometry>

#include <nlohmann/json.hpp>

#include "core/image.h"

using namespace quadrix;
using test_support::CmdResult;
using test_support::q;
using test_support::quadrix_run;
using test_support::read_json;

namespace {
Eigen::Vector3d vec(const nlohmann::json& v) { return {v.at(0).get<double>(), v.at(1).get<double>(), v.at(2).get<double>()}; }

struct Mask {
  int w = 0, h = 0, x0 = 1 << 30, x1 = -1, y0 = 1 << 30, y1 = -1, covered = 0;
  std::vector<bool> on{};
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
    const std::string size = options.find("--size") == std::string::npos ? " --size 160x120 " : " ";
    const CmdResult r = quadrix_run("render --backend cpu " + q(model) + " -o " + q(png) + size +
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
  // One number is a square.
  ASSERT_EQ(quadrix_run("render --backend cpu " + q(model) + " -o " + q(png) + " --size 48").code, 0);
  EXPECT_EQ(read_png(png).width, 48);
  EXPECT_EQ(read_png(png).height, 48);
}

namespace {
std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
}  // namespace

TEST_F(CliCamera, SavedCameraReproducesTheImage) {
  const auto model = dir_ / "h.qxm", cam = dir_ / "cam.json";
  ASSERT_EQ(quadrix_run("synth hyperboloid1 --resolution 6 -o " + q(model)).code, 0);
  // An unusual view: up +z, a narrow lens, zoom, a non-square image.
  const std::string view = "--up +z --azimuth 70 --elevation 35 --fov 25 --zoom 1.3 --size 96x64";
  for (const char* backend : {"cpu", "gl"}) {
    const auto a = dir_ / (std::string(backend) + "-a.png"), b = dir_ / (std::string(backend) + "-b.png");
    CmdResult r = quadrix_run(std::string("render --backend ") + backend + " " + q(model) + " -o " + q(a) + " " + view +
                              " --no-cull --save-camera " + q(cam) + " --quiet");
    if (std::string(backend) == "gl" && r.code == 6) GTEST_SKIP() << "no OpenGL 4.5 context: " << r.out;
    ASSERT_EQ(r.code, 0) << r.out;
    const nlohmann::json saved = read_json(cam);
    EXPECT_EQ(saved["width"].get<int>(), 96);
    EXPECT_EQ(saved["height"].get<int>(), 64);
    // No view option beside --camera: the same camera, the same pixels, byte for byte.
    r = quadrix_run(std::string("render --backend ") + backend + " " + q(model) + " -o " + q(b) + " --no-cull --camera " +
                    q(cam) + " --quiet");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(slurp(a), slurp(b)) << backend;
    // A report's render.camera is a camera file too.
    const auto report = dir_ / "report.json", c = dir_ / "c.png";
    ASSERT_EQ(quadrix_run(std::string("render --backend ") + backend + " " + q(model) + " -o " + q(c) + " --no-cull --camera " +
                          q(cam) + " --quiet --report " + q(report)).code, 0);
    ASSERT_EQ(quadrix_run(std::string("render --backend ") + backend + " " + q(model) + " -o " + q(c) + " --no-cull --camera " +
                          q(report) + " --quiet").code, 0);
    EXPECT_EQ(slurp(a), slurp(c)) << backend;
  }
}

TEST_F(CliCamera, OptionsTypedBesideACameraFileOverrideIt) {
  const auto model = dir_ / "c.qxm", cam = dir_ / "cam.json";
  ASSERT_EQ(quadrix_run("synth cylinder -o " + q(model)).code, 0);
  const auto [a, ja] = render(model, "--view front --save-camera " + q(cam), "a");
  // --size: the image changes, the vertical lens and the eye stay.
  const auto [b, jb] = render(model, "--camera " + q(cam) + " --size 80x60", "b");
  EXPECT_EQ(jb["camera"]["width"].get<int>(), 80);
  EXPECT_TRUE(vec(ja["camera"]["eye"]).isApprox(vec(jb["camera"]["eye"])));
  EXPECT_EQ(ja["camera"]["fov_y_deg"].get<double>(), jb["camera"]["fov_y_deg"].get<double>());
  // --fov: the lens; --zoom narrows the file's lens.
  const auto [c, jc] = render(model, "--camera " + q(cam) + " --fov 20", "c");
  EXPECT_EQ(jc["camera"]["fov_y_deg"].get<double>(), 20.0);
  EXPECT_GT(c.covered, 1.3 * a.covered);  // magnified (and clipped by the frame)
  const auto [d, jd] = render(model, "--camera " + q(cam) + " --zoom 2", "d");
  EXPECT_NEAR(std::tan(jd["camera"]["fov_y_deg"].get<double>() * M_PI / 360),
              std::tan(ja["camera"]["fov_y_deg"].get<double>() * M_PI / 360) / 2, 1e-12);
  // --view: the eye turns about the file's target at the same distance.
  const auto [e, je] = render(model, "--camera " + q(cam) + " --view side", "e");
  const Eigen::Vector3d ta = vec(ja["camera"]["target"]), te = vec(je["camera"]["target"]);
  EXPECT_TRUE(ta.isApprox(te));
  EXPECT_NEAR((vec(je["camera"]["eye"]) - te).norm(), (vec(ja["camera"]["eye"]) - ta).norm(), 1e-9);
  EXPECT_TRUE((vec(je["camera"]["eye"]) - te).normalized().isApprox(Eigen::Vector3d::UnitX(), 1e-9));
  // The report's framing records what framed each view: every option without a camera file;
  // with one, the file and only the options typed beside it (the file held the rest).
  EXPECT_EQ(ja["framing"]["view"], "front");
  EXPECT_EQ(ja["framing"]["up"], "+y");
  EXPECT_TRUE(ja["framing"]["camera_file"].is_null());
  EXPECT_EQ(jb["framing"]["camera_file"], cam.string());
  for (const char* key : {"view", "azimuth_deg", "elevation_deg", "up", "fill"}) EXPECT_TRUE(jb["framing"][key].is_null()) << key;
  EXPECT_EQ(je["framing"]["view"], "side");
  EXPECT_EQ(je["framing"]["azimuth_deg"].get<double>(), 90.0);
  EXPECT_TRUE(je["framing"]["up"].is_null());
  // --up alone re-places the eye at the default angles: they are recorded.
  const auto [f, jf] = render(model, "--camera " + q(cam) + " --up +z", "f");
  EXPECT_EQ(jf["framing"]["up"], "+z");
  EXPECT_EQ(jf["framing"]["azimuth_deg"].get<double>(), 30.0);
  EXPECT_EQ(jf["framing"]["elevation_deg"].get<double>(), 20.0);
}

TEST_F(CliCamera, BadCameraFilesNameTheFileAndTheKey) {
  const auto model = dir_ / "s.qxm";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  const std::string good = R"("eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 40, "width": 32, "height": 32, "near": 0.1, "far": 10)";
  const auto run = [&](const std::string& name, const std::string& text) {
    const auto f = write_text(name, text);
    return quadrix_run("render --backend cpu " + q(model) + " -o " + q(dir_ / "x.png") + " --camera " + q(f));
  };
  EXPECT_EQ(run("ok.json", "{" + good + "}").code, 0);
  std::filesystem::remove(dir_ / "x.png");
  struct Case {
    std::string name, text, fragment;
  };
  const std::vector<Case> cases = {
      {"syntax.json", "{\"eye\": [0, 0,", "byte"},
      {"no-eye.json", R"({"target": [0, 0, 0]})", "'eye'"},
      {"eye2.json", "{" + std::string(R"("eye": [0, 0], )") + good.substr(good.find("\"target\"")) + "}", "'eye'"},
      {"fov.json", "{" + std::regex_replace(good, std::regex("\"fov_y_deg\": 40"), "\"fov_y_deg\": 180") + "}", "'fov_y_deg'"},
      {"width.json", "{" + std::regex_replace(good, std::regex("\"width\": 32"), "\"width\": 2.5") + "}", "'width'"},
      {"far.json", "{" + std::regex_replace(good, std::regex("\"far\": 10"), "\"far\": 0.01") + "}", "'far'"},
      {"up.json", "{" + std::regex_replace(good, std::regex("\"up\": \\[0, 1, 0\\]"), "\"up\": [0, 0, 1]") + "}", "'up'"},
      {"array.json", "[1, 2, 3]", "object"},
  };
  for (const Case& c : cases) {
    const CmdResult r = run(c.name, c.text);
    EXPECT_EQ(r.code, 3) << c.name << ": " << r.out;
    EXPECT_NE(r.out.find(c.name), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(c.fragment), std::string::npos) << c.name << ": " << r.out;
    EXPECT_FALSE(std::filesystem::exists(dir_ / "x.png")) << c.name;
  }
  const CmdResult missing = quadrix_run("render --backend cpu " + q(model) + " -o " + q(dir_ / "y.png") + " --camera " +
                                        q(dir_ / "none.json"));
  EXPECT_EQ(missing.code, 5) << missing.out;
  EXPECT_NE(missing.out.find("none.json"), std::string::npos) << missing.out;
}

TEST_F(CliCamera, SupersamplingIsTheBoxFilteredLargerImage) {
  const auto model = dir_ / "s.qxm", cam = dir_ / "cam.json";
  ASSERT_EQ(quadrix_run("synth ellipsoid -o " + q(model)).code, 0);
  const auto [a, ja] = render(model, "--size 40x30 --save-camera " + q(cam), "plain");
  const auto ss = dir_ / "ss.png", big = dir_ / "big.png";
  ASSERT_EQ(quadrix_run("render --backend cpu " + q(model) + " -o " + q(ss) + " --camera " + q(cam) +
                        " --supersample 3 --background none --quiet").code, 0);
  // The same camera at 3× the size, filtered here: the image --supersample 3 must give.
  ASSERT_EQ(quadrix_run("render --backend cpu " + q(model) + " -o " + q(big) + " --camera " + q(cam) +
                        " --size 120x90 --background none --quiet").code, 0);
  const Image8 s = read_png(ss), b = read_png(big);
  ASSERT_EQ(s.width, 40);
  ASSERT_EQ(s.height, 30);
  int partial = 0, max_diff = 0;
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      int sum[4] = {0, 0, 0, 0};
      for (int dy = 0; dy < 3; ++dy)
        for (int dx = 0; dx < 3; ++dx) {
          const std::uint8_t* p = b.pixel(3 * x + dx, 3 * y + dy);
          for (int k = 0; k < 3; ++k) sum[k] += p[k] * p[3];
          sum[3] += p[3];
        }
      const std::uint8_t* p = s.pixel(x, y);
      max_diff = std::max(max_diff, std::abs(p[3] - (sum[3] + 4) / 9));
      if (sum[3] > 0)
        for (int k = 0; k < 3; ++k) max_diff = std::max(max_diff, std::abs(p[k] - (sum[k] + sum[3] / 2) / sum[3]));
      partial += p[3] > 0 && p[3] < 255;
    }
  EXPECT_EQ(max_diff, 0);
  // Antialiased: the silhouette has partly covered pixels; without supersampling it has none.
  EXPECT_GT(partial, 20);
  const Image8 plain = read_png(dir_ / "plain.png");
  for (std::size_t i = 3; i < plain.rgba.size(); i += 4) ASSERT_TRUE(plain.rgba[i] == 0 || plain.rgba[i] == 255);
  EXPECT_EQ(quadrix_run("render --backend cpu " + q(model) + " -o " + q(ss) + " --supersample 2 --depth-out " +
                        q(dir_ / "d.pfm")).code, 2);
}

TEST_F(CliCamera, GlSupersamplingMatchesTheReference) {
  const auto model = dir_ / "h.qxm";
  ASSERT_EQ(quadrix_run("synth hyperboloid2 --resolution 6 -o " + q(model)).code, 0);
  const auto gl = dir_ / "gl.png", cpu = dir_ / "cpu.png";
  const std::string args = q(model) + " --size 64x48 --supersample 4 --no-cull --quiet -o ";
  const CmdResult r = quadrix_run("render --backend gl " + args + q(gl));
  if (r.code == 6) GTEST_SKIP() << "no OpenGL 4.5 context: " << r.out;
  ASSERT_EQ(r.code, 0) << r.out;
  ASSERT_EQ(quadrix_run("render --backend cpu " + args + q(cpu)).code, 0);
  const Image8 g = read_png(gl), c = read_png(cpu);
  ASSERT_EQ(g.rgba.size(), c.rgba.size());
  double total = 0;
  for (std::size_t i = 0; i < g.rgba.size(); ++i) total += std::abs(int(g.rgba[i]) - int(c.rgba[i]));
  EXPECT_LT(total / g.rgba.size(), 1.5);  // mean absolute difference per channel, 0..255
}

TEST_F(CliCamera, TurntableFramesTurnAboutTheUpAxis) {
  const auto model = dir_ / "c.qxm", out = dir_ / "t.png", report = dir_ / "t.json";
  ASSERT_EQ(quadrix_run("synth cylinder -o " + q(model)).code, 0);
  const CmdResult r = quadrix_run("render --backend cpu " + q(model) + " -o " + q(out) +
                                  " --size 64x48 --up +z --turntable 8 --background none --report " + q(report));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("8 frames"), std::string::npos) << r.out;  // the summary line
  EXPECT_FALSE(std::filesystem::exists(out));
  const nlohmann::json j = read_json(report)["render"]["turntable"];
  ASSERT_EQ(j["cameras"].size(), 8u);
  const Eigen::Vector3d target = vec(j["cameras"][0]["target"]);
  const Eigen::Vector3d e0 = vec(j["cameras"][0]["eye"]) - target;
  for (int i = 0; i < 8; ++i) {
    const auto frame = dir_ / fmt::format("t-{:04d}.png", i + 1);
    ASSERT_TRUE(std::filesystem::exists(frame)) << frame;
    const Mask m = alpha_mask(read_png(frame));
    EXPECT_GT(m.covered, 0);
    // Every frame inside the image, the widest one filling about 0.9.
    EXPECT_GT(m.x0, 0);
    EXPECT_GT(m.y0, 0);
    EXPECT_LT(m.x1, m.w - 1);
    EXPECT_LT(m.y1, m.h - 1);
    const nlohmann::json& c = j["cameras"][i];
    EXPECT_TRUE(vec(c["target"]).isApprox(target));
    const Eigen::Vector3d e = vec(c["eye"]) - target;
    // Same height along +z and distance; turned by 45° i about +z.
    EXPECT_NEAR(e.z(), e0.z(), 1e-9);
    EXPECT_NEAR(e.norm(), e0.norm(), 1e-9);
    const double turn = std::atan2(e0.x() * e.y() - e0.y() * e.x(), e0.x() * e.x() + e0.y() * e.y());
    EXPECT_NEAR(std::remainder(turn - 2 * M_PI * i / 8, 2 * M_PI), 0, 1e-9) << i;
  }
  // A contact sheet: the same frames in a 3×3 grid, the ninth cell background.
  const auto sheet = dir_ / "sheet.png";
  ASSERT_EQ(quadrix_run("render --backend cpu " + q(model) + " -o " + q(sheet) +
                        " --size 64x48 --up +z --turntable 8 --contact-sheet --background none --quiet").code, 0);
  const Image8 s = read_png(sheet);
  ASSERT_EQ(s.width, 3 * 64);
  ASSERT_EQ(s.height, 3 * 48);
  for (int i = 0; i < 9; ++i) {
    const int cx = (i % 3) * 64, cy = (i / 3) * 48;
    bool same = true;
    if (i < 8) {
      const Image8 f = read_png(dir_ / fmt::format("t-{:04d}.png", i + 1));
      for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) same &= std::equal(f.pixel(x, y), f.pixel(x, y) + 4, s.pixel(cx + x, cy + y));
    } else {
      for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) same &= s.pixel(cx + x, cy + y)[3] == 0;
    }
    EXPECT_TRUE(same) << "cell " << i;
  }
  EXPECT_EQ(quadrix_run("render --backend cpu " + q(model) + " -o " + q(sheet) + " --contact-sheet").code, 2);
}

// An open surface fitted from points without normals, seen from behind by the default view: a
// bowl opening towards +z, whose estimated normals face away from its centroid (down, out of the
// bowl). SLIM's blend draws the side its normals face only, so the default view into the bowl
// rendered an empty image with exit 0 (--no-cull too). Now the view turns round to a side that
// shows it, says so, and the report records the angles used; typed angles are kept.
TEST_F(CliCamera, AnOpenSurfaceSeenFromBehindTurnsTheDefaultView) {
  {
    std::ofstream f(dir_ / "bowl.xyz");
    for (int i = 0; i < 60; ++i)
      for (int j = 0; j < 60; ++j) {
        const double x = -1 + 2 * (i + 0.5 * (j % 2)) / 60.0, y = -1 + 2 * j / 60.0;
        f << x << ' ' << y << ' ' << 0.5 * (x * x + y * y) << '\n';
      }
  }
  const auto model = dir_ / "bowl.qxm";
  ASSERT_EQ(quadrix_run("fit " + q(dir_ / "bowl.xyz") + " -o " + q(model) + " --max-error 1e-2 --quiet").code, 0);
  const CmdResult r = quadrix_run("render --backend cpu " + q(model) + " -o " + q(dir_ / "b.png") +
                                  " --size 64 --background none --report " + q(dir_ / "b.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("nothing of the scene is seen from the default view"), std::string::npos) << r.out;
  const Mask m = alpha_mask(read_png(dir_ / "b.png"));
  EXPECT_GT(m.covered, 64 * 64 / 4);
  const auto framing = read_json(dir_ / "b.json")["render"]["framing"];
  EXPECT_FALSE(framing["azimuth_deg"].get<double>() == 30.0 && framing["elevation_deg"].get<double>() == 20.0)
      << framing.dump();
  const auto [typed, json] = render(model, "--azimuth 30 --elevation 20", "typed");
  EXPECT_EQ(typed.covered, 0) << "typed angles are the user's: the bowl from behind";
  EXPECT_EQ(json["framing"]["azimuth_deg"].get<double>(), 30.0);
}
