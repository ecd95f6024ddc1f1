#include "core/synth.h"

#include <cmath>
#include <numbers>
#include <random>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix {
namespace {

Rgb palette(int i) {
  static constexpr Rgb colours[] = {{230, 80, 60}, {70, 140, 230}, {240, 200, 60}, {90, 190, 110},
                                    {200, 200, 200}, {170, 90, 200}, {250, 140, 40}, {60, 200, 200}};
  return colours[i % 8];
}

Model tet_model(const Quadric& q, int n, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Rgb colour) {
  Model m;
  const Eigen::Vector3d h = (hi - lo) / n;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d c = lo + Eigen::Vector3d(i, j, k).cwiseProduct(h);
        for (const auto& t : split_cube(c, h)) {
          // Keep the tetrahedron when f changes sign over 20 samples (corners, edge thirds).
          double fmin = std::numeric_limits<double>::infinity(), fmax = -fmin;
          for (int a = 0; a < 4; ++a)
            for (int b = a; b < 4; ++b)
              for (const double s : {0.0, 1.0 / 3.0, 2.0 / 3.0}) {
                if (a == b && s > 0) continue;
                const double f = q.eval((1 - s) * t[a] + s * t[b]);
                fmin = std::min(fmin, f);
                fmax = std::max(fmax, f);
              }
          if (fmin <= 0.0 && fmax >= 0.0) m.tets.push_back(TetPatch::from_world(t, q, colour));
        }
      }
  return m;
}

}  // namespace

std::vector<std::array<Eigen::Vector3d, 4>> split_cube(const Eigen::Vector3d& lo, const Eigen::Vector3d& h) {
  // Corner k has offsets (k&1, k>>1&1, k>>2&1); the six monotone paths 0 → 7 give the tetrahedra.
  const auto corner = [&](int k) {
    return Eigen::Vector3d(lo.x() + (k & 1) * h.x(), lo.y() + ((k >> 1) & 1) * h.y(), lo.z() + ((k >> 2) & 1) * h.z());
  };
  static constexpr int paths[6][2] = {{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}};
  std::vector<std::array<Eigen::Vector3d, 4>> out;
  for (const auto& p : paths) {
    std::array<Eigen::Vector3d, 4> t{corner(0), corner(p[0]), corner(p[1]), corner(7)};
    if ((t[1] - t[0]).cross(t[2] - t[0]).dot(t[3] - t[0]) < 0) std::swap(t[1], t[2]);
    out.push_back(t);
  }
  return out;
}

Quadric synth_quadric(std::string_view kind) {
  Quadric q;
  q.A = Eigen::Vector3d(1, 1, -1).asDiagonal();
  if (kind == "hyperboloid1") q.c = -0.25;
  else if (kind == "hyperboloid2") q.c = 0.25;
  else throw InvalidInput(fmt::format("no analytic quadric for synth kind '{}'", kind));
  return q;
}

std::vector<std::string> synth_kinds() {
  return {"sphere", "ellipsoid", "cylinder", "glyphs", "hyperboloid1", "hyperboloid2", "slim-sphere"};
}

Model synth_model(std::string_view kind, const SynthOptions& o) {
  if (o.count < 0 || o.count > 50'000'000) throw InvalidInput(fmt::format("synth: --count {} out of range", o.count));
  if (o.resolution < 0 || o.resolution > 512)
    throw InvalidInput(fmt::format("synth: --resolution {} out of range", o.resolution));
  Model m;
  if (kind == "sphere") {
    m.glyphs.push_back({GlyphKind::sphere, {0, 0, 0}, 1.0, Eigen::Matrix3d::Identity(), palette(0)});
  } else if (kind == "ellipsoid") {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
    m.glyphs.push_back({GlyphKind::ellipsoid, {0, 0, 0}, 1.0, R * Eigen::Vector3d(1.5, 1.0, 0.6).asDiagonal(), palette(1)});
  } else if (kind == "cylinder") {
    Eigen::Matrix3d axes = Eigen::Matrix3d::Zero();
    axes.col(0) = Eigen::Vector3d(0.3, 1.0, 0.2);
    m.glyphs.push_back({GlyphKind::cylinder, {0, 0, 0}, 0.5, axes, palette(2)});
  } else if (kind == "glyphs") {
    const int n = o.count > 0 ? o.count : 1000;
    std::mt19937_64 rng(o.seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    // Atoms in a cube whose side grows with n^(1/3), so density (and overlap) stays constant.
    const double side = 4.0 * std::cbrt(static_cast<double>(n));
    m.glyphs.reserve(n);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d c(side * u(rng), side * u(rng), side * u(rng));
      const double r = 0.6 + 0.8 * u(rng);
      const int k = i % 10;
      if (k < 7) {
        m.glyphs.push_back({GlyphKind::sphere, c, r, Eigen::Matrix3d::Identity(), palette(i)});
      } else if (k < 9) {
        Eigen::Matrix3d axes = Eigen::Matrix3d::Zero();
        axes.col(0) = Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized() * (1.0 + u(rng));
        m.glyphs.push_back({GlyphKind::cylinder, c, 0.25, axes, palette(i)});
      } else {
        const Eigen::Matrix3d R =
            Eigen::AngleAxisd(6.28 * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng) + 0.1).normalized()).toRotationMatrix();
        m.glyphs.push_back({GlyphKind::ellipsoid, c, 1.0, R * Eigen::Vector3d(r, 0.7 * r, 0.4 * r).asDiagonal(), palette(i)});
      }
    }
  } else if (kind == "hyperboloid1" || kind == "hyperboloid2") {
    const int n = o.resolution > 0 ? o.resolution : 10;
    m = tet_model(synth_quadric(kind), n, {-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}, palette(kind == "hyperboloid1" ? 3 : 5));
  } else if (kind == "slim-sphere") {
    const int n = o.count > 0 ? o.count : 200;
    // Fibonacci sphere; support radius large enough that neighbouring balls overlap well.
    const double R = 3.6 / std::sqrt(static_cast<double>(n));
    const Quadric unit = Quadric::sphere(Eigen::Vector3d::Zero(), 1.0);
    for (int i = 0; i < n; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / n;
      const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const double phi = i * std::numbers::pi * (3.0 - std::sqrt(5.0));
      const Eigen::Vector3d c(r * std::cos(phi), r * std::sin(phi), z);
      m.slims.push_back({c, R, unit.to_local(c, R), ClipPlanes{}, palette(4), std::nullopt});
    }
  } else {
    throw InvalidInput(fmt::format("synth: unknown kind '{}' (one of: {})", kind, fmt::join(synth_kinds(), ", ")));
  }
  m.metadata["producer"] = fmt::format("quadrix synth {}", kind);
  m.metadata["units"] = "unit";
  return m;
}

}  // namespace quadrix
