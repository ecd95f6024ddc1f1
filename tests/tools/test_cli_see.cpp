// Seeing the error and finding the iso-value: fit's per-patch measured_error column,
// `render --colour-by error|patch|normal|depth` with its colour bar, `render --points`, and
// `info VOLUME` / `convert volume` without --iso (Otsu's threshold).
#include <gtest/gtest.h>

#include "tests/support.h"
#include "tests/tools/cli_support.h"

#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <set>

#include <nlohmann/json.hpp>

#include "core/camera.h"
#include "core/colour_map.h"
#include "core/image.h"
#include "core/model_io.h"

using namespace quadrix;
using test_support::CmdResult;
using test_support::q;
using test_support::quadrix_run;
using test_support::read_json;

namespace {
Eigen::Vector3d vec(const nlohmann::json& v) { return {v.at(0).get<double>(), v.at(1).get<double>(), v.at(2).get<double>()}; }

Camera camera_of(const nlohmann::json& c) {
  Camera cam;
  cam.eye = vec(c["eye"]);
  cam.target = vec(c["target"]);
  cam.up = vec(c["up"]);
  cam.fov_y_deg = c["fov_y_deg"].get<double>();
  cam.width = c["width"].get<int>();
  cam.height = c["height"].get<int>();
  cam.near_plane = c["near"].get<double>();
  cam.far_plane = c["far"].get<double>();
  return cam;
}

// Pixel (column, row) where p projects.
std::pair<int, int> project(const Camera& cam, const Eigen::Vector3d& p) {
  const Eigen::Vector4d c = cam.projection() * cam.view() * p.homogeneous();
  return {int(std::floor((c.x() / c.w() + 1) * 0.5 * cam.width)), int(std::floor((1 - c.y() / c.w()) * 0.5 * cam.height))};
}

double luminance(const std::uint8_t* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }
int max_diff(const std::uint8_t* a, const std::uint8_t* b) {
  return std::max({std::abs(a[0] - b[0]), std::abs(a[1] - b[1]), std::abs(a[2] - b[2])});
}

// Four planar SLIM patches z = 0 facing +z, apart (no blending), at x = −3, −1, 1, 3.
constexpr double kXs[4] = {-3, -1, 1, 3};
Model planes(const std::array<std::optional<double>, 4>& errors) {
  Model m;
  for (int i = 0; i < 4; ++i) {
    SlimPatch s;
    s.centre = {kXs[i], 0, 0};
    s.radius = 0.9;
    s.local = Quadric::from_coefficients({0, 0, 0, 0, 0, 0, 0, 0, 1, 0});  // g(u) = u_z
    s.measured_error = errors[std::size_t(i)];
    m.slims.push_back(s);
  }
  return m;
}
}  // namespace

class CliSee : public test_support::TempDir {
protected:
  /// Renders; returns the image and the report's render section, or nothing (GL missing: skipped by the caller).
  std::optional<std::pair<Image8, nlohmann::json>> render(const std::filesystem::path& model, const std::string& backend,
                                                          const std::string& options, const std::string& name,
                                                          int expect = 0) {
    const auto png = dir_ / (name + ".png"), report = dir_ / (name + ".json");
    const CmdResult r = quadrix_run("render --backend " + backend + " " + q(model) + " -o " + q(png) +
                                    " --size 200x160 --quiet --report " + q(report) + " " + options);
    if (backend == "gl" && r.code == 6) return std::nullopt;
    EXPECT_EQ(r.code, expect) << options << ": " << r.out;
    if (r.code != 0) return std::nullopt;
    return std::pair(read_png(png), read_json(report)["render"]);
  }
};

