// quadrix view MODEL: an interactive GLFW window. Left drag orbits about the up axis, right drag
// pans, the wheel zooms; C toggles culling, S cycles the shading, B the SLIM ball outlines (red:
// culled), H the key light's shadows, L the silhouette and crease lines, K saves the camera as JSON, P a screenshot, R resets the view, Esc quits. The title
// shows the frame time. The first view is the one `render` gives for the same options (tight
// framing, --up, --view, --camera, …). --frames N renders N frames and exits (scripts and tests),
// --press KEYS presses keys after the first frame. --animate NAME=FROM:TO:SECONDS sweeps a
// parameter of the implicit surfaces from FROM to TO and back every 2·SECONDS ([Singh10] dynamic
// surfaces: a uniform per frame, nothing recompiled); with --frames the clock runs at 30 frames
// per second of animation.
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <numbers>
#include <optional>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <fmt/format.h>

#include "core/error.h"
#include "core/image.h"
#include "core/implicit/expression.h"
#include "core/implicit/gallery.h"
#include "core/log.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "core/slim.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tools/cli.h"
#include "tools/scene_input.h"
#include "tools/view_options.h"

namespace quadrix::cli {
namespace {

// The window's camera: the resolved start view, then orbit (about the up axis through the
// target), pan and zoom (the distance) applied to it.
struct ViewState {
  Camera start;
  Camera camera;
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();  // the orbit axis
  render::RenderOptions options;
  double last_x = 0, last_y = 0;
  bool rotating = false, panning = false;
  std::string camera_file = "quadrix-camera.json", screenshot_file = "quadrix-screenshot.png";
  bool save_camera = false, save_screenshot = false;  // requested by K / P, done after the frame
  int saved_cameras = 0, saved_screenshots = 0;

