#pragma once
/// The view options `render` and `view` share: --camera FILE.json, --save-camera, --up, --view,
/// --azimuth, --elevation, --fov, --zoom, --fill; the camera they resolve to; turntable cameras;
/// camera JSON files (the schema of a render report's `render.camera`).
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/slim.h"
#include "core/camera.h"
#include "core/mesh_io.h"
#include "core/model.h"

namespace quadrix::cli {

/// Values of the shared view options; `app` remembers which were typed.
struct ViewArgs {
  std::string camera_file;       ///< --camera: the starting camera (explicit options override it)
  std::string save_camera;       ///< --save-camera: write the camera used as JSON
  std::string up = "+y";         ///< --up ±x|±y|±z
  std::string view;              ///< --view front|side|top|iso (empty: --azimuth/--elevation)
  double azimuth = 30;           ///< degrees about up, from the front
  double elevation = 20;         ///< degrees above the plane normal to up
  double fov = 40;               ///< the lens, vertical degrees (the distance is fitted for 40)
  double zoom = 1;               ///< magnification on top of the framing
  double fill = 0.9;             ///< visible geometry fills this of the smaller side (0: bounding sphere)
  const CLI::App* app = nullptr; ///< set by add_view_options; typed() asks it
  /// True when the option (e.g. "--fov") was given on the command line.
  bool typed(const std::string& option) const { return app && app->count(option) > 0; }
};

/// Azimuth and elevation in degrees: the named --view's, else --azimuth and --elevation.
std::pair<double, double> view_angles(const ViewArgs& args);

/// What framed the view, for a render report: without --camera, every view option's value (typed
/// or default); with --camera, the file and only the options typed beside it (the others null:
/// the file's camera held them), as resolve_camera applies them; `angles` are the azimuth and
/// elevation it used (turned round where the default view saw nothing).
nlohmann::json framing_json(const ViewArgs& args, std::pair<double, double> angles);

/// Adds the shared view options to a command, with their defaults shown in --help.
void add_view_options(CLI::App& app, ViewArgs& args);

/// The world points visible from a camera (covered pixels' corners back-projected), for tight
/// framing: a low-resolution CPU reference pass over the model plus the mesh's vertices.
struct VisibleOptions {
  bool cull = true;          ///< back-face culling as the render does it
  SlimBlendOptions slim;     ///< SLIM blend (the model's: core/slim.h slim_blend_of)
  int probe_pixels = 160;    ///< longer side of the probe image
};
struct VisiblePoints {
  /// The covered pixels' corners (none where the probe covers fewer than 64 pixels: too few to
  /// tell where the geometry is, so the bounds are framed), then the mesh's vertices.
  std::vector<Eigen::Vector3d> points;
  std::size_t covered = 0;  ///< probe pixels the model covers (0: nothing of it seen)
  bool mesh = false;        ///< a mesh was given (drawn whatever the view)
  bool nothing_seen() const { return covered == 0 && !mesh; }
};
VisiblePoints visible_points(const Model& model, const PolygonMesh* mesh, const Camera& camera,
                             const VisibleOptions& options = {});

/// Function giving the visible points from a camera (visible_points bound to a scene).
using VisibleFn = std::function<VisiblePoints(const Camera&)>;

/// The camera the options describe for a scene with bounds `box`, image width × height
/// (size_typed: --size was given, so it overrides a camera file's). Without --camera: framed
/// about --up from --view/--azimuth/--elevation, tightened to --fill, then --fov and --zoom as the
/// lens. With --camera: the file's camera; a typed --up, --view/--azimuth/--elevation re-places
/// the eye about the file's target at its distance, a typed --fill refits, --fov and --zoom
/// change the lens. skip_fill leaves tight framing to the caller (turntables).
/// \throws IoError (unreadable camera file), FormatError (malformed camera file, naming the key),
///         InvalidInput (an empty scene).
/// Without --camera and with no angle typed, a scene of which nothing is seen from the default
/// angles (an open surface seen from behind: SLIM's blend draws the side its normals face only, so
/// a fitted bowl seen into rendered empty, exit 0) is viewed from the first of azimuth + 180°,
/// −elevation and both that shows some of it (a warning); `angles` (when given) gets the
/// azimuth and elevation used. A scene seen only small (a few probe pixels) is not turned.
Camera resolve_camera(const ViewArgs& args, const Box3& box, int width, int height, bool size_typed,
                      const VisibleFn& visible, bool skip_fill = false, std::pair<double, double>* angles = nullptr);

/// True when the resolved camera gets tight framing (no camera file, or --fill typed) — what
/// resolve_camera skips with skip_fill.
bool wants_fill(const ViewArgs& args);

/// The axis a turntable turns about: the typed --up, else the camera file's up, else --up's default.
Eigen::Vector3d turntable_axis(const ViewArgs& args, const Camera& base);

/// n cameras turning `base` about `axis` through its target, 360°/n apart, starting at base.
/// With fill > 0 every frame keeps the target and one common distance: the smallest at which
/// each frame's visible geometry fits `fill` of the smaller side around the image centre.
std::vector<Camera> turntable_cameras(const Camera& base, const Eigen::Vector3d& axis, int n, double fill,
                                      const VisibleFn& visible);

/// Reads a camera: a JSON object with eye, target, up (3 numbers each), fov_y_deg (0, 179),
/// width and height (1..16384 pixels), near > 0 and far > near; or a render report holding one at
/// render.camera. \throws IoError when unreadable, FormatError naming the file and the key.
Camera read_camera(const std::filesystem::path& path);

/// Writes camera_json(camera) to path (atomically, with the command's other outputs).
/// \throws IoError.
void write_camera(const Camera& camera, const std::filesystem::path& path);

}  // namespace quadrix::cli
