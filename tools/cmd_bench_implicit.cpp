// quadrix bench implicit: adaptive marching points ([Singh10]) on the GL renderer for gallery
// surfaces, base step × root test → image error against the CPU reference's guaranteed roots
// (coverage mismatch, depth error) and ms/frame (shader compilation apart); in the same run
// POV-Ray renders the same surfaces with the same camera as `polynomial … sturm` (algebraic
// ones) and as `isosurface`, and its own images are measured against the same reference.
// Writes bench_implicit.csv, bench_implicit.json and bench_implicit.png.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <thread>

#include <fmt/format.h>

#include "bench/plot.h"
#include "core/atomic_file.h"
#include "core/camera.h"
#include "core/error.h"
#include "core/implicit/gallery.h"
#include "core/implicit/surface.h"
#include "core/log.h"
#include "core/primitive.h"
#include "core/reference.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tools/cli.h"

namespace quadrix::cli {
namespace {

namespace fs = std::filesystem;
using implicit::Expression;
using implicit::Node;
using implicit::Op;

// ---------------------------------------------------------------- image error

struct ImageError {
  double coverage_mismatch = 0;  ///< of pixels either image covers (outside the band): coverage differs
  double depth_error = 0;        ///< of pixels both cover (outside the band): |Δdepth| > 1e-4 of the depth range
  double depth_mean = 0;         ///< mean |Δdepth| / depth range over those pixels
  int covered = 0;               ///< pixels the reference covers
};

// The reference's 1-px silhouette band: a neighbour with another coverage or primitive, or a
// depth jump of more than 2 % (an inner silhouette).
std::vector<char> silhouette_band(const ReferenceImage& r) {
  std::vector<char> band(r.coverage.size(), 0);
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * r.width + x;
      for (int d = 0; d < 9 && !band[i]; ++d) {
        const int xx = std::clamp(x + d % 3 - 1, 0, r.width - 1), yy = std::clamp(y + d / 3 - 1, 0, r.height - 1);
        const std::size_t j = static_cast<std::size_t>(yy) * r.width + xx;
        band[i] = r.coverage[j] != r.coverage[i] || r.primitive[j] != r.primitive[i] ||
                  (r.coverage[i] && std::abs(r.depth[j] - r.depth[i]) > 0.02f * std::abs(r.depth[i]));
      }
    }
  return band;
}

ImageError image_error(const ReferenceImage& ref, const std::vector<char>& band, std::span<const std::uint8_t> coverage,
                       std::span<const float> depth) {
  ImageError e;
  float dmin = INFINITY, dmax = -INFINITY;
  for (std::size_t i = 0; i < ref.depth.size(); ++i)
    if (ref.coverage[i]) dmin = std::min(dmin, ref.depth[i]), dmax = std::max(dmax, ref.depth[i]);
  const double range = std::max(1e-30, double(dmax) - dmin);
  std::size_t either = 0, differ = 0, both = 0, far = 0;
  double sum = 0;
  for (std::size_t i = 0; i < ref.coverage.size(); ++i) {
    e.covered += ref.coverage[i] != 0;
    if (band[i] || !(ref.coverage[i] || coverage[i])) continue;
    ++either;
    differ += (ref.coverage[i] != 0) != (coverage[i] != 0);
    if (!(ref.coverage[i] && coverage[i])) continue;
    ++both;
    const double d = std::abs(double(depth[i]) - ref.depth[i]) / range;
    far += d > 1e-4;
    sum += d;
  }
  if (either) e.coverage_mismatch = double(differ) / either;
  if (both) e.depth_error = double(far) / both, e.depth_mean = sum / both;
  return e;
}

// ---------------------------------------------------------------- POV-Ray scenes

using Monomials = std::map<std::array<int, 3>, double>;

Monomials multiply(const Monomials& a, const Monomials& b) {
  Monomials out;
  for (const auto& [ea, ca] : a)
    for (const auto& [eb, cb] : b) out[{ea[0] + eb[0], ea[1] + eb[1], ea[2] + eb[2]}] += ca * cb;
  return out;
}

std::optional<double> constant_of(const Monomials& p) {
  if (p.empty()) return 0.0;
  if (p.size() == 1 && p.begin()->first == std::array<int, 3>{0, 0, 0}) return p.begin()->second;
  return std::nullopt;
}

// S as a polynomial in x, y, z (functions of constants folded), or nothing when it is not one.
std::optional<Monomials> polynomial(const Expression& e, std::span<const double> params) {
  std::vector<Monomials> v;
  v.reserve(e.nodes().size());
  for (const Node& n : e.nodes()) {
    Monomials p;
    const auto unary = [&](double (*f)(double)) -> bool {
      const auto c = constant_of(v[n.a]);
      if (!c) return false;
      p[{0, 0, 0}] = f(*c);
      return true;
    };
    switch (n.op) {
      case Op::constant: p[{0, 0, 0}] = n.value; break;
      case Op::parameter: p[{0, 0, 0}] = params[n.n]; break;
      case Op::x: p[{1, 0, 0}] = 1; break;
      case Op::y: p[{0, 1, 0}] = 1; break;
      case Op::z: p[{0, 0, 1}] = 1; break;
      case Op::add: case Op::sub:
        p = v[n.a];
        for (const auto& [k, c] : v[n.b]) p[k] += n.op == Op::add ? c : -c;
        break;
      case Op::neg:
        for (const auto& [k, c] : v[n.a]) p[k] = -c;
        break;
      case Op::mul: p = multiply(v[n.a], v[n.b]); break;
      case Op::div: {
        const auto c = constant_of(v[n.b]);
        if (!c || *c == 0) return std::nullopt;
        for (const auto& [k, x] : v[n.a]) p[k] = x / *c;
        break;
      }
      case Op::pow_int: {
        if (n.n < 0) return std::nullopt;
        p[{0, 0, 0}] = 1;
        for (int k = 0; k < n.n; ++k) p = multiply(p, v[n.a]);
        break;
      }
      case Op::cheb: {  // T_0 = 1, T_1 = e, T_k+1 = 2e·T_k − T_k−1
        Monomials t0{{{0, 0, 0}, 1.0}}, t1 = v[n.a];
        if (n.n == 0) { p = t0; break; }
        for (int k = 1; k < n.n; ++k) {
          Monomials t2 = multiply(v[n.a], t1);
          for (auto& [key, c] : t2) c *= 2;
          for (const auto& [key, c] : t0) t2[key] -= c;
          t0 = std::move(t1), t1 = std::move(t2);
        }
        p = t1;
        break;
      }
      case Op::sqrt: if (!unary([](double x) { return std::sqrt(x); })) return std::nullopt; break;
      case Op::sin: if (!unary([](double x) { return std::sin(x); })) return std::nullopt; break;
      case Op::cos: if (!unary([](double x) { return std::cos(x); })) return std::nullopt; break;
      case Op::exp: if (!unary([](double x) { return std::exp(x); })) return std::nullopt; break;
      case Op::log: if (!unary([](double x) { return std::log(x); })) return std::nullopt; break;
      default: return std::nullopt;
    }
    std::erase_if(p, [](const auto& kv) { return kv.second == 0; });
    v.push_back(std::move(p));
  }
  return v.back();
}

// S in POV-Ray's function syntax (log → ln, ^ → pow), or nothing for cheb (no recurrence there).
std::optional<std::string> pov_function(const Expression& e, std::span<const double> params) {
  std::vector<std::string> s;
  for (const Node& n : e.nodes()) {
    const auto a = [&] { return s[n.a]; };
    const auto b = [&] { return s[n.b]; };
    const auto f = [&](const char* name) { return fmt::format("{}({})", name, a()); };
    std::string t;
    switch (n.op) {
      case Op::constant: t = fmt::format("({:.17g})", n.value); break;
      case Op::parameter: t = fmt::format("({:.17g})", params[n.n]); break;
      case Op::x: t = "x"; break;
      case Op::y: t = "y"; break;
      case Op::z: t = "z"; break;
      case Op::add: t = fmt::format("({} + {})", a(), b()); break;
      case Op::sub: t = fmt::format("({} - {})", a(), b()); break;
      case Op::mul: t = fmt::format("({} * {})", a(), b()); break;
      case Op::div: t = fmt::format("({} / {})", a(), b()); break;
      case Op::neg: t = fmt::format("(-{})", a()); break;
      case Op::pow_int: t = fmt::format("pow({}, {})", a(), n.n); break;
      case Op::pow: t = fmt::format("pow({}, {})", a(), b()); break;
      case Op::log: t = f("ln"); break;
      case Op::min: t = fmt::format("min({}, {})", a(), b()); break;
      case Op::max: t = fmt::format("max({}, {})", a(), b()); break;
      case Op::sin: t = f("sin"); break;
      case Op::cos: t = f("cos"); break;
      case Op::tan: t = f("tan"); break;
      case Op::asin: t = f("asin"); break;
      case Op::acos: t = f("acos"); break;
      case Op::atan: t = f("atan"); break;
      case Op::exp: t = f("exp"); break;
      case Op::sqrt: t = f("sqrt"); break;
      case Op::abs: t = f("abs"); break;
      case Op::cosh: t = f("cosh"); break;
      case Op::sinh: t = f("sinh"); break;
      case Op::acosh: t = f("acosh"); break;
      case Op::cheb: return std::nullopt;
    }
    s.push_back(std::move(t));
  }
  return s.back();
}

std::string pov_vec(const Eigen::Vector3d& v) { return fmt::format("<{:.17g}, {:.17g}, {:.17g}>", v.x(), v.y(), v.z()); }

// The same pinhole as Camera::pixel_ray (POV-Ray takes direction + x·right + y·up literally);
// the surface is unlit and coloured by its depth along the view axis (red, 16 bits over
// [d0, d0 + range]) with blue marking coverage.
std::string pov_scene(const Camera& cam, const std::string& object, const Box3& box, double d0, double range) {
  const Eigen::Vector3d f = cam.forward();
  Eigen::Vector3d r = f.cross(cam.up).normalized();
  const Eigen::Vector3d u = r.cross(f);
  const double th = std::tan(cam.fov_y_deg * std::numbers::pi / 360.0);
  const double aspect = double(cam.width) / cam.height;
  return fmt::format(
      "#version 3.7;\nglobal_settings {{ assumed_gamma 1.0 }}\nbackground {{ rgb 0 }}\n"
      "camera {{ perspective location {} direction {} right {} up {} }}\n"
      "object {{ {}\n  clipped_by {{ box {{ {}, {} }} }} bounded_by {{ clipped_by }}\n"
      "  pigment {{ function {{ ((x - ({:.17g}))*({:.17g}) + (y - ({:.17g}))*({:.17g}) + (z - ({:.17g}))*({:.17g}) - "
      "({:.17g})) / ({:.17g}) }}\n    color_map {{ [0 rgb <0, 0, 1>] [1 rgb <1, 0, 1>] }} }}\n"
      "  finish {{ ambient 0 diffuse 0 emission 1 }} }}\n",
      pov_vec(cam.eye), pov_vec(f), pov_vec(2 * th * aspect * r), pov_vec(2 * th * u), object, pov_vec(box.min),
      pov_vec(box.max), cam.eye.x(), f.x(), cam.eye.y(), f.y(), cam.eye.z(), f.z(), d0, range);
}

struct PovImage {
  std::vector<std::uint8_t> coverage;
  std::vector<float> depth;
};

// A 16-bit binary PPM as POV-Ray writes it (+FP16; comments in the header).
PovImage read_pov_ppm(const fs::path& path, int w, int h, double d0, double range) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::size_t i = 0;
  std::vector<std::string> tok;
  while (tok.size() < 4 && i < bytes.size()) {
    if (std::isspace(static_cast<unsigned char>(bytes[i]))) { ++i; continue; }
    if (bytes[i] == '#') { while (i < bytes.size() && bytes[i] != '\n') ++i; continue; }
    const std::size_t j = i;
    while (i < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
    tok.push_back(bytes.substr(j, i - j));
  }
  ++i;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  if (tok.size() != 4 || tok[0] != "P6" || tok[1] != std::to_string(w) || tok[2] != std::to_string(h) ||
      tok[3] != "65535" || bytes.size() < i + 6 * n)
    throw Error(fmt::format("bench implicit: {} is not the {}x{} 16-bit PPM POV-Ray was asked for", path.string(), w, h));
  PovImage img{std::vector<std::uint8_t>(n), std::vector<float>(n, INFINITY)};
  const auto at = [&](std::size_t k) {
    return (static_cast<unsigned char>(bytes[i + 2 * k]) << 8) | static_cast<unsigned char>(bytes[i + 2 * k + 1]);
  };
  for (std::size_t k = 0; k < n; ++k) {
    img.coverage[k] = at(3 * k + 2) > 32768;
    if (img.coverage[k]) img.depth[k] = static_cast<float>(d0 + range * at(3 * k) / 65535.0);
  }
  return img;
}

struct PovRun {
  bool ran = false, timed_out = false;
  double seconds = 0;
  std::string error;
  PovImage image;
};

PovRun run_povray(const std::string& povray, const fs::path& dir, const std::string& name, const std::string& scene,
                  const Camera& cam, double d0, double range, int threads, double timeout_s) {
  PovRun r;
  const fs::path pov = dir / (name + ".pov"), ppm = dir / (name + ".ppm"), log = dir / (name + ".log");
  std::ofstream(pov) << scene;
  fs::remove(ppm);
  const std::string cmd = fmt::format(
      "timeout {:.0f} {} -D +I'{}' +O'{}' +W{} +H{} +FP16 File_Gamma=1.0 -A +WT{} > '{}' 2>&1", timeout_s, povray,
      pov.string(), ppm.string(), cam.width, cam.height, threads, log.string());
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  if (code == 124) {
    r.timed_out = true;
    r.error = fmt::format("timed out after {:.0f} s", timeout_s);
    return r;
  }
  if (code != 0 || !fs::exists(ppm)) {
    r.error = fmt::format("povray exit {} (see {})", code, log.string());
    return r;
  }
  r.image = read_pov_ppm(ppm, cam.width, cam.height, d0, range);
  r.ran = true;
  return r;
}

// The largest |∇S| on a 24³ lattice of the bounds, for POV-Ray's isosurface max_gradient.
double max_gradient(const implicit::CompiledImplicit& c) {
  double g = 0;
  const int n = 24;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      for (int k = 0; k <= n; ++k) {
        const Eigen::Vector3d t(double(i) / n, double(j) / n, double(k) / n);
        const Eigen::Vector3d p = c.bounds.min + t.cwiseProduct(c.bounds.max - c.bounds.min);
        const double v = c.expression.value_gradient(p, c.parameters).gradient.norm();
        if (std::isfinite(v)) g = std::max(g, v);
      }
  return g;
}

// ---------------------------------------------------------------- the run

struct Row {
  std::string surface, method, test;
  double step_divisions = 0, step = 0;
  double remainder = -1;  // κ of the AMP remainder test (−1: not AMP)
  ImageError error;
  double ms_frame = 0, compile_ms = 0;
  std::string note;
};

std::vector<std::string> default_surfaces() {
  // The algebraic gallery surfaces of order ≤ 8 and the Barth decic.
  std::vector<std::string> out;
  for (const auto& g : implicit::gallery()) {
    const auto c = implicit::compile(g.surface);
    const auto p = polynomial(c.expression, c.parameters);
    if (!p) continue;
    int order = 0;
    for (const auto& [k, v] : *p) order = std::max(order, k[0] + k[1] + k[2]);
    if (order <= 8 || g.name == "barth-decic") out.push_back(g.name);
  }
  return out;
}

Image8 draw_plot(const std::vector<Row>& rows) {
  PlotPanel time{"MS PER FRAME AGAINST IMAGE ERROR", "COVERAGE MISMATCH + DEPTH ERROR SHARE", {}};
  const std::array<Rgb, 8> colours{Rgb{31, 119, 180}, Rgb{255, 127, 14}, Rgb{44, 160, 44}, Rgb{214, 39, 40},
                                   Rgb{148, 103, 189}, Rgb{140, 86, 75}, Rgb{227, 119, 194}, Rgb{23, 190, 207}};
  std::map<std::string, PlotSeries> series;
  int next = 0;
  for (const Row& r : rows) {
    if (!r.note.empty()) continue;
    const std::string key = r.method == "amp" ? "AMP " + r.test : r.method;
    auto [it, fresh] = series.try_emplace(key);
    if (fresh) {
      it->second.label = key;
      it->second.colour = colours[next++ % colours.size()];
      it->second.style = PlotStyle::markers;
    }
    // An exact image plots at 1e-6 so it stays on the log axis.
    it->second.x.push_back(std::max(1e-6, r.error.coverage_mismatch + r.error.depth_error));
    it->second.y.push_back(r.ms_frame);
  }
  for (auto& [k, s] : series) time.series.push_back(std::move(s));
  const PlotPanel panels[] = {time};
  return plot_log_log(panels, {.panel_width = 900, .panel_height = 640});
}

}  // namespace