  // The camera at the window's size (the lens and the view kept).
  Camera at_size(int w, int h) const {
    Camera c = camera;
    c.width = std::max(w, 1);
    c.height = std::max(h, 1);
    return c;
  }
  void orbit(double dx, double dy) {
    const Eigen::Vector3d offset = camera.eye - camera.target;
    const Eigen::Vector3d f = -offset.normalized();
    Eigen::Vector3d right = f.cross(camera.up);
    if (right.squaredNorm() < 1e-24) return;
    right.normalize();
    // Azimuth about the up axis; elevation about the right axis, kept off the poles.
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(-dx * std::numbers::pi / 450.0, up).toRotationMatrix();
    Eigen::Vector3d o = turn * offset, u = turn * camera.up;
    const Eigen::Vector3d r = turn * right;
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(-dy * std::numbers::pi / 450.0, r).toRotationMatrix();
    const Eigen::Vector3d o2 = tilt * o;
    if (std::abs(o2.normalized().dot(up)) < 0.999) o = o2, u = tilt * u;
    camera.eye = camera.target + o;
    camera.up = std::abs(u.dot(up)) > 1e-6 ? up : u;  // keep the world up once off a top view
  }
  void pan(double dx, double dy, int height) {
    const Eigen::Vector3d f = camera.forward(), r = f.cross(camera.up).normalized(), u = r.cross(f);
    const double k = 2.0 * (camera.eye - camera.target).norm() * std::tan(camera.fov_y_deg * std::numbers::pi / 360.0) /
                     std::max(height, 1);
    const Eigen::Vector3d d = k * (-dx * r + dy * u);
    camera.eye += d, camera.target += d;
  }
  void zoom(double factor) {
    const Eigen::Vector3d offset = camera.eye - camera.target;
    camera.eye = camera.target + factor * offset;
    camera.near_plane *= factor, camera.far_plane *= factor;
  }
  void key(int key) {
    if (key == GLFW_KEY_C) options.cull = !options.cull;
    if (key == GLFW_KEY_B) options.slim_outlines = !options.slim_outlines;
    if (key == GLFW_KEY_H) options.shadows = !options.shadows;
    if (key == GLFW_KEY_L) options.outlines = !options.outlines;
    if (key == GLFW_KEY_S) options.shading = static_cast<render::Shading>((static_cast<int>(options.shading) + 1) % 3);
    if (key == GLFW_KEY_R) camera = start;
    if (key == GLFW_KEY_K) save_camera = true;
    if (key == GLFW_KEY_P) save_screenshot = true;
  }
};

// One --animate NAME=FROM:TO:SECONDS.
struct Animation {
  std::string name;
  double from = 0, to = 0, seconds = 1;
  /// Triangle wave: FROM at t = 0, TO at t = SECONDS, FROM again at 2·SECONDS.
  double at(double t) const {
    const double u = std::fmod(t / seconds, 2.0);
    return from + (to - from) * (u <= 1 ? u : 2 - u);
  }
};

Animation parse_animation(const std::string& text) {
  const auto eq = text.find('=');
  Animation a;
  bool ok = eq != std::string::npos && eq > 0;
  if (ok) {
    a.name = text.substr(0, eq);
    std::string rest = text.substr(eq + 1);
    double* out[3] = {&a.from, &a.to, &a.seconds};
    for (int k = 0; k < 3 && ok; ++k) {
      const auto colon = k < 2 ? rest.find(':') : std::string::npos;
      const std::string field = rest.substr(0, colon);
      char* end = nullptr;
      *out[k] = std::strtod(field.c_str(), &end);
      ok = !field.empty() && *end == '\0' && std::isfinite(*out[k]) && (k < 2 || colon == std::string::npos);
      if (k < 2) ok = ok && colon != std::string::npos, rest = ok ? rest.substr(colon + 1) : rest;
    }
    ok = ok && a.seconds > 0;
  }
  if (!ok)
    throw CLI::ValidationError("--animate",
                               fmt::format("expected NAME=FROM:TO:SECONDS (finite numbers, SECONDS > 0), got '{}'", text));
  return a;
}

}  // namespace

void add_view(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand("view", "Open an interactive window (GLFW) on a model");
  struct Args {
    std::string model, mesh, size = "960x720", screenshot, shading = "phong", press;
    std::string style, colour_by;  // a molecule MODEL's glyphs (empty: as render's defaults)
    ViewArgs view;  // camera options shared with `render`
    int frames = 0;
    std::string surface;
    std::vector<std::string> animate;
    bool no_cull = false;
    std::string background = "255,255,255";
    bool outlines = false;
    bool shadows = false, lines = false;
    double pixel_error = render::RenderOptions{}.slim_pixel_error;
  };
  auto a = std::make_shared<Args>();
  app->add_option("MODEL", a->model, "What render draws: a model (.qxm, .slim2t), a molecule (.pdb/.ent/.cif/.mmcif, "
                                    "optionally .gz) as glyphs, or a mesh (.ply/.obj/.off/.stl) as flat triangles; "
                                    "optional with --surface");
  app->add_option("--surface", a->surface, "Also draw this built-in implicit surface (render --surface list)");
  app->add_option("--animate", a->animate,
                  "Sweep a parameter of the implicit surfaces, NAME=FROM:TO:SECONDS, there and back (repeat)")
      ->default_str("");
  app->add_option("--mesh", a->mesh, "Also draw this triangle/polygon mesh (OBJ/OFF/PLY/STL), depth-correct");
  add_molecule_style_option(*app, a->style);
  app->add_option("--colour-by", a->colour_by, "A molecule MODEL's atoms by element (CPK), chain or residue, as "
                                              "convert glyphs (default: element)")
      ->check(CLI::IsMember({"element", "chain", "residue"}))
      ->default_str("");
  app->add_option("--size", a->size, "Window size WxH, or N for N×N")->capture_default_str();
  add_view_options(*app, a->view);
  app->add_option("--shading", a->shading, "phong, envmap or npr")
      ->check(CLI::IsMember({"phong", "envmap", "npr"}))
      ->capture_default_str();
  app->add_flag("--no-cull", a->no_cull, "Start with culling off");
  app->add_option("--background", a->background, "Background R,G,B, as render's (a window has no transparency)")
      ->capture_default_str();
  app->add_option("--pixel-error", a->pixel_error, "SLIM level of detail for models with a hierarchy: each frame "
                                                   "draws the coarsest balls whose error projects below P pixels "
                                                   "(0: full detail)")
      ->check(number({.lo = 0, .hi = 1000}))
      ->capture_default_str();
  app->add_flag("--outlines", a->outlines, "Start with the SLIM ball outlines shown (key B)");
  app->add_flag("--shadows", a->shadows, "Start with the key light's shadows (key H), as render --shadows");
  app->add_flag("--lines", a->lines, "Start with silhouette and crease lines (key L), as render --outlines");
  app->add_option("--frames", a->frames, "Render this many frames, then exit (0: until closed)")
      ->check(non_negative())
      ->capture_default_str();
  app->add_option("--screenshot", a->screenshot, "Save the last frame as PNG; key P saves the current one here "
                                                 "(default for P: quadrix-screenshot.png)");
  app->add_option("--press", a->press, "Keys pressed after the first frame, e.g. 'kp' (scripts and tests)");
  commands.push_back({app, [a](const CommonOptions&, Report& report) {
                        const auto [w, h] = parse_size(a->size);
                        if (a->model.empty() && a->surface.empty())
                          throw CLI::ValidationError("MODEL", "give a MODEL or --surface");
                        // What render reads from the same arguments (tools/scene_input.h).
                        Scene scene = read_scene(
                            {.model = a->model, .mesh = a->mesh, .style = a->style, .colour_by = a->colour_by});
                        Model model = std::move(scene.model);
                        const std::optional<PolygonMesh> mesh = std::move(scene.mesh);
                        if (!a->surface.empty()) {
                          try {
                            model.implicits.push_back(implicit::gallery_surface(a->surface).surface);
                          } catch (const InvalidInput& e) {
                            throw CLI::ValidationError("--surface", e.what());
                          }
                        }
                        // Each animation drives the surfaces whose expression names its parameter.
                        std::vector<Animation> animations;
                        std::vector<std::vector<std::size_t>> animated;
                        for (const auto& text : a->animate) {
                          animations.push_back(parse_animation(text));
                          animated.emplace_back();
                          for (std::size_t i = 0; i < model.implicits.size(); ++i) {
                            const auto names = implicit::Expression::parse(model.implicits[i].expression).parameters();
                            if (std::find(names.begin(), names.end(), animations.back().name) != names.end())
                              animated.back().push_back(i);
                          }
                          if (animated.back().empty())
                            throw CLI::ValidationError("--animate", fmt::format("no implicit surface has a parameter '{}'",
                                                                                animations.back().name));
                          for (std::size_t i : animated.back())
                            model.implicits[i].parameters[animations.back().name] = animations.back().from;
                        }
                        const std::string title = a->model.empty() ? a->surface : a->model;
                        Box3 box = bounds(model);
                        if (mesh)
                          for (const auto& v : mesh->vertices) box.extend(v);
                        ViewState st;
                        st.options.cull = !a->no_cull;
                        st.options.background = parse_rgb(a->background, "--background");
                        st.options.slim_outlines = a->outlines;
                        st.options.shadows = a->shadows;
                        st.options.outlines = a->lines;
                        st.options.shading = a->shading == "envmap" ? render::Shading::envmap
                                             : a->shading == "npr"  ? render::Shading::npr
                                                                    : render::Shading::phong;
                        const SlimBlendOptions blend = slim_blend_of(model);
                        st.options.set_slim_blend(blend);
                        st.options.slim_pixel_error = a->pixel_error;
                        // The start view as `render` resolves it (tools/view_options.h).
                        const VisibleFn visible = [&](const Camera& c) {
                          return visible_points(model, mesh ? &*mesh : nullptr, c,
                                                {.cull = st.options.cull, .slim = blend});
                        };
                        st.start = st.camera = resolve_camera(a->view, box, w, h, a->view.typed("--size"), visible);
                        st.up = turntable_axis(a->view, st.start);
                        if (!a->view.save_camera.empty()) st.camera_file = a->view.save_camera;
                        if (!a->screenshot.empty()) st.screenshot_file = a->screenshot;
                        auto context = render::create_context(
                            "glfw", {.width = st.start.width, .height = st.start.height, .visible = true,
                                     .title = "quadrix " + title});
                        render::Renderer renderer(*context);
                        renderer.set_model(model);
                        if (mesh) renderer.set_mesh(*mesh);
                        auto* win = static_cast<GLFWwindow*>(context->native_window());
                        glfwSetWindowUserPointer(win, &st);
                        glfwSetMouseButtonCallback(win, [](GLFWwindow* wnd, int button, int action, int) {
                          auto& s = *static_cast<ViewState*>(glfwGetWindowUserPointer(wnd));
                          glfwGetCursorPos(wnd, &s.last_x, &s.last_y);
                          if (button == GLFW_MOUSE_BUTTON_LEFT) s.rotating = action == GLFW_PRESS;
                          if (button == GLFW_MOUSE_BUTTON_RIGHT) s.panning = action == GLFW_PRESS;
                        });
                        glfwSetCursorPosCallback(win, [](GLFWwindow* wnd, double x, double y) {
                          auto& s = *static_cast<ViewState*>(glfwGetWindowUserPointer(wnd));
                          const double dx = x - s.last_x, dy = y - s.last_y;
                          s.last_x = x, s.last_y = y;
                          int ww, wh;
                          glfwGetFramebufferSize(wnd, &ww, &wh);
                          if (s.rotating) s.orbit(dx, dy);
                          else if (s.panning) s.pan(dx, dy, wh);
                        });
                        glfwSetScrollCallback(win, [](GLFWwindow* wnd, double, double dy) {
                          static_cast<ViewState*>(glfwGetWindowUserPointer(wnd))->zoom(std::pow(0.9, dy));
                        });
                        glfwSetKeyCallback(win, [](GLFWwindow* wnd, int key, int, int action, int) {
                          if (action != GLFW_PRESS) return;
                          if (key == GLFW_KEY_ESCAPE || key == GLFW_KEY_Q) glfwSetWindowShouldClose(wnd, GLFW_TRUE);
                          static_cast<ViewState*>(glfwGetWindowUserPointer(wnd))->key(key);
                        });
                        int frame = 0, cut_uploads = 0;
                        std::uint64_t slim_balls = 0;
                        double ms = 0;
                        const double start = glfwGetTime();
                        std::map<std::string, double> values;
                        while (!context->should_close() && (a->frames == 0 || frame < a->frames)) {
                          int fw, fh;
                          glfwGetFramebufferSize(win, &fw, &fh);
                          const double t = a->frames > 0 ? frame / 30.0 : glfwGetTime() - start;
                          for (std::size_t k = 0; k < animations.size(); ++k) {
                            values[animations[k].name] = animations[k].at(t);
                            for (std::size_t i : animated[k])
                              renderer.set_implicit_parameters(i, {{animations[k].name, values[animations[k].name]}});
                          }
                          const Camera camera = st.at_size(fw, fh);
                          const auto stats = renderer.draw(camera, st.options);
                          ms = stats.ms_total;
                          cut_uploads += stats.slim_cut_uploaded;
                          slim_balls = stats.slim_balls;
                          // Saved files land when the window closes, with the command's other outputs.
                          if (st.save_screenshot) write_png(renderer.read_colour(), st.screenshot_file), ++st.saved_screenshots;
                          if (st.save_camera) write_camera(camera, st.camera_file), ++st.saved_cameras;
                          st.save_camera = st.save_screenshot = false;
                          renderer.present(fw, fh);
                          context->swap_buffers();
                          std::string shown;
                          for (const auto& [k, v] : values) shown += fmt::format(", {} = {:.4g}", k, v);
                          if (!model.slim_hierarchy.empty()) shown += fmt::format(", {} SLIM balls", slim_balls);
                          glfwSetWindowTitle(win, fmt::format("quadrix {} — {:.1f} ms/frame, culling {}{}", title, ms,
                                                              st.options.cull ? "on" : "off", shown)
                                                      .c_str());
                          glfwPollEvents();
                          if (frame == 0)
                            for (const char c : a->press)
                              if (std::isalpha(static_cast<unsigned char>(c)))
                                st.key(GLFW_KEY_A + (std::toupper(static_cast<unsigned char>(c)) - 'A'));
                          ++frame;
                        }
                        int fw, fh;
                        glfwGetFramebufferSize(win, &fw, &fh);
                        if (!a->screenshot.empty()) write_png(renderer.read_colour(), a->screenshot);
                        if (!a->view.save_camera.empty()) write_camera(st.at_size(fw, fh), a->view.save_camera);
                        report.json["view"] = {{"frames", frame}, {"ms_last_frame", ms}, {"context", context->description()},
                                               {"camera", camera_json(st.at_size(fw, fh))},
                                               {"input", scene_input_name(scene.kind)}};
                        if (scene.kind == SceneInputKind::molecule) report.json["view"]["molecule"] = molecule_json(model);
                        if (!values.empty()) report.json["view"]["parameters_last_frame"] = values;
                        if (!model.slim_hierarchy.empty())
                          report.json["view"]["slim_lod"] = {{"pixel_error", a->pixel_error},
                                                             {"balls_last_frame", slim_balls},
                                                             {"cut_uploads", cut_uploads}};
                        report.summary = fmt::format("{} frames, {} screenshots, {} cameras saved", frame,
                                                     st.saved_screenshots + !a->screenshot.empty(),
                                                     st.saved_cameras + !a->view.save_camera.empty());
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
