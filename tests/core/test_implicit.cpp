// Implicit surfaces: the expression parser (precedence, errors with their column), the gradient
// against finite differences, the interval enclosures (property tests on random boxes), and the
// guaranteed first root of the reference against analytic hits.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/camera.h"
#include "core/error.h"
#include "core/implicit/expression.h"
#include "core/implicit/gallery.h"
#include "core/implicit/surface.h"
#include "core/reference.h"

using namespace quadrix;
using namespace quadrix::implicit;

namespace {

double eval(const std::string& text, Eigen::Vector3d p = {0.3, -0.7, 1.1}, std::vector<double> params = {}) {
  return Expression::parse(text).value(p, params);
}

std::string parse_error(const std::string& text) {
  try {
    Expression::parse(text);
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ImplicitExpression, Precedence) {
  EXPECT_DOUBLE_EQ(eval("1 + 2*3"), 7);
  EXPECT_DOUBLE_EQ(eval("(1 + 2)*3"), 9);
  EXPECT_DOUBLE_EQ(eval("2^3^2"), 512);  // right-associative
  EXPECT_DOUBLE_EQ(eval("-2^2"), -4);    // −(2²)
  EXPECT_DOUBLE_EQ(eval("2^-1"), 0.5);
  EXPECT_DOUBLE_EQ(eval("8/4/2"), 1);    // left-associative
  EXPECT_DOUBLE_EQ(eval("10 - 4 - 3"), 3);
  EXPECT_DOUBLE_EQ(eval("x*y + z"), 0.3 * -0.7 + 1.1);
  EXPECT_DOUBLE_EQ(eval("y^3"), std::pow(-0.7, 3));  // whole exponent: a product, negative base fine
  EXPECT_DOUBLE_EQ(eval("2*pi"), 2 * std::numbers::pi);
  EXPECT_DOUBLE_EQ(eval("max(x, min(y, z)) + abs(y)"), 0.3 + 0.7);
  EXPECT_DOUBLE_EQ(eval("cosh(x) - sinh(x) - exp(-x)"), std::cosh(0.3) - std::sinh(0.3) - std::exp(-0.3));
  EXPECT_NEAR(eval("cheb(7, x) - cos(7*acos(x))"), 0.0, 1e-14);
  EXPECT_NEAR(eval("acosh(z) - log(z + sqrt(z^2 - 1))"), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(eval("1.5e1 + .5 + 2E-1"), 15.7);
}

TEST(ImplicitExpression, Parameters) {
  const Expression e = Expression::parse("a*x^k + b - a");
  ASSERT_EQ(e.parameters(), (std::vector<std::string>{"a", "k", "b"}));
  const std::vector<double> v{2.0, 2.5, 1.0};
  EXPECT_DOUBLE_EQ(e.value({4, 0, 0}, v), 2 * 32 + 1 - 2);
  ImplicitSurface s{"x^2 + y^2 + z^2 - r^2", {{"r", 1.0}}, {Eigen::Vector3d::Constant(-2), Eigen::Vector3d::Constant(2)}, {}};
  EXPECT_NO_THROW(compile(s));
  s.parameters.clear();
  EXPECT_THROW(compile(s), InvalidInput);  // r has no value
  s.parameters = {{"r", 1.0}, {"q", 2.0}};
  EXPECT_THROW(compile(s), InvalidInput);  // q names no parameter
}

TEST(ImplicitExpression, ErrorsNameTheColumn) {
  EXPECT_NE(parse_error("x + * y").find("column 5"), std::string::npos) << parse_error("x + * y");
  EXPECT_NE(parse_error("sin(x").find("column 6"), std::string::npos) << parse_error("sin(x");
  EXPECT_NE(parse_error("x^2 + foo(y)").find("column 7"), std::string::npos) << parse_error("x^2 + foo(y)");
  EXPECT_NE(parse_error("x^y").find("column 2"), std::string::npos) << parse_error("x^y");
  EXPECT_NE(parse_error("max(x)").find("column 1"), std::string::npos);
  EXPECT_NE(parse_error("x y").find("column 3"), std::string::npos);
  EXPECT_NE(parse_error("cheb(2.5, x)").find("column 6"), std::string::npos);
  EXPECT_NE(parse_error("").find("column 1"), std::string::npos);
  EXPECT_NE(parse_error("x + 1 )").find("column 7"), std::string::npos);
}

// Found by fuzzing: 2,600 nested '(' overflowed the recursive parser's stack. Nesting is bounded
// (256 levels: parentheses, unary signs, exponents and function arguments alike); the message
// echoes at most 80 characters of the expression.
TEST(ImplicitExpression, DeepNestingIsAnErrorNotACrash) {
  EXPECT_NO_THROW(implicit::Expression::parse(std::string(200, '(') + "x" + std::string(200, ')')));
  for (const std::string& deep : {std::string(100000, '(') + "x", std::string(100000, '-') + "x",
                                  [] { std::string e = "x"; for (int i = 0; i < 300; ++i) e += "^1"; return e; }(), std::string(300, '(') + "x" + std::string(300, ')')}) {
    const std::string m = parse_error(deep);
    EXPECT_NE(m.find("nested more than 256 levels deep"), std::string::npos) << m.substr(0, 200);
    EXPECT_LT(m.size(), 300u);
  }
  EXPECT_NE(parse_error("x + \x07").find("unexpected '\\x07'"), std::string::npos) << parse_error("x + \x07");
}

TEST(ImplicitExpression, GradientMatchesFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.9, 0.9);
  for (const auto& g : gallery()) {
    const CompiledImplicit c = compile(g.surface);
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d p(u(rng), u(rng), u(rng));
      const ValueGradient vg = c.expression.value_gradient(p, c.parameters);
      EXPECT_NEAR(vg.value, c.expression.value(p, c.parameters), 1e-9 * (1 + std::abs(vg.value))) << g.name;
      const double h = 1e-6;
      for (int a = 0; a < 3; ++a) {
        Eigen::Vector3d d = Eigen::Vector3d::Zero();
        d[a] = h;
        const double fd = (c.expression.value(p + d, c.parameters) - c.expression.value(p - d, c.parameters)) / (2 * h);
        EXPECT_NEAR(vg.gradient[a], fd, 1e-5 * (1 + std::abs(fd))) << g.name << " at " << p.transpose() << " axis " << a;
      }
    }
  }
}

// Every point of a random t interval evaluates inside the enclosure of F and F′.
TEST(ImplicitInterval, EnclosuresHoldEverySample) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.2, 1.2), w(0.0, 0.5);
  std::vector<std::string> texts{"sin(3*x)*cos(2*y) + tan(z/3)", "exp(x)*log(2 + y) - sqrt(1.5 + z)",
                                 "abs(x)^2.5 + abs(y)^0.7 - cosh(z) + sinh(x*y)", "min(x, y)*max(y, z) - atan(x) + asin(z/2)",
                                 "acosh(2 + x^2) + acos(y/2) + (x - y)^-2", "cheb(9, x) + cheb(50, y/1.3) - cheb(4, z)"};
  for (const auto& g : gallery()) texts.push_back(g.surface.expression);
  std::map<std::string, double> defaults;
  for (const auto& g : gallery()) defaults.insert(g.surface.parameters.begin(), g.surface.parameters.end());
  for (const auto& text : texts) {
    const Expression e = Expression::parse(text);
    std::vector<double> params;
    for (const auto& p : e.parameters()) params.push_back(defaults.at(p));
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector3d o(u(rng), u(rng), u(rng));
      const Eigen::Vector3d d = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
      const double t0 = u(rng), t1 = t0 + w(rng);
      const RayEnclosure E = e.enclose(o, d, {t0, t1}, params);
      for (int j = 0; j <= 16; ++j) {
        const double t = t0 + (t1 - t0) * j / 16.0;
        const ValueGradient vg = e.value_gradient(o + t * d, params);
        if (!std::isfinite(vg.value)) continue;
        EXPECT_TRUE(E.value.contains(vg.value)) << text << " t=" << t << " F=" << vg.value << " in [" << E.value.lo
                                                << ", " << E.value.hi << "]";
        const double dF = vg.gradient.dot(d);
        if (std::isfinite(dF)) {
          EXPECT_TRUE(E.derivative.contains(dF)) << text << " t=" << t << " F'=" << dF << " in [" << E.derivative.lo
                                                 << ", " << E.derivative.hi << "]";
        }
      }
    }
  }
}

