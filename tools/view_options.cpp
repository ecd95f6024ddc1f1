#include "tools/view_options.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "core/reference.h"
#include "tools/cli.h"

namespace quadrix::cli {
namespace {

double radians(double deg) { return deg * std::numbers::pi / 180.0; }
double degrees(double rad) { return rad * 180.0 / std::numbers::pi; }

// The field of view after --zoom: the lens narrowed by the magnification.
double zoomed(double fov_y_deg, double zoom) { return 2.0 * degrees(std::atan(std::tan(radians(fov_y_deg) / 2.0) / zoom)); }

// The eye about `up` at azimuth/elevation around the camera's target, its distance kept; the
// same directions as frame_view (core/camera.h).
Camera place(Camera c, const Eigen::Vector3d& up_axis, double azimuth, double elevation) {
  const double dist = (c.eye - c.target).norm();
  const Eigen::Vector3d up = up_axis.normalized(), front = front_axis(up), right = up.cross(front);
  const double az = radians(azimuth), el = radians(elevation);
  const Eigen::Vector3d horizontal = std::cos(az) * front + std::sin(az) * right;
  c.eye = c.target + dist * (std::cos(el) * horizontal + std::sin(el) * up);
  c.up = std::abs(std::cos(el)) < 1e-6 ? Eigen::Vector3d(-(std::sin(el) > 0 ? 1.0 : -1.0) * horizontal) : up;
  return c;
}

// One key of a camera file: the value, or a FormatError naming the file and the key.
const nlohmann::json& key(const nlohmann::json& j, const std::filesystem::path& path, const char* name) {
  if (!j.contains(name)) throw FormatError(fmt::format("{}: camera: key '{}' is missing", path.string(), name));
  return j.at(name);
}

double number_at(const nlohmann::json& j, const std::filesystem::path& path, const char* name) {
  const nlohmann::json& v = key(j, path, name);
  if (!v.is_number() || !std::isfinite(v.get<double>()))
    throw FormatError(fmt::format("{}: camera: key '{}' must be a finite number, got {}", path.string(), name,
                                  v.dump().substr(0, 60)));
  return v.get<double>();
}

Eigen::Vector3d vector_at(const nlohmann::json& j, const std::filesystem::path& path, const char* name) {
  const nlohmann::json& v = key(j, path, name);
  const bool ok = v.is_array() && v.size() == 3 &&
                  std::all_of(v.begin(), v.end(), [](const auto& e) { return e.is_number() && std::isfinite(e.template get<double>()); });
  if (!ok)
    throw FormatError(fmt::format("{}: camera: key '{}' must be an array of 3 finite numbers, got {}", path.string(),
                                  name, v.dump().substr(0, 60)));
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

int pixels_at(const nlohmann::json& j, const std::filesystem::path& path, const char* name) {
  const double v = number_at(j, path, name);
  if (v != std::floor(v) || v < 1 || v > 16384)
    throw FormatError(fmt::format("{}: camera: key '{}' must be a whole number of pixels in [1, 16384], got {}",
                                  path.string(), name, v));
  return static_cast<int>(v);
}

// How much of the image (the larger of the fractions of width and height, measured from the
// centre both ways) the points span from a camera.
double centred_extent(const Camera& c, const std::vector<Eigen::Vector3d>& points, double* zmin, double* zmax) {
  const Eigen::Vector3d f = c.forward();
  Eigen::Vector3d r = f.cross(c.up);
  if (r.squaredNorm() < 1e-24) r = f.cross(std::abs(f.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
  r.normalize();
  const Eigen::Vector3d u = r.cross(f);
  const double tan_y = std::tan(radians(c.fov_y_deg) / 2.0), tan_x = tan_y * c.width / c.height;
  double extent = 0;
  for (const auto& p : points) {
    const Eigen::Vector3d d = p - c.eye;
    const double z = d.dot(f);
    if (!(z > 0)) return INFINITY;  // behind the eye: too close
    extent = std::max({extent, std::abs(d.dot(r)) / (z * tan_x), std::abs(d.dot(u)) / (z * tan_y)});
    *zmin = std::min(*zmin, z);
    *zmax = std::max(*zmax, z);
  }
  return extent;
}

}  // namespace

std::pair<double, double> view_angles(const ViewArgs& a) {
  if (a.view == "front") return {0, 0};
  if (a.view == "side") return {90, 0};
  if (a.view == "top") return {0, 90};
  if (a.view == "iso") return {45, 35.264389682754654};
  return {a.azimuth, a.elevation};
}

nlohmann::json framing_json(const ViewArgs& a, std::pair<double, double> used) {
  const bool file = !a.camera_file.empty();
  // A typed --up re-places the eye about the file's target at the (default or typed) angles.
  const bool angles = !file || a.typed("--up") || a.typed("--view") || a.typed("--azimuth") || a.typed("--elevation");
  const auto [azimuth, elevation] = used;
  const auto applied = [&](bool used, const nlohmann::json& value) { return used ? value : nlohmann::json(nullptr); };
  return {{"up", applied(!file || a.typed("--up"), a.up)},
          {"view", applied(angles && !a.view.empty(), a.view)},
          {"azimuth_deg", applied(angles, azimuth)},
          {"elevation_deg", applied(angles, elevation)},
          {"fill", applied(!file || a.typed("--fill"), a.fill)},
          {"zoom", a.zoom},
          {"camera_file", applied(file, a.camera_file)}};
}

void add_view_options(CLI::App& app, ViewArgs& a) {
  a.app = &app;
  app.add_option("--camera", a.camera_file, "Start from this camera JSON (as --save-camera writes, or a render report); "
                                             "options typed beside it override it");
  app.add_option("--save-camera", a.save_camera, "Write the camera used as JSON (eye, target, up, fov_y_deg, width, "
                                                 "height, near, far)");
  app.add_option("--azimuth", a.azimuth, "Camera azimuth in degrees about the up axis, from the front")
      ->check(number({.lo = -3600.0, .hi = 3600.0}))
      ->capture_default_str();
  app.add_option("--elevation", a.elevation, "Camera elevation in degrees above the plane normal to up")
      ->check(number({.lo = -90.0, .hi = 90.0}))
      ->capture_default_str();
  app.add_option("--up", a.up, "World up axis: +x -x +y -y +z -z")
      ->check(CLI::IsMember({"+x", "-x", "+y", "-y", "+z", "-z", "x", "y", "z"}))
      ->capture_default_str();
  app.add_option("--view", a.view, "Named view (overrides --azimuth/--elevation): front, side, top, iso "
                                   "(default: --azimuth/--elevation)")
      ->check(CLI::IsMember({"front", "side", "top", "iso"}));
  app.add_option("--fov", a.fov, "Vertical field of view in degrees: the lens (the distance is fitted for 40, so a "
                                 "narrower lens zooms in)")
      ->check(number({.lo = 0.001, .hi = 179.0}))
      ->capture_default_str();
  app.add_option("--zoom", a.zoom, "Magnification of the framed view")
      ->check(number({.lo = 0.01, .hi = 1000.0}))
      ->capture_default_str();
  app.add_option("--fill", a.fill, "Fraction of the smaller image side the visible geometry fills (0: frame the "
                                   "bounding sphere instead)")
      ->check(number({.lo = 0.0, .hi = 1.0}))
      ->capture_default_str();
}

VisiblePoints visible_points(const Model& model, const PolygonMesh* mesh, const Camera& camera, const VisibleOptions& o) {
  VisiblePoints out;
  std::vector<Eigen::Vector3d>& visible = out.points;
  if (!model.empty()) {
    const ReferenceScene scene(model);
    Camera probe = camera;
    const double s = double(o.probe_pixels) / std::max(camera.width, camera.height);
    probe.width = std::max(8, static_cast<int>(std::lround(camera.width * s)));
    probe.height = std::max(8, static_cast<int>(std::lround(camera.height * s)));
    ReferenceRenderOptions po;
    po.trace.cull_backfaces = o.cull;
    po.trace.slim = o.slim;
    const ReferenceImage img = render_reference(scene, probe, po);
    // A probe that sees only a few pixels (a model of sub-pixel specks, such as a fit far below
    // its cloud's sampling) cannot tell where the geometry is: the camera stays as placed (the
    // bounding box framed, or a camera file's).
    constexpr std::ptrdiff_t kFewestPixels = 64;
    const std::ptrdiff_t covered = std::count_if(img.coverage.begin(), img.coverage.end(), [](auto v) { return v != 0; });
    out.covered = std::size_t(covered);
    if (covered < kFewestPixels) log::debug("framing: the probe covers {} pixels: framing the bounds", covered);
    for (int y = 0; y < img.height && covered >= kFewestPixels; ++y)
      for (int x = 0; x < img.width; ++x)
        if (const std::size_t i = std::size_t(y) * img.width + x; img.coverage[i]) {
          // Pixel corners too, so the bounds are those of the covered pixels, not their centres.
          for (const double dx : {0.0, 1.0})
            for (const double dy : {0.0, 1.0}) visible.push_back(probe.pixel_ray(x + dx, y + dy).at(img.distance[i]));
        }
  }
  if (mesh) {
    out.mesh = true;
    const std::size_t step = std::max<std::size_t>(1, mesh->vertices.size() / 200000);
    for (std::size_t v = 0; v < mesh->vertices.size(); v += step) visible.push_back(mesh->vertices[v]);
  }
  return out;
}

bool wants_fill(const ViewArgs& a) { return a.fill > 0 && (a.camera_file.empty() || a.typed("--fill")); }

Camera resolve_camera(const ViewArgs& a, const Box3& box, int width, int height, bool size_typed,
                      const VisibleFn& visible, bool skip_fill, std::pair<double, double>* used) {
  auto [azimuth, elevation] = view_angles(a);
  const bool angles_typed = a.typed("--view") || a.typed("--azimuth") || a.typed("--elevation");
  Camera camera;
  std::optional<VisiblePoints> seen;  // what the camera as placed sees, where asked already
  if (a.camera_file.empty()) {
    // About the chosen up axis, the distance fitted for a 40° lens.
    constexpr double kFitFov = 40.0;
    const auto framed = [&](double az, double el) {
      return frame_view(box, {.up = parse_axis(a.up), .azimuth_deg = az, .elevation_deg = el, .fov_y_deg = kFitFov,
                              .fit_fov_y_deg = kFitFov, .zoom = 1.0, .margin = 1.05, .width = width, .height = height});
    };
    camera = framed(azimuth, elevation);
    if (!angles_typed && (seen = visible(camera))->nothing_seen()) {
      const std::pair<double, double> turns[] = {{azimuth + 180.0, elevation}, {azimuth, -elevation}, {azimuth + 180.0, -elevation}};
      for (const auto& [az, el] : turns)
        if (const Camera c = framed(az, el); !(seen = visible(c))->nothing_seen()) {
          log::warn("nothing of the scene is seen from the default view (azimuth {:g}, elevation {:g}: an open surface "
                    "seen from behind, whose blend draws the side its normals face only); viewed from azimuth {:g}, "
                    "elevation {:g} instead (--azimuth and --elevation choose)",
                    azimuth, elevation, std::fmod(az, 360.0), el);
          camera = c, azimuth = std::fmod(az, 360.0), elevation = el;
          break;
        }
      // None shows anything: the default stays, and what it sees (nothing) is what seen holds.
    }
  } else {
    camera = read_camera(a.camera_file);
    if (size_typed) camera.width = width, camera.height = height;
    if (a.typed("--up") || angles_typed) {
      const Eigen::Vector3d up = a.typed("--up") ? parse_axis(a.up) : Eigen::Vector3d(camera.up);
      camera = place(camera, up, azimuth, elevation);
    }
  }
  if (!skip_fill && wants_fill(a)) camera = fit_points(camera, (seen ? *seen : visible(camera)).points, a.fill);
  if (a.camera_file.empty() || a.typed("--fov")) camera.fov_y_deg = a.fov;
  camera.fov_y_deg = zoomed(camera.fov_y_deg, a.zoom);
  if (used) *used = {azimuth, elevation};
  return camera;
}

Eigen::Vector3d turntable_axis(const ViewArgs& a, const Camera& base) {
  if (a.camera_file.empty() || a.typed("--up")) return parse_axis(a.up);
  return base.up.normalized();
}

std::vector<Camera> turntable_cameras(const Camera& base, const Eigen::Vector3d& axis, int n, double fill,
                                      const VisibleFn& visible) {
  std::vector<Camera> frames;
  const Eigen::Vector3d k = axis.normalized();
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(2.0 * std::numbers::pi * i / n, k).toRotationMatrix();
    Camera c = base;
    c.eye = base.target + R * (base.eye - base.target);
    c.up = R * base.up;
    frames.push_back(c);
  }
  if (!(fill > 0)) return frames;
  // One distance for all frames: bisect the scale of the eye's offset until the widest frame
  // spans `fill` around the centre.
  std::vector<std::vector<Eigen::Vector3d>> points;
  for (const Camera& c : frames) points.push_back(visible(c).points);
  const auto scaled = [&](const Camera& c, double s) {
    Camera d = c;
    d.eye = c.target + s * (c.eye - c.target);
    return d;
  };
  const auto widest = [&](double s, double* zmin, double* zmax) {
    double e = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) e = std::max(e, centred_extent(scaled(frames[i], s), points[i], zmin, zmax));
    return e;
  };
  double lo = 1e-3, hi = 1.0, zmin = INFINITY, zmax = 0;
  while (widest(hi, &zmin, &zmax) > fill && hi < 1e6) lo = hi, hi *= 2;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    double z0 = INFINITY, z1 = 0;
    (widest(mid, &z0, &z1) > fill ? lo : hi) = mid;
  }
  zmin = INFINITY, zmax = 0;
  widest(hi, &zmin, &zmax);
  for (Camera& c : frames) {
    c = scaled(c, hi);
    const double dist = (c.eye - c.target).norm();
    if (std::isfinite(zmin) && zmax > 0) {
      c.near_plane = std::max(0.5 * zmin, dist * 1e-3);
      c.far_plane = std::max(2.0 * zmax, c.near_plane * 2);
    }
  }
  return frames;
}

Camera read_camera(const std::filesystem::path& path) {
  const std::string text = read_file(path, 1 << 20);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw FormatError(fmt::format("{}: byte {}: not JSON", path.string(), e.byte));
  }
  if (j.is_object() && !j.contains("eye") && j.contains("render") && j["render"].is_object() &&
      j["render"].contains("camera"))
    j = j["render"]["camera"];  // a render report
  if (!j.is_object()) throw FormatError(fmt::format("{}: camera: expected a JSON object", path.string()));
  Camera c;
  c.eye = vector_at(j, path, "eye");
  c.target = vector_at(j, path, "target");
  c.up = vector_at(j, path, "up");
  c.fov_y_deg = number_at(j, path, "fov_y_deg");
  c.width = pixels_at(j, path, "width");
  c.height = pixels_at(j, path, "height");
  c.near_plane = number_at(j, path, "near");
  c.far_plane = number_at(j, path, "far");
  const auto bad = [&](const char* name, const std::string& why) {
    return FormatError(fmt::format("{}: camera: key '{}': {}", path.string(), name, why));
  };
  if ((c.eye - c.target).norm() == 0) throw bad("target", "equals the eye");
  if (c.up.norm() == 0) throw bad("up", "is the zero vector");
  if (c.up.normalized().cross(c.forward()).norm() < 1e-9) throw bad("up", "is parallel to the viewing direction");
  if (!(c.fov_y_deg > 0 && c.fov_y_deg < 179)) throw bad("fov_y_deg", fmt::format("{} is outside (0, 179)", c.fov_y_deg));
  if (!(c.near_plane > 0)) throw bad("near", fmt::format("{} is not > 0", c.near_plane));
  if (!(c.far_plane > c.near_plane)) throw bad("far", fmt::format("{} is not > near ({})", c.far_plane, c.near_plane));
  return c;
}

void write_camera(const Camera& camera, const std::filesystem::path& path) {
  write_file_atomically(path, [&](std::ostream& out) { out << camera_json(camera).dump(2) << "\n"; });
}

}  // namespace quadrix::cli