TEST_F(CliSee, ColourByPatchGivesEachPatchItsColourOnGlAndCpu) {
  const auto model = dir_ / "h.qxm";
  ASSERT_EQ(quadrix_run("synth hyperboloid1 --resolution 3 -o " + q(model)).code, 0);
  const auto cpu = render(model, "cpu", "--colour-by patch --background none", "cpu");
  ASSERT_TRUE(cpu);
  const auto plain = render(model, "cpu", "--background none", "plain");
  ASSERT_TRUE(plain);
  // Distinct colours: hues of the covered pixels fall into many bins (the plain model is grey).
  const auto hues = [](const Image8& img) {
    std::set<int> bins;
    for (std::size_t i = 0; i < img.rgba.size(); i += 4) {
      const std::uint8_t* p = &img.rgba[i];
      const int mx = std::max({p[0], p[1], p[2]}), mn = std::min({p[0], p[1], p[2]});
      if (p[3] == 0 || mx - mn < 40) continue;
      double h = mx == p[0] ? double(p[1] - p[2]) / (mx - mn) : mx == p[1] ? 2.0 + double(p[2] - p[0]) / (mx - mn)
                                                                            : 4.0 + double(p[0] - p[1]) / (mx - mn);
      bins.insert(int(std::floor((h < 0 ? h + 6 : h) * 4)));  // 24 hue bins
    }
    return bins.size();
  };
  EXPECT_GE(hues(cpu->first), 8u);
  EXPECT_LE(hues(plain->first), 2u);  // the model's own colour: one hue
  const auto gl = render(model, "gl", "--colour-by patch --background none", "gl");
  if (!gl) GTEST_SKIP() << "no OpenGL context";
  // GL == CPU: covered pixels agree in colour but for a thin band at patch borders.
  std::size_t both = 0, same = 0;
  for (std::size_t i = 0; i < cpu->first.rgba.size(); i += 4) {
    if (cpu->first.rgba[i + 3] == 0 || gl->first.rgba[i + 3] == 0) continue;
    ++both;
    same += max_diff(&cpu->first.rgba[i], &gl->first.rgba[i]) <= 8;
  }
  ASSERT_GT(both, 5000u);
  EXPECT_GE(double(same) / double(both), 0.97) << same << " of " << both;
}

TEST_F(CliSee, ErrorColoursRiseWithTheStoredErrorAndTheBarShowsTheRange) {
  const auto model = dir_ / "planes.qxm";
  const std::array<std::optional<double>, 4> errors = {0.1, 0.4, std::nullopt, 0.2};
  write_model(planes(errors), model);
  ASSERT_EQ(read_model(model).slims[1].measured_error, 0.4);  // the column round-trips
  ASSERT_FALSE(read_model(model).slims[2].measured_error);
  std::optional<Image8> first;
  for (const std::string backend : {"cpu", "gl"}) {
    const auto r = render(model, backend, "--view front --colour-by error", backend);
    if (!r) continue;  // no GL here
    const auto& [img, j] = *r;
    EXPECT_EQ(j["colour_by"]["source"], "measured_error");
    EXPECT_EQ(j["colour_by"]["range"][0].get<double>(), 0.1);
    EXPECT_EQ(j["colour_by"]["range"][1].get<double>(), 0.4);
    const Camera cam = camera_of(j["camera"]);
    double lum[4];
    for (int i = 0; i < 4; ++i) {
      const auto [x, y] = project(cam, {kXs[i], 0.3, 0});
      lum[i] = luminance(img.pixel(x, y));
    }
    EXPECT_LT(lum[0], lum[3]) << backend;  // 0.1 < 0.2
    EXPECT_LT(lum[3], lum[1]) << backend;  // 0.2 < 0.4
    const auto [gx, gy] = project(cam, {kXs[2], 0.3, 0});  // no value: grey
    const std::uint8_t* g = img.pixel(gx, gy);
    EXPECT_LE(std::abs(g[0] - g[1]) + std::abs(g[1] - g[2]), 2) << backend;
    // The bar: the map's ends, unlit, near the right edge, the high end above the low one.
    const Rgb top = scalar_colour(1.0), bottom = scalar_colour(0.0);
    int top_row = -1, bottom_row = -1;
    for (int y = 0; y < img.height; ++y)
      for (int x = img.width * 4 / 5; x < img.width; ++x) {
        const std::uint8_t* p = img.pixel(x, y);
        if (max_diff(p, top.data()) <= 6 && top_row < 0) top_row = y;
        if (max_diff(p, bottom.data()) <= 6) bottom_row = y;
      }
    EXPECT_GE(top_row, 0) << backend;
    EXPECT_GT(bottom_row, top_row + img.height / 3) << backend;
    if (!first) first = img;
    else {
      // GL and CPU agree at the patch centres.
      for (int i = 0; i < 4; ++i) {
        const auto [x, y] = project(cam, {kXs[i], 0.3, 0});
        EXPECT_LE(max_diff(first->pixel(x, y), img.pixel(x, y)), 6) << "patch " << i;
      }
    }
  }
  // Without the column and without --points: a usage error naming the way out.
  const auto bare = dir_ / "bare.qxm";
  write_model(planes({std::nullopt, std::nullopt, std::nullopt, std::nullopt}), bare);
  const CmdResult r = quadrix_run("render --backend cpu " + q(bare) + " -o " + q(dir_ / "x.png") + " --colour-by error");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--points"), std::string::npos) << r.out;
}

