#include "core/implicit/expression.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <numbers>
#include <tuple>

#include <fmt/format.h>

#include "core/error.h"
#include "core/io/file.h"

namespace quadrix::implicit {
namespace {

struct FunctionInfo {
  Op op;
  int arity;
};

const std::map<std::string_view, FunctionInfo>& functions() {
  static const std::map<std::string_view, FunctionInfo> f{
      {"sin", {Op::sin, 1}},     {"cos", {Op::cos, 1}},     {"tan", {Op::tan, 1}},   {"asin", {Op::asin, 1}},
      {"acos", {Op::acos, 1}},   {"atan", {Op::atan, 1}},   {"exp", {Op::exp, 1}},   {"log", {Op::log, 1}},
      {"sqrt", {Op::sqrt, 1}},   {"abs", {Op::abs, 1}},     {"cosh", {Op::cosh, 1}}, {"sinh", {Op::sinh, 1}},
      {"acosh", {Op::acosh, 1}}, {"min", {Op::min, 2}},     {"max", {Op::max, 2}},   {"cheb", {Op::cheb, 2}}};
  return f;
}

bool is_whole(double e) { return e == std::floor(e) && std::abs(e) <= 1e6; }

double powi(double a, int n) {
  double r = 1.0, b = a;
  for (unsigned m = static_cast<unsigned>(n < 0 ? -n : n); m; m >>= 1, b *= b)
    if (m & 1u) r *= b;
  return n < 0 ? 1.0 / r : r;
}

// Chebyshev T_n and T_n′ = n·U_{n−1} by the three-term recurrences ([Singh10] appendix: the
// iterative form, stable where the power form of high orders is not).
std::pair<double, double> cheb(int n, double x) {
  if (n == 0) return {1.0, 0.0};
  double t0 = 1, t1 = x, u0 = 1, u1 = 2 * x;
  for (int k = 1; k < n; ++k) {
    const double t2 = 2 * x * t1 - t0;
    t0 = t1, t1 = t2;
    const double u2 = 2 * x * u1 - u0;
    u0 = u1, u1 = u2;
  }
  return {t1, n * u0};
}

// Scalar semantics of every operation (also used for constant folding).
double apply(const Node& nd, double a, double b) {
  switch (nd.op) {
    case Op::add: return a + b;
    case Op::sub: return a - b;
    case Op::mul: return a * b;
    case Op::div: return a / b;
    case Op::neg: return -a;
    case Op::pow_int: return powi(a, nd.n);
    case Op::pow: return is_whole(b) ? powi(a, static_cast<int>(b)) : std::pow(a, b);
    case Op::sin: return std::sin(a);
    case Op::cos: return std::cos(a);
    case Op::tan: return std::tan(a);
    case Op::asin: return std::asin(a);
    case Op::acos: return std::acos(a);
    case Op::atan: return std::atan(a);
    case Op::exp: return std::exp(a);
    case Op::log: return std::log(a);
    case Op::sqrt: return std::sqrt(a);
    case Op::abs: return std::abs(a);
    case Op::cosh: return std::cosh(a);
    case Op::sinh: return std::sinh(a);
    case Op::acosh: return std::acosh(a);
    case Op::min: return std::min(a, b);
    case Op::max: return std::max(a, b);
    case Op::cheb: return cheb(nd.n, a).first;
    default: return nd.value;
  }
}

class Parser {
public:
  explicit Parser(std::string_view text) : s_(text) {}

  void run(std::vector<Node>& nodes, std::vector<std::string>& params) {
    nodes_ = &nodes;
    params_ = &params;
    const int r = expr();
    skip();
    if (pos_ < s_.size()) fail(pos_, fmt::format("unexpected '{}'", io::echo(s_.substr(pos_, 1))));
    // The result must be the last node: re-add it if it was shared.
    if (r != static_cast<int>(nodes.size()) - 1) nodes.push_back(Node{Op::add, r, add_const(0.0), 0, 0});
  }

private:
  [[noreturn]] void fail(std::size_t at, const std::string& what) const {
    throw InvalidInput(fmt::format("expression '{}', column {}: {}", io::echo(s_), at + 1, what));
  }
  void skip() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool eat(char c) {
    skip();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }

  // Adds a node, folding constants and sharing equal nodes.
  int add(Node nd) {
    auto& nodes = *nodes_;
    const bool unary = nd.op >= Op::neg && nd.op != Op::pow && nd.op != Op::min && nd.op != Op::max;
    if (nd.a >= 0 && nodes[nd.a].op == Op::constant && (unary || (nd.b >= 0 && nodes[nd.b].op == Op::constant)))
      return add_const(apply(nd, nodes[nd.a].value, nd.b >= 0 ? nodes[nd.b].value : 0.0));
    const auto key = std::make_tuple(nd.op, nd.a, nd.b, nd.value, nd.n);
    if (const auto it = shared_.find(key); it != shared_.end()) return it->second;
    nodes.push_back(nd);
    const int id = static_cast<int>(nodes.size()) - 1;
    shared_[key] = id;
    depends_.push_back(nd.op == Op::x || nd.op == Op::y || nd.op == Op::z || (nd.a >= 0 && depends_[nd.a]) ||
                       (nd.b >= 0 && depends_[nd.b]));
    return id;
  }
  int add_const(double v) { return add(Node{Op::constant, -1, -1, v, 0}); }
  int add_op(Op op, int a, int b = -1, int n = 0) { return add(Node{op, a, b, 0.0, n}); }

