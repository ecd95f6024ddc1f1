#pragma once
/// Implicit-surface expressions S(x, y, z) as text, parsed once and compiled into a flat list of
/// operations that evaluates S with its gradient in double (forward-mode dual numbers), encloses
/// S and dS/dt along a ray in interval arithmetic (the reference's root isolation), and emits
/// GLSL computing S and ∇S together ([Singh10] §IV-A (a)).
///
/// Grammar: + − * / ^ (right-associative, binds tighter than unary minus: -x^2 = −(x²)), unary
/// minus, parentheses, numbers (1, 2.5, 1e-3), the variables x y z, the constant pi, functions
/// sin cos tan asin acos atan exp log sqrt abs cosh sinh acosh (one argument), min max (two),
/// cheb(n, e) (Chebyshev T_n of e by the stable recurrence, n a whole number 0…1000), and any
/// other name as a parameter whose value is bound at evaluation (uniforms in GLSL, so they can
/// change every frame). An exponent must not depend on x, y, z; a whole-number exponent is a
/// product (x^3 < 0 for x < 0), any other needs a base ≥ 0.
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "core/implicit/interval.h"

namespace quadrix::implicit {

enum class Op : std::uint8_t {
  constant, parameter, x, y, z, add, sub, mul, div, neg, pow_int, pow,
  sin, cos, tan, asin, acos, atan, exp, log, sqrt, abs, cosh, sinh, acosh, min, max, cheb
};

enum class GlslPrecision { single, double_ };

/// One operation; operands are earlier entries of the list.
struct Node {
  Op op = Op::constant;
  int a = -1, b = -1;  ///< operand indices (−1: none)
  double value = 0;    ///< constant
  int n = 0;           ///< parameter index, integer exponent, Chebyshev order
};

/// S and ∇S at a point.
struct ValueGradient {
  double value = 0;
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
};

/// F(t) = S(o + t·d) and F′(t) enclosed over an interval of t.
struct RayEnclosure {
  Interval value, derivative;
};

class Expression {
public:
  /// Parses and compiles. \throws InvalidInput "column C: …" (1-based) for a syntax error, an
  /// unknown function, a wrong argument count or an exponent that depends on x, y, z.
  static Expression parse(std::string_view text);

  const std::string& text() const { return text_; }
  /// Parameter names in order of first appearance; values are passed in this order.
  const std::vector<std::string>& parameters() const { return parameters_; }
  const std::vector<Node>& nodes() const { return nodes_; }

  double value(const Eigen::Vector3d& p, std::span<const double> params) const;
  ValueGradient value_gradient(const Eigen::Vector3d& p, std::span<const double> params) const;
  /// F and F′ over t ∈ [t.lo, t.hi] along x(t) = origin + t·dir, rigorous (outward rounded).
  RayEnclosure enclose(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, const Interval& t,
                       std::span<const double> params) const;

  /// GLSL functions `float NAME_value(vec3 q)` and `vec4 NAME_grad(vec3 q)`: S and ∇S at
  /// p = NAME_origin + q, reading the parameters from uniforms `NAME_pK` (K the parameter's
  /// index), all declared in the returned text. In double precision the origin, the parameters
  /// and every value are double (functions GLSL has only in float go through float), so a
  /// surface far from the world's origin keeps its digits: x − 1e6 is exact near 1e6; in float
  /// the origin and parameters are float uniforms too.
  std::string glsl(std::string_view name, GlslPrecision precision = GlslPrecision::single) const;

private:
  std::string text_;
  std::vector<std::string> parameters_;
  std::vector<Node> nodes_;  // the result is the last
};

}  // namespace quadrix::implicit