TEST_F(CliSee, ErrorMeasuredAgainstPointsFollowsTheirDistance) {
  const auto model = dir_ / "planes.qxm";
  write_model(planes({std::nullopt, std::nullopt, std::nullopt, std::nullopt}), model);
  // Points with normals above each plane at heights 0.02, 0.08, 0.04, 0.01.
  const double height[4] = {0.02, 0.08, 0.04, 0.01};
  const auto pts = dir_ / "p.xyz";
  {
    std::ofstream out(pts);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.4, 0.4);
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 40; ++k) out << kXs[i] + u(rng) << ' ' << u(rng) << ' ' << height[i] << " 0 0 1\n";
  }
  const auto r = render(model, "cpu", "--view front --colour-by error --points " + q(pts) + " --point-size 0.5", "pts");
  ASSERT_TRUE(r);
  const auto& [img, j] = *r;
  EXPECT_EQ(j["colour_by"]["source"].get<std::string>(), "points");
  EXPECT_NEAR(j["colour_by"]["range"][0].get<double>(), 0.01, 1e-9);
  EXPECT_NEAR(j["colour_by"]["range"][1].get<double>(), 0.08, 1e-9);
  const Camera cam = camera_of(j["camera"]);
  double lum[4];
  for (int i = 0; i < 4; ++i) {
    const auto [x, y] = project(cam, {kXs[i], 0.7, 0});  // away from the splats
    lum[i] = luminance(img.pixel(x, y));
  }
  EXPECT_LT(lum[3], lum[0]);
  EXPECT_LT(lum[0], lum[2]);
  EXPECT_LT(lum[2], lum[1]);
}

TEST_F(CliSee, PointsAppearWhereTheyProjectAndHideBehindTheSurface) {
  const auto model = dir_ / "planes.qxm";
  write_model(planes({std::nullopt, std::nullopt, std::nullopt, std::nullopt}), model);
  const auto pts = dir_ / "p.xyz";
  const Eigen::Vector3d front(-3, 0.2, 0.001), behind(1, 0.2, -0.5), free_point(0, 0.2, 0.0);
  {
    std::ofstream out(pts);
    for (const auto& p : {front, behind, free_point}) out << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  }
  const Rgb splat{230, 30, 30};
  for (const std::string backend : {"cpu", "gl"}) {
    const auto r = render(model, backend, "--view front --points " + q(pts) + " --point-size 2", "pts" + backend);
    if (!r) continue;
    const auto& [img, j] = *r;
    const Camera cam = camera_of(j["camera"]);
    const auto at = [&](const Eigen::Vector3d& p) {
      const auto [x, y] = project(cam, p);
      return img.pixel(x, y);
    };
    EXPECT_EQ(max_diff(at(front), splat.data()), 0) << backend;
    EXPECT_EQ(max_diff(at(free_point), splat.data()), 0) << backend;  // over the background between patches
    EXPECT_GT(max_diff(at(behind), splat.data()), 60) << backend;     // behind the patch at x = 1
    // Nowhere else: the splats cover a few pixels each.
    std::size_t red = 0;
    for (std::size_t i = 0; i < img.rgba.size(); i += 4) red += max_diff(&img.rgba[i], splat.data()) == 0;
    EXPECT_GE(red, 2u);
    EXPECT_LE(red, 2u * 16u);
    EXPECT_EQ(j["points"]["drawn"].get<int>(), 2);
    EXPECT_EQ(j["points"]["hidden"].get<int>(), 1);
  }
}

TEST_F(CliSee, NormalAndDepthColouringsAreTheEncodedValues) {
  const auto model = dir_ / "planes.qxm";
  write_model(planes({std::nullopt, std::nullopt, std::nullopt, std::nullopt}), model);
  const auto n = render(model, "cpu", "--view front --colour-by normal", "n");
  ASSERT_TRUE(n);
  const Camera cam = camera_of(n->second["camera"]);
  const auto [x, y] = project(cam, {-1, 0.3, 0});
  const Rgb expected = normal_colour(Eigen::Vector3f(0, 0, 1));
  EXPECT_LE(max_diff(n->first.pixel(x, y), expected.data()), 1);
  // Depth: the nearer side of a tilted view reads darker (low end of the map).
  const auto d = render(model, "cpu", "--azimuth 40 --elevation 0 --colour-by depth", "d");
  ASSERT_TRUE(d);
  const Camera c2 = camera_of(d->second["camera"]);
  const auto [ax, ay] = project(c2, {3.0, 0.3, 0});   // nearer the eye (azimuth towards +x)
  const auto [bx, by] = project(c2, {-3.0, 0.3, 0});
  EXPECT_LT(luminance(d->first.pixel(ax, ay)), luminance(d->first.pixel(bx, by)));
  const auto range = d->second["colour_by"]["range"];
  EXPECT_LT(range[0].get<double>(), range[1].get<double>());
}