  int expr() {
    int r = term();
    for (;;) {
      if (eat('+')) r = add_op(Op::add, r, term());
      else if (eat('-')) r = add_op(Op::sub, r, term());
      else return r;
    }
  }
  int term() {
    int r = unary();
    for (;;) {
      if (eat('*')) r = add_op(Op::mul, r, unary());
      else if (eat('/')) r = add_op(Op::div, r, unary());
      else return r;
    }
  }
  // Every recursion of the grammar passes through unary(): its depth bounds the parser's stack
  // (found by fuzzing: 2,600 nested '(' overflowed it).
  static constexpr int kMaxDepth = 256;
  int unary() {
    struct Level {
      int& depth;
      ~Level() { --depth; }
    } level{++depth_};
    if (depth_ > kMaxDepth) fail(pos_, fmt::format("nested more than {} levels deep", kMaxDepth));
    if (eat('-')) return add_op(Op::neg, unary());
    if (eat('+')) return unary();
    return power();
  }
  int power() {
    const int base = primary();
    skip();
    const std::size_t at = pos_;
    if (!eat('^')) return base;
    const int e = unary();
    if (depends_[e]) fail(at, "the exponent must not depend on x, y or z (write exp(e*log(b)) for b > 0)");
    const Node& en = (*nodes_)[e];
    if (en.op == Op::constant && is_whole(en.value)) {
      if (en.value == 1) return base;
      return add_op(Op::pow_int, base, -1, static_cast<int>(en.value));
    }
    return add_op(Op::pow, base, e);
  }
  int primary() {
    skip();
    if (pos_ >= s_.size()) fail(pos_, "unexpected end of expression");
    const std::size_t start = pos_;
    const char c = s_[pos_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      std::size_t end = pos_;
      while (end < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[end])) || s_[end] == '.')) ++end;
      if (end < s_.size() && (s_[end] == 'e' || s_[end] == 'E')) {
        std::size_t k = end + 1;
        if (k < s_.size() && (s_[k] == '+' || s_[k] == '-')) ++k;
        if (k < s_.size() && std::isdigit(static_cast<unsigned char>(s_[k]))) {
          end = k;
          while (end < s_.size() && std::isdigit(static_cast<unsigned char>(s_[end]))) ++end;
        }
      }
      const std::string number(s_.substr(pos_, end - pos_));
      char* stop = nullptr;
      const double v = std::strtod(number.c_str(), &stop);
      if (stop != number.c_str() + number.size() || !std::isfinite(v)) fail(start, fmt::format("bad number '{}'", number));
      pos_ = end;
      return add_const(v);
    }
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      std::size_t end = pos_;
      while (end < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[end])) || s_[end] == '_')) ++end;
      const std::string name(s_.substr(pos_, end - pos_));
      pos_ = end;
      skip();
      if (pos_ < s_.size() && s_[pos_] == '(') return call(name, start);
      if (name == "x") return add_op(Op::x, -1);
      if (name == "y") return add_op(Op::y, -1);
      if (name == "z") return add_op(Op::z, -1);
      if (name == "pi") return add_const(std::numbers::pi);
      if (functions().count(name)) fail(start, fmt::format("function '{}' needs arguments in parentheses", name));
      auto& p = *params_;
      const auto it = std::find(p.begin(), p.end(), name);
      int index = static_cast<int>(it - p.begin());
      if (it == p.end()) p.push_back(name);
      return add(Node{Op::parameter, -1, -1, 0.0, index});
    }
    if (eat('(')) {
      const int r = expr();
      if (!eat(')')) fail(pos_, "expected ')'");
      return r;
    }
    fail(pos_, fmt::format("unexpected '{}'", io::echo(std::string_view(&c, 1))));
  }
  int call(const std::string& name, std::size_t at) {
    const auto it = functions().find(name);
    if (it == functions().end()) fail(at, fmt::format("unknown function '{}'", name));
    eat('(');
    std::vector<int> args;
    std::vector<std::size_t> where;
    if (!eat(')')) {
      do {
        skip();
        where.push_back(pos_);
        args.push_back(expr());
      } while (eat(','));
      if (!eat(')')) fail(pos_, "expected ',' or ')'");
    }
    if (static_cast<int>(args.size()) != it->second.arity)
      fail(at, fmt::format("'{}' takes {} argument{}, got {}", name, it->second.arity, it->second.arity == 1 ? "" : "s",
                           args.size()));
    if (it->second.op == Op::cheb) {
      const Node& n = (*nodes_)[args[0]];
      if (n.op != Op::constant || !is_whole(n.value) || n.value < 0 || n.value > 1000)
        fail(where[0], "cheb(n, e) needs a whole number 0 ≤ n ≤ 1000 as n");
      return add_op(Op::cheb, args[1], -1, static_cast<int>(n.value));
    }
    return add_op(it->second.op, args[0], args.size() > 1 ? args[1] : -1);
  }

  std::string_view s_;
  std::size_t pos_ = 0;
  int depth_ = 0;  // unary() calls open (kMaxDepth)
  std::vector<Node>* nodes_ = nullptr;
  std::vector<std::string>* params_ = nullptr;
  std::vector<bool> depends_;
  std::map<std::tuple<Op, int, int, double, int>, int> shared_;
};

// Forward-mode dual number: value and gradient.
struct Dual {
  double v;
  Eigen::Vector3d g;
};

// Interval value and derivative along the ray.
struct RayDual {
  Interval v, d;
};

// Statements `T out = base^n;` by repeated squaring, unrolled (T float or double).
std::string power_code(const std::string& base, int n, const std::string& out, std::string_view T) {
  if (n == 0) return fmt::format("  {} {} = 1.0;\n", T, out);
  std::string code = fmt::format("  {} {}_b0 = {};\n", T, out, base);
  std::string acc;
  int k = 0;
  for (unsigned m = static_cast<unsigned>(n < 0 ? -n : n);; ++k) {
    if (m & 1u) acc = acc.empty() ? fmt::format("{}_b{}", out, k) : fmt::format("{} * {}_b{}", acc, out, k);
    m >>= 1;
    if (!m) break;
    code += fmt::format("  {3} {0}_b{1} = {0}_b{2} * {0}_b{2};\n", out, k + 1, k, T);
  }
  return code + fmt::format("  {} {} = {};\n", T, out, n < 0 ? "1.0 / (" + acc + ")" : acc);
}

