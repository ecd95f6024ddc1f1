#include "core/implicit/gallery.h"

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix::implicit {
namespace {

Box3 cube(double h) { return {Eigen::Vector3d::Constant(-h), Eigen::Vector3d::Constant(h)}; }
Box3 box(double hx, double hy, double hz) { return {Eigen::Vector3d(-hx, -hy, -hz), Eigen::Vector3d(hx, hy, hz)}; }

GalleryEntry entry(std::string name, std::string description, std::string expression, Box3 bounds,
                   std::map<std::string, double> params = {}, std::string test = "sign", double step = 0) {
  return {std::move(name), std::move(description), {std::move(expression), std::move(params), bounds, std::nullopt},
          std::move(test), step};
}

// T_n in the power basis (integer coefficients by the recurrence), as text in v.
std::string chebyshev_power(int n, const std::string& v) {
  std::vector<double> t0{1}, t1{0, 1};
  for (int k = 1; k < n; ++k) {
    std::vector<double> t2(k + 2, 0.0);
    for (std::size_t i = 0; i < t1.size(); ++i) t2[i + 1] += 2 * t1[i];
    for (std::size_t i = 0; i < t0.size(); ++i) t2[i] -= t0[i];
    t0 = std::move(t1);
    t1 = std::move(t2);
  }
  const std::vector<double>& c = n == 0 ? t0 : t1;
  std::string s;
  for (int i = static_cast<int>(c.size()) - 1; i >= 0; --i) {
    if (c[i] == 0) continue;
    const std::string term = i == 0 ? fmt::format("{:.17g}", std::abs(c[i]))
                             : i == 1 ? fmt::format("{:.17g}*{}", std::abs(c[i]), v)
                                      : fmt::format("{:.17g}*{}^{}", std::abs(c[i]), v, i);
    s += s.empty() ? (c[i] < 0 ? "-" + term : term) : (c[i] < 0 ? " - " : " + ") + term;
  }
  return "(" + s + ")";
}

// Chmutov T_n(x) + T_n(y) + T_n(z) (+1 for odd n) = 0 ([Singh10] appendix), three forms.
GalleryEntry chmutov(int n, std::string_view form) {
  const std::string tail = n % 2 ? " + 1" : "";
  // Beyond |x| = 1 the surface reaches only to cosh(acosh(3)/n) (|T_n| ≤ 3 there).
  const double reach = std::cosh(std::acosh(3.0) / n) * 1.001;
  if (form == "power")
    return entry(fmt::format("chmutov-{}", n), fmt::format("Chmutov [{}], power basis", n),
                 chebyshev_power(n, "x") + " + " + chebyshev_power(n, "y") + " + " + chebyshev_power(n, "z") + tail,
                 cube(reach), {}, "sign", n <= 8 ? 0.02 : 0.01);
  if (form == "iter")
    return entry(fmt::format("chmutov-iter-{}", n), fmt::format("Chmutov [{}], iterative Chebyshev form", n),
                 fmt::format("cheb({0}, x) + cheb({0}, y) + cheb({0}, z){1}", n, tail), cube(reach), {}, "sign", 0.01);
  // The trigonometric form cos(n·acos x) holds on [−1, 1]: clamped there and bounded by the cube.
  const auto t = [n](char v) { return fmt::format("cos({0}*acos(min(max({1}, -1), 1)))", n, v); };
  return entry(fmt::format("chmutov-trig-{}", n), fmt::format("Chmutov {}, trigonometric Chebyshev form", n),
               t('x') + " + " + t('y') + " + " + t('z') + tail, cube(1.0), {}, "sign", 0.01);
}

// Blinn's blobby with N balls on a golden-angle spiral ([Singh10] appendix A.2).
GalleryEntry blinn(int n) {
  std::string s;
  Box3 centres;
  const double r = 0.9 / std::cbrt(static_cast<double>(n)) + 0.12;
  for (int i = 0; i < n; ++i) {
    const double h = n == 1 ? 0.0 : 1.0 - 2.0 * (i + 0.5) / n;
    const double rho = std::sqrt(std::max(0.0, 1.0 - h * h));
    const double phi = i * std::numbers::pi * (3.0 - std::sqrt(5.0));
    const double a = n == 1 ? 0.0 : 0.9 + 0.15 * std::sin(3.0 * i);
    const Eigen::Vector3d c(a * rho * std::cos(phi), a * h, a * rho * std::sin(phi));
    centres.extend(c);
    s += fmt::format("{}{:.6g}/((x - {:.6g})^2 + (y - {:.6g})^2 + (z - {:.6g})^2 + eps)", i ? " + " : "", r * r, c.x(),
                     c.y(), c.z());
  }
  // Past r·√N from every centre the field is below 1: a bound that holds.
  const Eigen::Vector3d m = Eigen::Vector3d::Constant(r * std::sqrt(static_cast<double>(n)));
  return entry(fmt::format("blinn-{}", n), fmt::format("Blinn's blobby, {} balls", n), s + " - 1",
               {centres.min - m, centres.max + m}, {{"eps", 0.01}}, "sign", 0.05);
}

}  // namespace

std::vector<GalleryEntry> gallery() {
  const double phi = (1 + std::sqrt(5.0)) / 2;
  std::vector<GalleryEntry> g{
      entry("ding-dong", "Ding-Dong [3]", "x^2 + y^2 - z*(1 - z^2)", box(1.5, 1.5, 1.5), {}, "sign", 0.03),
      entry("clebsch", "Clebsch [3]",
            "81*(x^3 + y^3 + z^3) - 189*(x^2*(y + z) + y^2*(x + z) + z^2*(x + y)) + 54*x*y*z + 126*(x*y + y*z + x*z)"
            " - 9*(x^2 + y^2 + z^2) - 9*(x + y + z) + 1",
            cube(1.5), {}, "sign", 0.03),
      entry("cayley", "Cayley [3]", "-5*(x^2*(y + z) + y^2*(x + z) + z^2*(x + y)) + 2*(x*y + y*z + x*z)", cube(1.5), {},
            "sign", 0.03),
      entry("torus", "Torus [4]", "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)", box(1.5, 1.5, 0.5),
            {{"R", 1.0}, {"r", 0.4}}, "sign", 0.04),
      entry("goursat", "Goursat [4]", "x^4 + y^4 + z^4 - 1", cube(1.1), {}, "sign", 0.04),
      entry("kummer", "Kummer [4] (the paper's form)",
            "x^4 + y^4 + z^4 - x^2 - y^2 - z^2 - x^2*y^2 - y^2*z^2 - z^2*x^2 + 1", cube(2.0), {}, "sign", 0.02),
      entry("cross-cap", "Cross-cap [4]", "4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)", cube(1.1), {}, "taylor",
            0.02),
      entry("steiner", "Steiner's Roman surface [4]", "x^2*y^2 + x^2*z^2 + y^2*z^2 - 2*x*y*z", cube(0.6), {}, "taylor",
            0.02),
      entry("tooth", "Tooth [4]", "x^4 + y^4 + z^4 - x^2 - y^2 - z^2", cube(1.3), {}, "sign", 0.03),
      entry("piriform", "Piriform [4]", "x^4 - x^3 + y^2 + z^2", box(1.1, 0.5, 0.5), {}, "sign", 0.02),
      entry("barth-sextic", "Barth [6]",
            "4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - (1 + 2*phi)*(x^2 + y^2 + z^2 - 1)^2", cube(1.6),
            {{"phi", phi}}, "sign", 0.02),
      entry("heart", "Heart [6]", "(2*x^2 + 2*y^2 + z^2 - 1)^3 - 0.1*x^2*z^3 - y^2*z^3", cube(1.3), {}, "sign", 0.02),
      chmutov(6, "power"),
      chmutov(8, "power"),
      entry("endrass", "Endrass [8]",
            "64*(x^2 - 1)*(y^2 - 1)*((x + y)^2 - 2)*((x - y)^2 - 2) - (-4*(1 - sqrt(2))*(x^2 + y^2)^2"
            " + 8*(2 - sqrt(2))*z^2 + 2*(2 - 7*sqrt(2))*(x^2 + y^2) - 16*z^4 + 8*(1 + 2*sqrt(2))*z^2"
            " - (1 - 12*sqrt(2)))^2",
            cube(2.0), {}, "sign", 0.01),
      chmutov(9, "power"),
      entry("barth-decic", "Barth [10]",
            "8*(x^2 - phi^4*y^2)*(y^2 - phi^4*z^2)*(z^2 - phi^4*x^2)*(x^4 + y^4 + z^4 - 2*x^2*y^2 - 2*x^2*z^2"
            " - 2*y^2*z^2) + (3 + 5*phi)*(x^2 + y^2 + z^2 - 1)^2*(x^2 + y^2 + z^2 - 2 + phi)^2",
            cube(1.6), {{"phi", phi}}, "sign", 0.015),
      chmutov(14, "iter"),
      chmutov(18, "iter"),
      chmutov(22, "iter"),
      chmutov(50, "iter"),
      chmutov(50, "trig"),
      entry("torus-sqrt", "Torus (non-algebraic form)", "(c - sqrt(x^2 + y^2))^2 + z^2 - a^2", box(1.5, 1.5, 0.5),
            {{"c", 1.0}, {"a", 0.4}}, "sign", 0.04),
      entry("superquadric", "Superquadric |x|^m + |y|^m + |z|^m = 1", "abs(x)^m + abs(y)^m + abs(z)^m - 1", cube(1.05),
            {{"m", 4.0}}, "sign", 0.02),
      entry("blobby", "Blobby (sinusoidal)", "x^2 + y^2 + z^2 + sin(4*x) - cos(4*y) + sin(4*z) - 1", cube(2.0), {},
            "sign", 0.05),
      blinn(8),
      // Two surfaces made to be animated (quadrix view --animate): three blobs pulled apart by s
      // (merged below about s = 0.6, separate above 0.9) and a superquadric twisted by k radians
      // per unit of z.
      entry("blobs-merging", "Three Blinn blobs at distance s from the centre",
            "0.25/((x - s)^2 + y^2 + z^2 + 0.01) + 0.25/((x + 0.5*s)^2 + (y - 0.866*s)^2 + z^2 + 0.01)"
            " + 0.25/((x + 0.5*s)^2 + (y + 0.866*s)^2 + z^2 + 0.01) - 1",
            box(2.2, 2.2, 1.0), {{"s", 0.8}}, "sign", 0.05),
      entry("superquadric-twist", "Superquadric |x'|^4 + |y'|^4 + |z|^4 = 1, (x', y') turned by k·z",
            "(x*cos(k*z) - y*sin(k*z))^4 + (x*sin(k*z) + y*cos(k*z))^4 + z^4 - 1", box(1.2, 1.2, 1.05),
            {{"k", 1.0}}, "sign", 0.02),
      entry("scherk", "Scherk's minimal surface", "exp(z)*cos(y) - cos(x)", box(3.0, 3.0, 2.0), {}, "sign", 0.03),
      entry("diamond", "Diamond (Schwarz D)",
            "sin(x)*sin(y)*sin(z) + sin(x)*cos(y)*cos(z) + cos(x)*sin(y)*cos(z) + cos(x)*cos(y)*sin(z)", cube(2.5), {},
            "sign", 0.04),
  };
  return g;
}

GalleryEntry gallery_surface(std::string_view name) {
  for (auto& e : gallery())
    if (e.name == name) return e;
  int n = 0;
  char tail = 0;
  const std::string s(name);
  const auto whole = [&](const char* pattern) { return std::sscanf(s.c_str(), pattern, &n, &tail) == 1; };
  if (whole("chmutov-iter-%d%c") && n >= 2 && n <= 1000) return chmutov(n, "iter");
  if (whole("chmutov-trig-%d%c") && n >= 2 && n <= 1000) return chmutov(n, "trig");
  if (whole("chmutov-%d%c") && n >= 2 && n <= 1000) return chmutov(n, "power");
  if (whole("blinn-%d%c") && n >= 1 && n <= 1000) return blinn(n);
  std::string names;
  for (const auto& e : gallery()) names += (names.empty() ? "" : ", ") + e.name;
  throw InvalidInput(fmt::format("no built-in surface '{}' (known: {}; also chmutov-N, chmutov-iter-N, "
                                 "chmutov-trig-N, blinn-N)", name, names));
}

}  // namespace quadrix::implicit
