#pragma once
/// An implicit surface ready for ray queries in double: its expression parsed and its parameters
/// bound, and the guaranteed first-root isolation that makes the CPU reference the truth for
/// implicits (interval Newton-style subdivision in t, after Mitchell 1990, [Singh10] §II).
#include <optional>
#include <vector>

#include "core/implicit/expression.h"
#include "core/model.h"
#include "core/ray.h"

namespace quadrix::implicit {

/// An ImplicitSurface parsed, with its parameter values in the expression's order.
struct CompiledImplicit {
  Expression expression;
  std::vector<double> parameters;
  Box3 bounds;
};

/// \throws InvalidInput for a syntax error (with its column), a parameter without a value, a
/// value for a name the expression does not use, a non-finite value, or empty/non-finite bounds.
CompiledImplicit compile(const ImplicitSurface& surface);

struct RootOptions {
  /// Intervals of t narrower than this times the bounds' diagonal that still may hold a root
  /// (a tangent ray, a double root) count as a root at their middle.
  double tolerance = 1e-9;
  /// Subdivisions per ray before the first unresolved interval is taken as the root.
  int max_intervals = 1 << 15;
};

struct ImplicitRoot {
  double t = 0;
  /// True when a sign change with a derivative free of 0 proved one simple root, refined by
  /// bisection to double precision; false for a root accepted at the tolerance.
  bool certain = false;
};

/// The first t ∈ (tmin, tmax) inside the bounds with S(origin + t·dir) = 0. Every interval of
/// t before the returned root is proved root-free by the interval enclosure of S and dS/dt
/// (natural and mean-value forms); a simple root is isolated by a sign change with dS/dt ≠ 0.
std::optional<ImplicitRoot> first_root(const CompiledImplicit& surface, const Ray& ray, double tmin, double tmax,
                                       const RootOptions& options = {});

/// The slab test of a ray against a box: the t range inside, or an empty interval.
Interval clip_to_box(const Ray& ray, const Box3& box);

}  // namespace quadrix::implicit