TEST_F(CliSee, FitStoresEachPatchsMeasuredError) {
  // A sphere of radius 1 with exact normals.
  const auto pts = dir_ / "s.xyz";
  {
    std::ofstream out(pts);
    std::mt19937 rng(7);
    std::normal_distribution<double> g;
    for (int i = 0; i < 3000; ++i) {
      Eigen::Vector3d p(g(rng), g(rng), g(rng));
      p.normalize();
      out << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
  }
  const auto model = dir_ / "s.qxm", report = dir_ / "fit.json";
  const CmdResult r = quadrix_run("fit " + q(pts) + " -o " + q(model) + " --max-error 2e-3 --quiet --report " + q(report));
  ASSERT_EQ(r.code, 0) << r.out;
  const Model m = read_model(model);
  const auto j = read_json(report)["fit"];
  std::size_t with = 0;
  double max = 0;
  for (const auto& s : m.slims)
    if (s.measured_error) ++with, max = std::max(max, *s.measured_error);
  EXPECT_GE(double(with), 0.9 * double(m.slims.size()));
  EXPECT_EQ(j["patch_errors"]["measured_patches"].get<std::size_t>(), with);
  // The per-patch maximum is the fit's measured points-side maximum.
  EXPECT_NEAR(max, j["measured_max_abs"].get<double>(), 1e-12);
  EXPECT_LE(max, j["max_error_abs"].get<double>());
  EXPECT_GT(max, 0);
}

// A coloured scan through the command line: a PLY with red/green/blue on its vertices (a bumpy
// sphere, red on its upper half, blue on its lower; normals estimated), every patch of the model
// coloured by the points in its ball, the colours in the file.
TEST_F(CliSee, FitCarriesAScansColoursIntoItsPatches) {
  const auto pts = dir_ / "c.ply";
  {
    std::mt19937 rng(9);
    std::normal_distribution<double> g;
    std::ostringstream body;
    const int n = 6000;
    for (int i = 0; i < n; ++i) {
      Eigen::Vector3d p(g(rng), g(rng), g(rng));
      p.normalize();
      p *= 1.0 + 0.08 * std::sin(7 * p.x()) * std::sin(7 * p.y()) * std::sin(7 * p.z());
      body << p.x() << ' ' << p.y() << ' ' << p.z() << (p.z() > 0 ? " 220 30 30\n" : " 30 30 220\n");
    }
    std::ofstream out(pts);
    out << "ply\nformat ascii 1.0\nelement vertex " << n
        << "\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\nproperty uchar green\n"
           "property uchar blue\nend_header\n"
        << body.str();
  }
  const auto model = dir_ / "c.qxm";
  const CmdResult r = quadrix_run("fit " + q(pts) + " -o " + q(model) + " --max-error 2e-3 --allow-exceed --quiet");
  ASSERT_EQ(r.code, 0) << r.out;
  const Model m = read_model(model);
  ASSERT_GT(m.slims.size(), 20u);
  int upper = 0, lower = 0;
  for (const auto& s : m.slims) {
    ASSERT_TRUE(s.colour.has_value());
    const Rgb c = *s.colour;
    if (s.centre.z() > 0.5) {
      ++upper;
      EXPECT_GT(c[0], 200) << s.centre.transpose();
    }
    if (s.centre.z() < -0.5) {
      ++lower;
      EXPECT_GT(c[2], 200) << s.centre.transpose();
    }
  }
  EXPECT_GT(upper, 5);
  EXPECT_GT(lower, 5);
}

TEST_F(CliSee, InfoOnAVolumeSuggestsOtsusThreshold) {
  // Two levels: 10 in the lower half (z < 10), 200 above, a 20³ uint8 raw file: every boundary
  // between the two values splits the classes alike, so Otsu's threshold is the midpoint 105.
  const auto raw = dir_ / "two.raw";
  {
    std::ofstream out(raw, std::ios::binary);
    for (int z = 0; z < 20; ++z)
      for (int i = 0; i < 400; ++i) out.put(char(z < 10 ? 10 : 200));
  }
  const CmdResult r = quadrix_run("info " + q(raw) + " --dims 20,20,20 --type uint8 --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(j["dims"], nlohmann::json({20, 20, 20}));
  EXPECT_EQ(j["type"], "uint8");
  EXPECT_EQ(j["min"].get<double>(), 10);
  EXPECT_EQ(j["max"].get<double>(), 200);
  EXPECT_EQ(j["percentiles"]["50"].get<double>(), 10);
  EXPECT_EQ(j["percentiles"]["75"].get<double>(), 200);
  const double bin = 190.0 / 256;
  EXPECT_EQ(j["suggested_iso"][0]["method"], "otsu");
  EXPECT_NEAR(j["suggested_iso"][0]["iso"].get<double>(), 105.0, bin);
  EXPECT_DOUBLE_EQ(j["suggested_iso"][0]["fraction_below"].get<double>(), 0.5);
  std::size_t total = 0;
  for (const auto& c : j["histogram"]["counts"]) total += c.get<std::size_t>();
  EXPECT_EQ(total, 8000u);
  // convert volume without --iso uses it and says so.
  const auto model = dir_ / "two.qxm", report = dir_ / "conv.json";
  const CmdResult c = quadrix_run("convert volume " + q(raw) + " --dims 20,20,20 --type uint8 -o " + q(model) +
                                  " --report " + q(report));
  ASSERT_EQ(c.code, 0) << c.out;
  EXPECT_NE(c.out.find("Otsu"), std::string::npos) << c.out;
  const auto cj = read_json(report)["convert"];
  EXPECT_EQ(cj["iso_source"], "otsu");
  EXPECT_NEAR(cj["iso"].get<double>(), 105.0, bin);
  EXPECT_GT(cj["tets"].get<int>(), 0);
  EXPECT_EQ(read_model(model).metadata.at("iso_source"), "otsu");
  // A constant volume: one line for its one value (16 rows "7 – 7" before), and no suggestion.
  const auto flat = dir_ / "flat.raw";
  {
    std::ofstream out(flat, std::ios::binary);
    for (int i = 0; i < 16 * 16 * 16; ++i) out.put(char(7));
  }
  const CmdResult t = quadrix_run("info " + q(flat) + " --dims 16,16,16 --type uint8");
  ASSERT_EQ(t.code, 0) << t.out;
  EXPECT_NE(t.out.find("histogram    every sample is 7\n"), std::string::npos) << t.out;
  std::size_t dashes = 0;  // the range's "7 – 7" only
  for (std::size_t at = t.out.find(" – "); at != std::string::npos; at = t.out.find(" – ", at + 1)) ++dashes;
  EXPECT_EQ(dashes, 1u) << t.out;
  EXPECT_NE(t.out.find("suggested iso none"), std::string::npos) << t.out;
}

TEST_F(CliSee, InfoOnMarschnerLobbPrintsTheSummary) {
  const auto vol = dir_ / "ml.nhdr";
  ASSERT_EQ(quadrix_run("synth marschner-lobb -o " + q(vol)).code, 0);
  const CmdResult t = quadrix_run("info " + q(vol));
  ASSERT_EQ(t.code, 0) << t.out;
  for (const char* s : {"volume 41x41x41 float", "range", "percentiles", "histogram", "suggested iso", "otsu", "otsu3-low"})
    EXPECT_NE(t.out.find(s), std::string::npos) << s << "\n" << t.out;
  const CmdResult r = quadrix_run("info " + q(vol) + " --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["samples"].get<int>(), 41 * 41 * 41);
  const double lo = j["min"].get<double>(), hi = j["max"].get<double>();
  EXPECT_GE(lo, 0.0);
  EXPECT_LE(hi, 1.0);
  double prev = lo;
  for (const char* p : {"1", "5", "25", "50", "75", "95", "99"}) {
    EXPECT_GE(j["percentiles"][p].get<double>(), prev) << p;  // non-decreasing
    prev = j["percentiles"][p].get<double>();
  }
  for (const auto& s : j["suggested_iso"]) {
    EXPECT_GT(s["iso"].get<double>(), lo);
    EXPECT_LT(s["iso"].get<double>(), hi);
  }
  // The three-class pair is ordered.
  EXPECT_LT(j["suggested_iso"][1]["iso"].get<double>(), j["suggested_iso"][2]["iso"].get<double>());
  // A raw file needs both --dims and --type.
  EXPECT_EQ(quadrix_run("info " + q(dir_ / "ml.raw") + " --dims 41,41,41").code, 2);
}
