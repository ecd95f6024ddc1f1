#pragma once
/// Adaptive marching points ([Singh10] Algorithm 1) in double on the CPU: the step rule, root
/// tests and refinement of the GL shader (render/shaders/implicit.frag), line for line, so the
/// march can be measured against the guaranteed first_root (core/implicit/surface.h) and tested
/// without a GL context. The GL side differs only in running in float.
#include <optional>

#include "core/implicit/surface.h"
#include "core/ray.h"

namespace quadrix::implicit {

/// The march of one surface, every value derived (render/passes/implicit_pass.h derives them
/// from AmpOptions and the surface).
struct MarchSettings {
  double step = 0;            ///< base step b, world units
  double tau1 = 0, tau2 = 0;  ///< eq. 2 proximity thresholds on |S|
  double tau3 = 0;            ///< eq. 2 horizon threshold on |∇S·D|
  /// The step is capped at this fraction of |F|/|F′| (the Newton distance to a root); 0: off.
  double newton_fraction = 0;
  /// Remainder factor κ of the step test: a step whose ends have one sign is accepted only when
  /// F(t₀) + F′(t₀)·h and F(t₁) − F′(t₁)·h (the Taylor test's lines to the middle, eq. 3) stay
  /// on that sign by more than κ·L·h²/2, where L = |F′(t₁) − F′(t₀)|/s estimates |F″| on the
  /// step (a Lipschitz estimate of F′); else the step is quartered and retried. 0: off.
  double remainder = 0;
  double min_step = 0;  ///< floor of the Newton cap and of quartering
  bool taylor = false;  ///< Taylor test (eq. 3) with 8 sign-tested sub-steps where it holds
  int bisections = 10;  ///< Algorithm 1 step 11
  int max_steps = 20000;  ///< evaluations of S and ∇S per ray before the ray is given up
};

struct MarchResult {
  std::optional<double> t;  ///< the root found (secant through the bisected bracket), if any
  int steps = 0;            ///< evaluations of S and ∇S while marching (rejected steps included)
  int rejected = 0;         ///< steps quartered by the remainder test
};

/// Marches ray.at(t) for t from the bounds' entry (or tmin, if later) to their exit (or tmax).
/// \throws nothing beyond Expression::value_gradient.
MarchResult march_first_root(const CompiledImplicit& surface, const Ray& ray, double tmin, double tmax,
                             const MarchSettings& settings);

/// The step-size rule of the march from a point with F = f, F′ = df ([Singh10] eq. 2 and the
/// Newton cap), shared by march_first_root and documented for the shader's copy.
double march_step(const MarchSettings& settings, double f, double df);

/// The remainder test: true where a step [t₀, t₀ + s] without a sign change may still hide a
/// pair of roots and is to be quartered (see MarchSettings::remainder); the march accepts it
/// anyway once the step is at the floor min_step.
bool step_is_suspect(const MarchSettings& settings, double s, double f0, double df0, double f1, double df1);

}  // namespace quadrix::implicit
