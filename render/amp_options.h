#pragma once
/// Settings of the adaptive marching points (AMP) search for implicit surfaces ([Singh10] §III,
/// Algorithm 1, eq. 2–3). Every value ≤ 0 is derived from the surface and its bounds when the
/// surface is uploaded (render/passes/implicit_pass.h documents how).
namespace quadrix::render {

enum class RootTest { automatic, sign, taylor };  ///< automatic: sign (the CLI picks per gallery surface)

struct AmpOptions {
  double step = 0;   ///< base step b, world units; ≤ 0: the bounds' diagonal / step_divisions
  double step_divisions = 400;  ///< b = diagonal / this when step is derived
  double tau1 = 0;   ///< eq. 2 proximity threshold on |S| (halve b below); ≤ 0: derived
  double tau2 = 0;   ///< eq. 2 far threshold on |S| (double b above); ≤ 0: 2·τ₁
  double tau3 = 0;   ///< eq. 2 horizon threshold on |∇S·D| (quarter b below, with τ₁); ≤ 0: derived
  /// Root-containment test of Algorithm 1 step 5.
  RootTest test = RootTest::automatic;
  /// Beyond eq. 2: the step is also capped at this fraction of |S|/|∇S·D| (the Newton distance
  /// to a root along the ray), so fast oscillations (Chmutov 50 near its cube's faces) are not
  /// stepped over; 0 gives [Singh10]'s rule alone.
  double newton_fraction = 0.5;
  /// Remainder factor κ of the step test (core/implicit/march.h, MarchSettings::remainder): a
  /// step without a sign change whose Taylor lines come within κ·L·h²/2 of zero is quartered,
  /// so a pair of close roots inside one step is not stepped over; 0 turns the test off.
  double remainder = 2;
  double min_step_fraction = 1.0 / 32;  ///< the cap never takes the step below b times this
  int bisections = 10;     ///< Algorithm 1 step 11
  int max_steps = 20000;   ///< marching steps per ray before the pixel is given up
};

}  // namespace quadrix::render