void add_bench_implicit(CLI::App& bench, Commands& commands) {
  auto* app = bench.add_subcommand(
      "implicit", "Implicit surfaces: AMP step × root test against the reference, beside POV-Ray poly/sturm and isosurface");
  struct Args {
    std::vector<std::string> surfaces;
    std::vector<double> divisions{100, 200, 400, 800};
    std::vector<std::string> tests{"sign", "taylor"};
    std::vector<double> remainders{render::AmpOptions{}.remainder};
    std::string out = ".";
    std::string context = "auto";
    int size = 512;
    int frames = 3;
    std::string povray = "povray";
    int pov_threads = 2;
    double pov_timeout = 120;
  };
  auto a = std::make_shared<Args>();
  app->add_option("--surfaces", a->surfaces,
                  "Gallery surfaces (default: the algebraic ones of order <= 8 and barth-decic)")
      ->delimiter(',')
      ->default_str("");
  app->add_option("--divisions", a->divisions, "Base steps b = bounds diagonal / each of these")
      ->delimiter(',')
      ->check(number({.lo = 1, .hi = 1e6}))
      ->capture_default_str();
  app->add_option("--tests", a->tests, "Root tests to run (sign, taylor)")
      ->delimiter(',')
      ->check(CLI::IsMember({"sign", "taylor"}))
      ->capture_default_str();
  app->add_option("--remainders", a->remainders, "Remainder factors of the AMP step test (0: off) to run")
      ->delimiter(',')
      ->check(number({.lo = 0, .hi = 1e3}))
      ->capture_default_str();
  app->add_option("--out", a->out, "Folder for bench_implicit.{csv,json,png} and the POV-Ray scenes")
      ->capture_default_str();
  app->add_option("--context", a->context, "GL context")->check(CLI::IsMember(render::context_names()))->capture_default_str();
  app->add_option("--size", a->size, "Image side, pixels")->check(number({.lo = 16, .hi = 4096}))->capture_default_str();
  app->add_option("--frames", a->frames, "Timed frames per configuration (median)")
      ->check(number({.lo = 1, .hi = 1000}))
      ->capture_default_str();
  app->add_option("--povray", a->povray, "POV-Ray executable; 'off' skips it")->capture_default_str();
  app->add_option("--pov-threads", a->pov_threads, "POV-Ray render threads (+WT)")
      ->check(number({.lo = 1, .hi = 256}))
      ->capture_default_str();
  app->add_option("--pov-timeout", a->pov_timeout, "Seconds before a POV-Ray render is given up")
      ->check(number({.lo = 1, .hi = 86400}))
      ->capture_default_str();
  commands.push_back({app, [a](const CommonOptions& common, Report& report) {
    const fs::path out_dir(a->out);
    std::error_code ec;
    fs::create_directories(out_dir / "povray", ec);
    if (ec) throw IoError(fmt::format("bench implicit: cannot create {}: {}", out_dir.string(), ec.message()));
    std::vector<implicit::GalleryEntry> entries;
    for (const auto& name : a->surfaces.empty() ? default_surfaces() : a->surfaces) {
      try {
        entries.push_back(implicit::gallery_surface(name));
      } catch (const InvalidInput& e) {
        throw CLI::ValidationError("--surfaces", e.what());
      }
    }
    const bool pov = a->povray != "off";
    if (pov && std::system(fmt::format("{} --version > /dev/null 2>&1", a->povray).c_str()) != 0)
      throw InvalidInput(fmt::format("bench implicit: cannot run '{}' (install Debian's povray, or --povray off)",
                                     a->povray));
    auto context = render::create_context(a->context, {.width = a->size, .height = a->size});
    render::Renderer renderer(*context);
    nlohmann::json j = {{"size", a->size},
                        {"frames", a->frames},
                        {"context", context->description()},
                        {"threads", std::thread::hardware_concurrency()},
                        {"povray_threads", a->pov_threads},
                        {"surfaces", nlohmann::json::object()}};
    std::vector<Row> rows;
    Progress progress("bench implicit", progress_allowed(common));
    std::size_t done = 0;
    for (const auto& g : entries) {
      Model m;
      m.implicits.push_back(g.surface);
      const Camera cam = frame_box(g.surface.bounds, {.azimuth_deg = 40, .elevation_deg = 25, .width = a->size,
                                                      .height = a->size});
      log::info("bench implicit: {}: reference", g.name);
      const auto t0 = std::chrono::steady_clock::now();
      const ReferenceImage ref = render_reference(ReferenceScene(m), cam);
      const double ref_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const std::vector<char> band = silhouette_band(ref);
      nlohmann::json js = {{"description", g.description}, {"expression", g.surface.expression},
                           {"gallery_test", g.test},       {"reference_seconds", ref_s},
                           {"reference_covered", std::count(ref.coverage.begin(), ref.coverage.end(), 1)}};
      const double diagonal = g.surface.bounds.diagonal();
      std::optional<double> best_amp_ms;
      for (const std::string& test : a->tests)
        for (double div : a->divisions)
          for (double kappa : a->remainders) {
          render::AmpOptions o;
          o.step_divisions = div;
          o.remainder = kappa;
          o.test = test == "taylor" ? render::RootTest::taylor : render::RootTest::sign;
          const auto c0 = std::chrono::steady_clock::now();
          renderer.set_model(m, o);
          const double first = renderer.draw(cam, {}).ms_total;
          const double set_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - c0).count();
          std::vector<double> ms;
          for (int f = 0; f < a->frames; ++f) ms.push_back(renderer.draw(cam, {}).ms_total);
          std::sort(ms.begin(), ms.end());
          const render::GBuffer gb = renderer.read_gbuffer();
          Row r;
          r.surface = g.name, r.method = "amp", r.test = test, r.step_divisions = div, r.step = diagonal / div;
          r.remainder = kappa;
          r.ms_frame = ms[ms.size() / 2];
          // Program generation and compile, plus the driver's JIT in the first frame.
          r.compile_ms = std::max(0.0, set_ms - r.ms_frame);
          r.error = image_error(ref, band, gb.coverage, gb.depth);
          log::info("bench implicit: {} AMP {} b = d/{:g} κ = {:g}: {:.1f} ms, mismatch {:.4f}, depth {:.4f} (first {:.0f} ms)",
                    g.name, test, div, kappa, r.ms_frame, r.error.coverage_mismatch, r.error.depth_error, first);
          if (r.error.coverage_mismatch <= 0.005 && r.error.depth_error <= 0.005)
            best_amp_ms = std::min(best_amp_ms.value_or(INFINITY), r.ms_frame);
          rows.push_back(r);
        }
      js["amp_best_ms_within_0_5_percent"] = best_amp_ms ? nlohmann::json(*best_amp_ms) : nlohmann::json(nullptr);
      if (pov) {
        const implicit::CompiledImplicit c = implicit::compile(g.surface);
        // Depth along the view axis over the bounds' corners, for the colour encoding.
        double dlo = INFINITY, dhi = -INFINITY;
        for (int k = 0; k < 8; ++k) {
          const Eigen::Vector3d p((k & 1 ? c.bounds.max : c.bounds.min).x(), (k & 2 ? c.bounds.max : c.bounds.min).y(),
                                  (k & 4 ? c.bounds.max : c.bounds.min).z());
          const double d = (p - cam.eye).dot(cam.forward());
          dlo = std::min(dlo, d), dhi = std::max(dhi, d);
        }
        const double d0 = dlo - 0.01 * (dhi - dlo), range = 1.02 * (dhi - dlo);
        std::vector<std::pair<std::string, std::string>> objects;
        if (const auto p = polynomial(c.expression, c.parameters)) {
          int order = 0;
          std::string terms;
          for (const auto& [k, v] : *p) {
            order = std::max(order, k[0] + k[1] + k[2]);
            terms += fmt::format(" xyz({},{},{}):{:.17g},", k[0], k[1], k[2], v);
          }
          terms.pop_back();
          if (order >= 2 && order <= 35) objects.push_back({"povray-poly", fmt::format("polynomial {{ {},{} sturm }}", order, terms)});
        }
        if (const auto f = pov_function(c.expression, c.parameters)) {
          const double G = 1.2 * max_gradient(c);
          objects.push_back({"povray-isosurface",
                             fmt::format("isosurface {{ function {{ {} }} contained_by {{ box {{ {}, {} }} }} open "
                                         "max_gradient {:.6g} accuracy {:.6g} }}",
                                         *f, pov_vec(c.bounds.min), pov_vec(c.bounds.max), G, 2.5e-5 * diagonal)});
        }
        for (const auto& [method, object] : objects) {
          log::info("bench implicit: {}: {}", g.name, method);
          const PovRun pr = run_povray(a->povray, out_dir / "povray", g.name + "-" + method.substr(7),
                                       pov_scene(cam, object, c.bounds, d0, range), cam, d0, range, a->pov_threads,
                                       a->pov_timeout);
          Row r;
          r.surface = g.name, r.method = method;
          r.ms_frame = 1000 * pr.seconds;
          if (pr.ran) r.error = image_error(ref, band, pr.image.coverage, pr.image.depth);
          else r.note = pr.error;
          if (best_amp_ms && pr.ran) js["ratio_amp_to_" + method.substr(7)] = *best_amp_ms / r.ms_frame;
          rows.push_back(r);
        }
      }
      j["surfaces"][g.name] = js;
      progress.update(double(++done) / double(entries.size()));
    }
    // Geometric mean of AMP (best within 0.5 %) over POV-Ray isosurface where both rendered.
    double log_sum = 0;
    int n = 0;
    for (const auto& [name, js] : j["surfaces"].items())
      if (js.contains("ratio_amp_to_isosurface")) log_sum += std::log(js["ratio_amp_to_isosurface"].get<double>()), ++n;
    if (n) j["geometric_mean_ratio_amp_to_isosurface"] = std::exp(log_sum / n);

    write_file_atomically(out_dir / "bench_implicit.csv", [&](std::ostream& os) {
      os << "surface,method,test,step_divisions,step,remainder,coverage_mismatch,depth_error_share,depth_mean_rel,"
            "reference_covered,ms_frame,compile_ms,note\n";
      for (const auto& r : rows)
        os << fmt::format("{},{},{},{},{},{},{},{},{:.1f},{:.1f},{}\n", r.surface, r.method, r.test,
                          r.step_divisions > 0 ? fmt::format("{:g}", r.step_divisions) : "",
                          r.step > 0 ? fmt::format("{:.6g}", r.step) : "",
                          r.remainder >= 0 ? fmt::format("{:g}", r.remainder) : "",
                          r.note.empty() ? fmt::format("{:.6g},{:.6g},{:.3g}", r.error.coverage_mismatch,
                                                       r.error.depth_error, r.error.depth_mean)
                                         : ",,",
                          r.error.covered, r.ms_frame, r.compile_ms, r.note);
    });
    write_file_atomically(out_dir / "bench_implicit.json", [&](std::ostream& os) { os << j.dump(2) << "\n"; });
    write_png(draw_plot(rows), out_dir / "bench_implicit.png");
    report.json["bench_implicit"] = j;
    if (!common.quiet) {
      std::cout << fmt::format("{:<14} {:<18} {:<7} {:>6} {:>4} {:>10} {:>10} {:>11} {:>10}  {}\n", "surface",
                               "method", "test", "b=d/", "κ", "mismatch", "depth>1e-4", "ms/frame", "compile ms", "note");
      for (const auto& r : rows)
        std::cout << fmt::format("{:<14} {:<18} {:<7} {:>6} {:>4} {:>10} {:>10} {:>11.1f} {:>10.1f}  {}\n", r.surface,
                                 r.method, r.test, r.step_divisions > 0 ? fmt::format("{:g}", r.step_divisions) : "-",
                                 r.remainder >= 0 ? fmt::format("{:g}", r.remainder) : "-",
                                 r.note.empty() ? fmt::format("{:.5f}", r.error.coverage_mismatch) : "-",
                                 r.note.empty() ? fmt::format("{:.5f}", r.error.depth_error) : "-", r.ms_frame,
                                 r.compile_ms, r.note);
      std::cout << fmt::format("wrote {}/bench_implicit.{{csv,json,png}}\n", out_dir.string());
    }
    return kOk;
  }});
}

}  // namespace quadrix::cli