TEST(ImplicitInterval, ChebyshevRangeIsTight) {
  // The exact range of T_50 over [0, 1] is [−1, 1]; over [1, 1.001] it is [1, T_50(1.001)].
  const Interval a = chebyshev(50, {0.0, 1.0});
  EXPECT_NEAR(a.lo, -1, 1e-12);
  EXPECT_NEAR(a.hi, 1, 1e-12);
  const Interval b = chebyshev(50, {1.0, 1.001});
  EXPECT_NEAR(b.lo, 1, 1e-12);
  EXPECT_NEAR(b.hi, std::cosh(50 * std::acosh(1.001)), 1e-9);
  EXPECT_GT(chebyshev(3, {-2.0, -1.5}).hi, -27.1);  // odd: T_3(−1.5) = −7.5
  EXPECT_LT(chebyshev(3, {-2.0, -1.5}).hi, -7.4);
}

// The first root of rays through a sphere, an expression with a known answer.
TEST(ImplicitRoot, SphereHitsAreExactAndFirst) {
  const ImplicitSurface s{"x^2 + y^2 + z^2 - 1", {}, {Eigen::Vector3d::Constant(-2), Eigen::Vector3d::Constant(2)}, {}};
  const CompiledImplicit c = compile(s);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.99, 0.99);
  for (int k = 0; k < 500; ++k) {
    const double py = u(rng), pz = u(rng) * std::sqrt(1 - py * py);
    const Ray ray{{-5, py, pz}, {1, 0, 0}};
    const auto r = first_root(c, ray, 0, 100);
    ASSERT_TRUE(r);
    EXPECT_TRUE(r->certain);
    EXPECT_NEAR(r->t, 5 - std::sqrt(1 - py * py - pz * pz), 1e-12);
  }
  EXPECT_FALSE(first_root(c, Ray{{-5, 1.001, 0}, {1, 0, 0}}, 0, 100));
  // A root before tmin is skipped: the exit root is found.
  const auto far = first_root(c, Ray{{-5, 0, 0}, {1, 0, 0}}, 4.5, 100);
  ASSERT_TRUE(far);
  EXPECT_NEAR(far->t, 6, 1e-12);
}