std::string literal(double v, bool dbl) {
  const std::string t = dbl ? fmt::format("{:.17e}LF", v) : fmt::format("{:.9e}", v);
  return v < 0 ? "(" + t + ")" : t;
}

}  // namespace

Expression Expression::parse(std::string_view text) {
  Expression e;
  e.text_ = std::string(text);
  Parser(e.text_).run(e.nodes_, e.parameters_);
  return e;
}

double Expression::value(const Eigen::Vector3d& p, std::span<const double> params) const {
  thread_local std::vector<double> r;
  r.resize(nodes_.size());
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node& nd = nodes_[i];
    switch (nd.op) {
      case Op::constant: r[i] = nd.value; break;
      case Op::parameter: r[i] = params[nd.n]; break;
      case Op::x: r[i] = p.x(); break;
      case Op::y: r[i] = p.y(); break;
      case Op::z: r[i] = p.z(); break;
      default: r[i] = apply(nd, r[nd.a], nd.b >= 0 ? r[nd.b] : 0.0);
    }
  }
  return r.back();
}

ValueGradient Expression::value_gradient(const Eigen::Vector3d& p, std::span<const double> params) const {
  thread_local std::vector<Dual> r;
  r.resize(nodes_.size());
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node& nd = nodes_[i];
    const Dual a = nd.a >= 0 ? r[nd.a] : Dual{0, zero};
    const Dual b = nd.b >= 0 ? r[nd.b] : Dual{0, zero};
    Dual& o = r[i];
    switch (nd.op) {
      case Op::constant: o = {nd.value, zero}; break;
      case Op::parameter: o = {params[nd.n], zero}; break;
      case Op::x: o = {p.x(), Eigen::Vector3d::UnitX()}; break;
      case Op::y: o = {p.y(), Eigen::Vector3d::UnitY()}; break;
      case Op::z: o = {p.z(), Eigen::Vector3d::UnitZ()}; break;
      case Op::add: o = {a.v + b.v, a.g + b.g}; break;
      case Op::sub: o = {a.v - b.v, a.g - b.g}; break;
      case Op::mul: o = {a.v * b.v, a.v * b.g + b.v * a.g}; break;
      case Op::div: {
        const double q = a.v / b.v;
        o = {q, (a.g - q * b.g) / b.v};
        break;
      }
      case Op::neg: o = {-a.v, -a.g}; break;
      case Op::pow_int: o = {powi(a.v, nd.n), nd.n * powi(a.v, nd.n - 1) * a.g}; break;
      case Op::pow: {
        const double e = b.v;
        const double d = e == 0 ? 0.0 : e * (is_whole(e) ? powi(a.v, static_cast<int>(e) - 1) : std::pow(a.v, e - 1));
        o = {apply(nd, a.v, e), d * a.g};
        break;
      }
      case Op::sin: o = {std::sin(a.v), std::cos(a.v) * a.g}; break;
      case Op::cos: o = {std::cos(a.v), -std::sin(a.v) * a.g}; break;
      case Op::tan: {
        const double c = std::cos(a.v);
        o = {std::tan(a.v), a.g / (c * c)};
        break;
      }
      case Op::asin: o = {std::asin(a.v), a.g / std::sqrt(1 - a.v * a.v)}; break;
      case Op::acos: o = {std::acos(a.v), -a.g / std::sqrt(1 - a.v * a.v)}; break;
      case Op::atan: o = {std::atan(a.v), a.g / (1 + a.v * a.v)}; break;
      case Op::exp: {
        const double e = std::exp(a.v);
        o = {e, e * a.g};
        break;
      }
      case Op::log: o = {std::log(a.v), a.g / a.v}; break;
      case Op::sqrt: {
        const double s = std::sqrt(a.v);
        o = {s, a.g * (0.5 / s)};
        break;
      }
      case Op::abs: o = {std::abs(a.v), (a.v < 0 ? -1.0 : a.v > 0 ? 1.0 : 0.0) * a.g}; break;
      case Op::cosh: o = {std::cosh(a.v), std::sinh(a.v) * a.g}; break;
      case Op::sinh: o = {std::sinh(a.v), std::cosh(a.v) * a.g}; break;
      case Op::acosh: o = {std::acosh(a.v), a.g / std::sqrt(a.v * a.v - 1)}; break;
      case Op::min: o = a.v <= b.v ? a : b; break;
      case Op::max: o = a.v >= b.v ? a : b; break;
      case Op::cheb: {
        const auto [t, d] = cheb(nd.n, a.v);
        o = {t, d * a.g};
        break;
      }
    }
  }
  return {r.back().v, r.back().g};
}

