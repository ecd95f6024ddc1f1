#include "core/shade.h"

#include <algorithm>
#include <cmath>

#include "core/lighting.h"

namespace quadrix {

Image8 shade_phong(const ReferenceImage& img, const Camera& camera, const ShadeOptions& o) {
  Image8 out;
  out.width = img.width;
  out.height = img.height;
  out.rgba.resize(static_cast<std::size_t>(img.width) * img.height * 4);
  const Eigen::Matrix4d V = camera.view();
  const Eigen::Matrix3d R = V.topLeftCorner<3, 3>();
  // Lights in eye space: a head light and a key light from the upper left.
  const Eigen::Vector3d head(0, 0, 1), key = key_light_eye();
  std::vector<std::uint8_t> edges;
  if (o.outlines)
    edges = detect_outlines({.width = img.width, .height = img.height, .coverage = img.coverage.data(),
                             .depth = img.depth.data(), .normal = img.normal.data(), .fov_y_deg = camera.fov_y_deg,
                             .scene_radius = img.scene_radius},
                            o.outline);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * img.width + x;
      std::uint8_t* px = out.pixel(x, y);
      if (!edges.empty() && edges[i]) {
        px[0] = px[1] = px[2] = 0, px[3] = 255;
        continue;
      }
      if (!img.coverage[i]) {
        px[0] = o.background[0], px[1] = o.background[1], px[2] = o.background[2], px[3] = 255;
        continue;
      }
      const Eigen::Vector3d n = (R * img.normal[i].cast<double>()).normalized();
      const Eigen::Vector3d view_dir = camera.pixel_ray(x + 0.5, y + 0.5).dir;
      const Eigen::Vector3d to_eye = -(R * view_dir);
      double diffuse = 0, spec = 0;
      const double key_visible = img.key_light.empty() ? 1.0 : img.key_light[i];
      for (const auto& [l, k] : {std::pair{head, 0.55}, std::pair{key, 0.45 * key_visible}}) {
        const double d = std::max(0.0, n.dot(l));
        diffuse += k * d;
        const Eigen::Vector3d h = (l + to_eye).normalized();
        if (d > 0) spec += k * std::pow(std::max(0.0, n.dot(h)), o.shininess);
      }
      for (int c = 0; c < 3; ++c) {
        const double a = img.albedo[i][c] / 255.0;
        const double v = a * (o.ambient + diffuse) + o.specular * spec;
        px[c] = static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5);
      }
      px[3] = 255;
    }
  }
  return out;
}

FloatImage depth_image(const ReferenceImage& img) {
  return {img.width, img.height, 1, img.depth};
}

FloatImage normal_image(const ReferenceImage& img) {
  FloatImage f{img.width, img.height, 3, {}};
  f.data.reserve(img.normal.size() * 3);
  for (const auto& n : img.normal) f.data.insert(f.data.end(), {n.x(), n.y(), n.z()});
  return f;
}

}  // namespace quadrix
