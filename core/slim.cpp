#include "core/slim.h"

#include <cmath>
#include <cstdlib>

namespace quadrix {

double slim_weight(double r) {
  if (r < 0.0) r = -r;
  if (r < 0.5) return std::exp(-8.0 * r * r);
  if (r <= 1.0) {
    const double s = 1.0 - r;
    return 16.0 * std::exp(-2.0) * s * s * s * s;
  }
  return 0.0;
}

bool intersect_slim_patch(const SlimPatch& patch, const Ray& ray, double tmin, double tmax, Hit& hit) {
  // Local frame u = (x − c)/R; λ is unchanged when both origin and direction are scaled.
  // The local origin starts at the ray's closest approach to the centre so γ stays O(1).
  const double inv_r = 1.0 / patch.radius;
  Ray local;
  const double t0 = rebase_ray(ray, patch.centre, local);
  local.origin *= inv_r;
  local.dir *= inv_r;
  if (local.origin.squaredNorm() > 1.0) return false;  // the ray misses the ball
  const auto inside = [&](const Eigen::Vector3d& u) {
    return u.squaredNorm() <= 1.0 && (!patch.clip || patch.clip->keeps(u));
  };
  Hit h;
  if (!intersect_quadric(patch.local, local, tmin - t0, tmax - t0, /*cull_backfaces=*/true, inside, h)) return false;
  hit.t = h.t + t0;
  hit.point = ray.at(hit.t);
  hit.gradient = h.gradient * inv_r;
  hit.front_facing = true;
  return true;
}

double slim_offset_of(const Model& model) {
  if (const auto it = model.metadata.find("slim_offset"); it != model.metadata.end()) {
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end != it->second.c_str() && std::isfinite(v) && v >= 0.0) return v;
  }
  return SlimBlendOptions{}.offset;
}

void sample_slim_patch(const SlimPatch& patch, int grid, std::vector<SlimSurfaceSample>& out) {
  constexpr int kRimRefine = 3;
  constexpr double kRim2 = 0.8 * 0.8;
  const int fine = grid * kRimRefine;
  const double step = 2.0 / fine;
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (int i = 0; i < fine; ++i)
      for (int j = 0; j < fine; ++j) {
        // Lines of the coarse lattice keep every root; the others only roots in the rim.
        const bool coarse = i % kRimRefine == kRimRefine / 2 && j % kRimRefine == kRimRefine / 2;
        Ray line;
        line.origin = Eigen::Vector3d::Zero();
        line.origin[a1] = -1.0 + (i + 0.5) * step;
        line.origin[a2] = -1.0 + (j + 0.5) * step;
        if (line.origin.squaredNorm() >= 1.0) continue;
        line.dir = Eigen::Vector3d::Unit(axis);
        const Roots roots = solve_ray_quadratic(ray_quadratic(patch.local, line));
        for (int k = 0; k < roots.count; ++k) {
          const Eigen::Vector3d u = line.at(roots.t[k]);
          const double r2 = u.squaredNorm();
          if (!(r2 < 1.0) || (!coarse && r2 <= kRim2) || (patch.clip && !patch.clip->keeps(u))) continue;
          const Eigen::Vector3d g = patch.local.gradient(u);
          const double gn = g.norm();
          if (!(gn > 0.0)) continue;
          out.push_back({patch.centre + patch.radius * u, g / gn, std::sqrt(r2)});
        }
      }
  }
}

std::optional<SlimBlend> blend_slim_samples(std::span<const SlimSample> samples, const SlimBlendOptions& options,
                                            std::vector<SlimSample>* used) {
  if (used) used->clear();
  double t_cut = std::numeric_limits<double>::infinity();
  for (const auto& s : samples) t_cut = std::min(t_cut, s.hit.t + options.offset * s.radius);
  SlimBlend b;
  double t_first = std::numeric_limits<double>::infinity();
  for (const auto& s : samples) {
    if (s.hit.t > t_cut || !(s.weight > 0.0)) continue;
    const double g = s.hit.gradient.norm();
    if (!(g > 0.0)) continue;
    b.weight_sum += s.weight;
    b.t += s.weight * s.hit.t;
    b.point += s.weight * s.hit.point;
    b.normal += (s.weight / g) * s.hit.gradient;
    ++b.count;
    if (used) used->push_back(s);
    if (s.hit.t < t_first) {
      t_first = s.hit.t;
      b.first_index = s.index;
    }
  }
  if (!(b.weight_sum > 0.0)) return std::nullopt;
  b.t /= b.weight_sum;
  b.point /= b.weight_sum;
  const double n = b.normal.norm();
  if (!(n > 0.0)) return std::nullopt;
  b.normal /= n;
  return b;
}

}  // namespace quadrix