RayEnclosure Expression::enclose(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, const Interval& t,
                                 std::span<const double> params) const {
  thread_local std::vector<RayDual> r;
  r.resize(nodes_.size());
  const Interval zero = Interval::point(0.0), one = Interval::point(1.0);
  const auto coord = [&](int k) {
    return RayDual{Interval::point(origin[k]) + Interval::point(dir[k]) * t, Interval::point(dir[k])};
  };
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node& nd = nodes_[i];
    const RayDual a = nd.a >= 0 ? r[nd.a] : RayDual{zero, zero};
    const RayDual b = nd.b >= 0 ? r[nd.b] : RayDual{zero, zero};
    RayDual& o = r[i];
    switch (nd.op) {
      case Op::constant: o = {Interval::point(nd.value), zero}; break;
      case Op::parameter: o = {Interval::point(params[nd.n]), zero}; break;
      case Op::x: o = coord(0); break;
      case Op::y: o = coord(1); break;
      case Op::z: o = coord(2); break;
      case Op::add: o = {a.v + b.v, a.d + b.d}; break;
      case Op::sub: o = {a.v - b.v, a.d - b.d}; break;
      case Op::mul: o = {a.v * b.v, a.v * b.d + b.v * a.d}; break;
      case Op::div: {
        const Interval q = a.v / b.v;
        o = {q, (a.d - q * b.d) / b.v};
        break;
      }
      case Op::neg: o = {-a.v, -a.d}; break;
      case Op::pow_int:
        o = {pow_int(a.v, nd.n), Interval::point(nd.n) * pow_int(a.v, nd.n - 1) * a.d};
        break;
      case Op::pow: {
        const double e = b.v.lo;  // variable-free: a point
        if (is_whole(e)) {
          const int n = static_cast<int>(e);
          o = {pow_int(a.v, n), Interval::point(e) * pow_int(a.v, n - 1) * a.d};
        } else {
          o = {pow_real(a.v, e), Interval::point(e) * pow_real(a.v, e - 1) * a.d};
        }
        break;
      }
      case Op::sin: o = {sin(a.v), cos(a.v) * a.d}; break;
      case Op::cos: o = {cos(a.v), -(sin(a.v) * a.d)}; break;
      case Op::tan: {
        const Interval c = cos(a.v);
        o = {tan(a.v), a.d / (c * c)};
        break;
      }
      case Op::asin: o = {asin(a.v), a.d / sqrt(one - a.v * a.v)}; break;
      case Op::acos: o = {acos(a.v), -(a.d / sqrt(one - a.v * a.v))}; break;
      case Op::atan: o = {atan(a.v), a.d / (one + pow_int(a.v, 2))}; break;
      case Op::exp: {
        const Interval e = exp(a.v);
        o = {e, e * a.d};
        break;
      }
      case Op::log: o = {log(a.v), a.d / a.v}; break;
      case Op::sqrt: {
        const Interval s = sqrt(a.v);
        o = {s, a.d / (Interval::point(2.0) * s)};
        break;
      }
      case Op::abs: {
        const Interval sign = a.v.lo > 0 ? one : a.v.hi < 0 ? -one : Interval{-1.0, 1.0};
        o = {abs(a.v), sign * a.d};
        break;
      }
      case Op::cosh: o = {cosh(a.v), sinh(a.v) * a.d}; break;
      case Op::sinh: o = {sinh(a.v), cosh(a.v) * a.d}; break;
      case Op::acosh: o = {acosh(a.v), a.d / sqrt(pow_int(a.v, 2) - one)}; break;
      case Op::min:
        o = {min(a.v, b.v), a.v.hi < b.v.lo ? a.d : b.v.hi < a.v.lo ? b.d : hull(a.d, b.d)};
        break;
      case Op::max:
        o = {max(a.v, b.v), a.v.lo > b.v.hi ? a.d : b.v.lo > a.v.hi ? b.d : hull(a.d, b.d)};
        break;
      case Op::cheb: o = {chebyshev(nd.n, a.v), chebyshev_derivative(nd.n, a.v) * a.d}; break;
    }
    // An empty value (outside the domain) empties the derivative too.
    if (o.v.is_empty()) o.d = Interval::empty();
  }
  return {r.back().v, r.back().d};
}