// Two roots 1e-6 apart in t (a thin shell): the interval isolation finds the first; a marcher
// with a coarse step would step over both.
TEST(ImplicitRoot, ThinShellsAreNotMissed) {
  const ImplicitSurface s{"(x^2 + y^2 + z^2 - 1)^2 - 1e-12", {}, {Eigen::Vector3d::Constant(-2), Eigen::Vector3d::Constant(2)}, {}};
  const CompiledImplicit c = compile(s);
  const auto r = first_root(c, Ray{{-5, 0, 0}, {1, 0, 0}}, 0, 100);
  ASSERT_TRUE(r);
  EXPECT_NEAR(r->t, 5 - std::sqrt(1 + 1e-6), 1e-9);
}

TEST(ImplicitRoot, ChmutovFiftyHasNoFalseRoots) {
  const CompiledImplicit c = compile(gallery_surface("chmutov-iter-50").surface);
  // Along y = z = 1: T_50(x) + 2 = 0 has no real root (T_50 ≥ −1 everywhere).
  EXPECT_FALSE(first_root(c, Ray{{-3, 1, 1}, {1, 0, 0}}, 0, 10));
  // Along y = z = 0 (T_50(0) = −1): T_50(x) = 2, first at x = −cosh(acosh(2)/50), just outside the cube.
  const auto r = first_root(c, Ray{{-3, 0, 0}, {1, 0, 0}}, 0, 10);
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->certain);
  EXPECT_NEAR(-3 + r->t, -std::cosh(std::acosh(2.0) / 50), 1e-12);
  // Through x = y = a with T_50(a) = 1: T_50(z) = −3 has no root, so the ray misses.
  const double a = std::cos(2 * std::numbers::pi / 50);
  EXPECT_FALSE(first_root(c, Ray{{a, a, -3}, {0, 0, 1}}, 0, 10));
}

