#pragma once
/// Implicit surfaces S(x, y, z) = 0 by adaptive marching points ([Singh10] Algorithm 1): one
/// program generated per surface from its expression (S and ∇S together), one full-screen pass
/// per surface into the G-buffer, depth-tested with the other kinds.
///
/// A surface whose bounds lie far from the world's origin (their centre more than
/// kImplicitFarFactor diagonals away) is marched relative to that centre and evaluated in double
/// (core/implicit/expression.h GlslPrecision): in float world coordinates (x − 1e6)² near 1e6
/// keeps no digits. Others are evaluated in float about the world's origin.
///
/// Derived defaults (AmpOptions ≤ 0): b = diagonal / step_divisions; over a 16³ lattice of the
/// bounds, τ₁ = 0.05·median |S|, τ₂ = 2τ₁, τ₃ = 0.1·median |∇S| (the horizon: a ray within
/// about 6° of grazing a surface of typical slope).
#include <span>
#include <string>
#include <vector>

#include "core/implicit/march.h"
#include "core/model.h"
#include "render/amp_options.h"
#include "render/passes/frame.h"

namespace quadrix::render {

/// What the march of one surface uses, after defaults were derived (the CPU march takes the same).
using AmpSettings = implicit::MarchSettings;

/// Derives the AMP settings of a surface (see above); RootTest::automatic is the sign test.
/// \throws InvalidInput as implicit::compile.
AmpSettings amp_settings(const ImplicitSurface& surface, const AmpOptions& options);

/// Bounds whose centre is farther than this many diagonals from the origin take the double path.
constexpr double kImplicitFarFactor = 8.0;

class ImplicitPass final : public Pass {
public:
  /// Compiles one program per surface (timed: compile_ms).
  /// \throws InvalidInput for a bad expression or past kMaxPrimitiveIndex surfaces, GlError.
  void upload(std::span<const ImplicitSurface> surfaces, const AmpOptions& options = {});
  /// New parameter values for surface i (names as in its expression), used from the next frame
  /// on without recompiling. \throws InvalidInput for an unknown name.
  void set_parameters(std::size_t i, const std::map<std::string, double>& values);
  std::size_t count() const { return surfaces_.size(); }
  double compile_ms() const { return compile_ms_; }
  const AmpSettings& settings(std::size_t i) const { return surfaces_[i].amp; }
  bool needed(const RenderOptions&) const override { return !surfaces_.empty(); }
  void run(const Frame& frame) override;

private:
  struct Surface {
    gl::Program program;
    std::vector<std::string> parameter_names;
    std::vector<double> parameters;
    bool far = false;  ///< double precision about origin
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    Box3 bounds;
    AmpSettings amp;
    std::uint32_t colour = 0;
  };
  std::vector<Surface> surfaces_;
  AmpOptions options_;
  double compile_ms_ = 0;
};

}  // namespace quadrix::render