std::string Expression::glsl(std::string_view name, GlslPrecision precision) const {
  // Double: every value and dual (value, gradient) in double, so that x − 1e6 near 1e6 keeps its
  // digits; GLSL has no double sin, exp, pow…, so those go through float (their arguments are
  // what they are: no cancellation happens inside them).
  const bool dbl = precision == GlslPrecision::double_;
  const std::string T = dbl ? "double" : "float", V4 = dbl ? "dvec4" : "vec4", V3 = dbl ? "dvec3" : "vec3";
  const std::string F = dbl ? "float" : "";  // wraps a double operand for a float-only function
  const std::string D = dbl ? "double" : "";  // wraps its float result back
  std::string u, v, g;
  for (std::size_t k = 0; k < parameters_.size(); ++k) u += fmt::format("uniform {} {}_p{};\n", T, name, k);
  u += fmt::format("uniform {} {}_origin;  // S is evaluated at {}_origin + q\n", V3, name, name);
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node& nd = nodes_[i];
    const std::string a = fmt::format("r{}", nd.a), b = fmt::format("r{}", nd.b);
    std::string ve, ge;  // value, and (value, gradient) as a 4-vector
    const std::string ax = a + ".x", axf = F + "(" + ax + ")";
    // A float-only function f with derivative df (written in terms of axf).
    const auto unary = [&](std::string f, std::string df) {
      ve = fmt::format("{}({}({}({})))", D, f, F, a);
      ge = fmt::format("{}({}({}({}({}))), {}({}) * {}.yzw)", V4, D, f, F, ax, D, df, a);
    };
    // A function that GLSL also has in double (sqrt, abs): no round trip through float.
    const auto native = [&](std::string f, std::string df) {
      ve = fmt::format("{}({})", f, a);
      ge = fmt::format("{}({}({}), ({}) * {}.yzw)", V4, f, ax, df, a);
    };
    switch (nd.op) {
      case Op::constant:
        ve = literal(nd.value, dbl);
        ge = fmt::format("{}({}, 0.0, 0.0, 0.0)", V4, ve);
        break;
      case Op::parameter:
        ve = fmt::format("{}_p{}", name, nd.n);
        ge = fmt::format("{}({}, 0.0, 0.0, 0.0)", V4, ve);
        break;
      case Op::x: ve = "p.x", ge = V4 + "(p.x, 1.0, 0.0, 0.0)"; break;
      case Op::y: ve = "p.y", ge = V4 + "(p.y, 0.0, 1.0, 0.0)"; break;
      case Op::z: ve = "p.z", ge = V4 + "(p.z, 0.0, 0.0, 1.0)"; break;
      case Op::add: ve = ge = fmt::format("{} + {}", a, b); break;
      case Op::sub: ve = ge = fmt::format("{} - {}", a, b); break;
      case Op::neg: ve = ge = fmt::format("-{}", a); break;
      case Op::mul:
        ve = fmt::format("{} * {}", a, b);
        ge = fmt::format("{2}({0}.x * {1}.x, {0}.x * {1}.yzw + {1}.x * {0}.yzw)", a, b, V4);
        break;
      case Op::div:
        ve = fmt::format("{} / {}", a, b);
        ge = fmt::format("qx_div({}, {})", a, b);
        break;
      case Op::pow_int: {
        // Straight-line products (loops per power make a JIT like llvmpipe's crawl).
        const std::string pv = fmt::format("q{}", i);
        v += power_code(a, nd.n, pv, T);
        g += power_code(ax, nd.n - 1, pv, T);
        ve = pv;
        ge = fmt::format("{4}({0} * {1}, {2}.0 * {0} * {3}.yzw)", pv, ax, nd.n, a, V4);
        break;
      }
      case Op::pow:
        ve = fmt::format("{2}(qx_pow({3}({0}), {3}({1})))", a, b, D, F);
        ge = fmt::format("{2}({3}(qx_pow({4}({0}.x), {4}({1}.x))), {3}({4}({1}.x) * qx_pow({4}({0}.x), {4}({1}.x) - 1.0)) * {0}.yzw)",
                         a, b, V4, D, F);
        break;
      case Op::sin: unary("sin", "cos(" + axf + ")"); break;
      case Op::cos: unary("cos", "-sin(" + axf + ")"); break;
      case Op::tan: unary("tan", fmt::format("1.0 / (cos({0}) * cos({0}))", axf)); break;
      case Op::asin: unary("qx_asin", fmt::format("inversesqrt(1.0 - {0} * {0})", axf)); break;
      case Op::acos: unary("qx_acos", fmt::format("-inversesqrt(1.0 - {0} * {0})", axf)); break;
      case Op::atan: unary("atan", fmt::format("1.0 / (1.0 + {0} * {0})", axf)); break;
      case Op::exp: unary("exp", "exp(" + axf + ")"); break;
      case Op::log: unary("log", "1.0 / " + axf); break;
      case Op::sqrt: native("sqrt", "0.5 * inversesqrt(" + ax + ")"); break;
      case Op::abs: native("abs", "sign(" + ax + ")"); break;
      case Op::cosh: unary("cosh", "sinh(" + axf + ")"); break;
      case Op::sinh: unary("sinh", "cosh(" + axf + ")"); break;
      case Op::acosh: unary("acosh", fmt::format("inversesqrt({0} * {0} - 1.0)", axf)); break;
      case Op::min:
        ve = fmt::format("min({}, {})", a, b);
        ge = fmt::format("({0}.x <= {1}.x ? {0} : {1})", a, b);
        break;
      case Op::max:
        ve = fmt::format("max({}, {})", a, b);
        ge = fmt::format("({0}.x >= {1}.x ? {0} : {1})", a, b);
        break;
      case Op::cheb:
        ve = fmt::format("{}(qx_cheb({}, {}({})).x)", D, nd.n, F, a);
        ge = fmt::format("qx_cheb_dual({}, {})", nd.n, a);
        break;
    }
    v += fmt::format("  {} r{} = {};\n", T, i, ve);
    g += fmt::format("  {} r{} = {};\n", V4, i, ge);
  }
  const std::size_t last = nodes_.size() - 1;
  std::string comment = text_;
  std::replace_if(comment.begin(), comment.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
  const std::string at = fmt::format("  {0} p = {1}_origin + {0}(q);\n", V3, name);
  return fmt::format(
      "// Generated from: {0}\n{1}"
      "float {2}_value(vec3 q) {{\n{6}{3}  return float(r{5});\n}}\n"
      "vec4 {2}_grad(vec3 q) {{\n{6}{4}  return vec4(r{5});\n}}\n",
      comment, u, name, v, g, last, at);
}

}  // namespace quadrix::implicit