TEST(ImplicitGallery, EveryEntryCompilesAndNamedOrdersWork) {
  for (const auto& g : gallery()) EXPECT_NO_THROW(compile(g.surface)) << g.name;
  EXPECT_EQ(gallery_surface("blinn-75").name, "blinn-75");
  EXPECT_EQ(gallery_surface("chmutov-trig-22").name, "chmutov-trig-22");
  EXPECT_THROW(gallery_surface("nope"), InvalidInput);
  EXPECT_THROW(gallery_surface("chmutov-iter-1x"), InvalidInput);
}

// The reference draws implicits beside quadric primitives, depth-correct: a glyph sphere in
// front of an implicit sphere hides it where they overlap.
TEST(ImplicitReference, MixesWithOtherPrimitives) {
  Model m;
  m.implicits.push_back({"(x - 1)^2 + y^2 + z^2 - 1", {}, {Eigen::Vector3d(-0.1, -1.1, -1.1), Eigen::Vector3d(2.1, 1.1, 1.1)}, {}});
  Glyph g;
  g.centre = {-0.5, 0, 0.5};
  g.radius = 0.8;
  m.glyphs.push_back(g);
  const ReferenceScene scene(m);
  const Ray ray{{1, 0, 5}, {0, 0, -1}};
  const auto hit = scene.trace(ray, 0, 100, {});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->kind, PrimitiveKind::implicit);
  EXPECT_NEAR(hit->t, 4, 1e-12);
  EXPECT_NEAR(hit->normal.z(), 1, 1e-9);
  const auto behind = scene.trace(Ray{{-0.2, 0, 5}, {0, 0, -1}}, 0, 100, {});
  ASSERT_TRUE(behind);
  EXPECT_EQ(behind->kind, PrimitiveKind::glyph);
}

// The iterative and trigonometric Chebyshev forms of Chmutov 50 are the same surface inside the
// cube: the reference finds the same first hits for both.
TEST(ImplicitRoot, ChmutovFormsAgree) {
  const Box3 cube{Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};
  ImplicitSurface iter = gallery_surface("chmutov-iter-50").surface, trig = gallery_surface("chmutov-trig-50").surface;
  iter.bounds = trig.bounds = cube;
  const CompiledImplicit a = compile(iter), b = compile(trig);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0, same = 0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector3d target(0.6 * u(rng), 0.6 * u(rng), 0.6 * u(rng));
    const Eigen::Vector3d eye = 4.0 * Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const Ray ray{eye, (target - eye).normalized()};
    const auto ra = first_root(a, ray, 0, 20), rb = first_root(b, ray, 0, 20);
    ASSERT_EQ(ra.has_value(), rb.has_value()) << k;
    if (!ra) continue;
    ++hits;
    same += std::abs(ra->t - rb->t) < 1e-6;
    EXPECT_NEAR(ra->t, rb->t, 1e-6) << "ray " << k << " certain " << ra->certain << rb->certain;
  }
  EXPECT_GT(hits, 200);
}
