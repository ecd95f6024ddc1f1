#pragma once
/// Small analytic models for tests, benchmarks and the demo (`quadrix synth`).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/model.h"

namespace quadrix {

struct SynthOptions {
  int count = 0;             ///< primitives for `glyphs` and `slim-sphere` (0: the kind's default)
  int resolution = 0;        ///< grid cells per axis for tetrahedron kinds (0: default)
  std::uint64_t seed = 1;    ///< random models
};

/// Kinds: sphere, ellipsoid, cylinder (one glyph each); glyphs (`count` random spheres,
/// ellipsoids and cylinders, a molecule-like cloud); hyperboloid1 and hyperboloid2 (the one- and
/// two-sheet hyperboloids x² + y² − z² ∓ ¼ = 0 clipped by the tetrahedra of a 6-per-cube grid
/// that the surface crosses); slim-sphere (the unit sphere as SLIM patches on a Fibonacci set).
/// \throws InvalidInput for an unknown kind or absurd sizes.
Model synth_model(std::string_view kind, const SynthOptions& options = {});

/// The kinds synth_model accepts.
std::vector<std::string> synth_kinds();

/// The analytic quadric behind a tetrahedron kind (for tests): hyperboloid1 or hyperboloid2.
Quadric synth_quadric(std::string_view kind);

/// Splits the axis-aligned grid cell with minimum corner `lo` and edge `h` into 6 tetrahedra
/// sharing the diagonal lo → lo + h(1,1,1) (a conforming split of a regular grid).
std::vector<std::array<Eigen::Vector3d, 4>> split_cube(const Eigen::Vector3d& lo, const Eigen::Vector3d& h);

}  // namespace quadrix
