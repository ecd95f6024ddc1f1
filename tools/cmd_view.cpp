// quadrix view MODEL: an interactive GLFW window. Left drag orbits, right drag pans, the wheel
// zooms; C toggles culling, S cycles the shading, B the SLIM ball outlines (red: culled), R
// resets the view, Esc quits. The title shows
// the frame time. --frames N renders N frames and exits (scripts and tests), --screenshot saves
// the last frame. --animate NAME=FROM:TO:SECONDS sweeps a parameter of the implicit surfaces
// from FROM to TO and back every 2·SECONDS ([Singh10] dynamic surfaces: a uniform per frame,
// nothing recompiled); with --frames the clock runs at 30 frames per second of animation.
#include <cmath>
#include <cstdlib>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <fmt/format.h>

#include "convert/molecule.h"
#include "convert/molecule_glyphs.h"
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

namespace quadrix::cli {
namespace {

struct ViewState {
  FramingOptions framing;
  Box3 box;
  Eigen::Vector3d pan = Eigen::Vector3d::Zero();
  double zoom = 1.0;
  render::RenderOptions options;
  double last_x = 0, last_y = 0;
  bool rotating = false, panning = false;

  Camera camera(int w, int h) const {
    FramingOptions f = framing;
    f.width = std::max(w, 1);
    f.height = std::max(h, 1);
    Camera c = frame_box(box, f);
    const Eigen::Vector3d dir = c.eye - c.target;
    c.target += pan;
    c.eye = c.target + zoom * dir;
    c.near_plane = std::max(c.near_plane * zoom, 1e-6 * dir.norm());
    c.far_plane *= std::max(1.0, zoom);
    return c;
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
    std::string model, mesh, size = "960x720", screenshot, shading = "phong";
    double azimuth = 30, elevation = 20, fov = 40;
    int frames = 0;
    std::string surface;
    std::vector<std::string> animate;
    bool no_cull = false;
    bool outlines = false;
  };
  auto a = std::make_shared<Args>();
  app->add_option("MODEL", a->model, "Model file (.qxm); optional with --surface");
  app->add_option("--surface", a->surface, "Also draw this built-in implicit surface (render --surface list)");
  app->add_option("--animate", a->animate,
                  "Sweep a parameter of the implicit surfaces, NAME=FROM:TO:SECONDS, there and back (repeat)");
  app->add_option("--mesh", a->mesh, "Also draw this mesh");
  app->add_option("--size", a->size, "Window size WxH");
  app->add_option("--azimuth", a->azimuth, "Initial azimuth (degrees)")->check(finite());
  app->add_option("--elevation", a->elevation, "Initial elevation (degrees)")->check(number({.lo = -89.9, .hi = 89.9}));
  app->add_option("--fov", a->fov, "Vertical field of view (degrees)")->check(number({.lo = 0.001, .hi = 179}));
  app->add_option("--shading", a->shading, "phong, envmap or npr")->check(CLI::IsMember({"phong", "envmap", "npr"}));
  app->add_flag("--no-cull", a->no_cull, "Start with culling off");
  app->add_flag("--outlines", a->outlines, "Start with the SLIM ball outlines shown (key B)");
  app->add_option("--frames", a->frames, "Render this many frames, then exit (0: until closed)")->check(non_negative());
  app->add_option("--screenshot", a->screenshot, "Save the last frame as PNG");
  commands.push_back({app, [a](const CommonOptions&, Report& report) {
                        const auto [w, h] = parse_size(a->size);
                        if (a->model.empty() && a->surface.empty())
                          throw CLI::ValidationError("MODEL", "give a MODEL or --surface");
                        Model model = a->model.empty()              ? Model{}
                                      : is_molecule_file(a->model) ? read_molecule_glyphs(a->model)
                                                                   : read_model(a->model);
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
                        std::optional<PolygonMesh> mesh;
                        if (!a->mesh.empty()) mesh = read_mesh(a->mesh);
                        ViewState st;
                        st.box = bounds(model);
                        if (mesh)
                          for (const auto& v : mesh->vertices) st.box.extend(v);
                        st.framing = {.azimuth_deg = a->azimuth, .elevation_deg = a->elevation, .fov_y_deg = a->fov};
                        st.options.cull = !a->no_cull;
                        st.options.slim_outlines = a->outlines;
                        st.options.shading = a->shading == "envmap" ? render::Shading::envmap
                                             : a->shading == "npr"  ? render::Shading::npr
                                                                    : render::Shading::phong;
                        auto context = render::create_context(
                            "glfw", {.width = w, .height = h, .visible = true, .title = "quadrix " + (a->model.empty() ? a->surface : a->model)});
                        render::Renderer renderer(*context);
                        renderer.set_model(model);
                        st.options.slim_offset = static_cast<float>(slim_offset_of(model));
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
                          if (s.rotating) {
                            s.framing.azimuth_deg -= 0.4 * dx;
                            s.framing.elevation_deg = std::clamp(s.framing.elevation_deg + 0.4 * dy, -89.0, 89.0);
                          } else if (s.panning) {
                            int ww, wh;
                            glfwGetFramebufferSize(wnd, &ww, &wh);
                            const Camera c = s.camera(ww, wh);
                            const Eigen::Vector3d f = c.forward(), r = f.cross(c.up).normalized(), u = r.cross(f);
                            const double k = 2.0 * (c.eye - c.target).norm() *
                                             std::tan(c.fov_y_deg * 3.14159265358979 / 360.0) / std::max(wh, 1);
                            s.pan += k * (-dx * r + dy * u);
                          }
                        });
                        glfwSetScrollCallback(win, [](GLFWwindow* wnd, double, double dy) {
                          auto& s = *static_cast<ViewState*>(glfwGetWindowUserPointer(wnd));
                          s.zoom = std::clamp(s.zoom * std::pow(0.9, dy), 1e-4, 1e4);
                        });
                        glfwSetKeyCallback(win, [](GLFWwindow* wnd, int key, int, int action, int) {
                          if (action != GLFW_PRESS) return;
                          auto& s = *static_cast<ViewState*>(glfwGetWindowUserPointer(wnd));
                          if (key == GLFW_KEY_ESCAPE || key == GLFW_KEY_Q) glfwSetWindowShouldClose(wnd, GLFW_TRUE);
                          if (key == GLFW_KEY_C) s.options.cull = !s.options.cull;
                          if (key == GLFW_KEY_B) s.options.slim_outlines = !s.options.slim_outlines;
                          if (key == GLFW_KEY_S)
                            s.options.shading = static_cast<render::Shading>((static_cast<int>(s.options.shading) + 1) % 3);
                          if (key == GLFW_KEY_R) s.pan.setZero(), s.zoom = 1.0;
                        });
                        int frame = 0;
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
                          const auto stats = renderer.draw(st.camera(fw, fh), st.options);
                          ms = stats.ms_total;
                          renderer.present(fw, fh);
                          context->swap_buffers();
                          std::string shown;
                          for (const auto& [k, v] : values) shown += fmt::format(", {} = {:.4g}", k, v);
                          glfwSetWindowTitle(win, fmt::format("quadrix {} — {:.1f} ms/frame, culling {}{}",
                                                              a->model.empty() ? a->surface : a->model, ms,
                                                              st.options.cull ? "on" : "off", shown)
                                                      .c_str());
                          glfwPollEvents();
                          ++frame;
                        }
                        if (!a->screenshot.empty()) write_png(renderer.read_colour(), a->screenshot);
                        report.json["view"] = {{"frames", frame}, {"ms_last_frame", ms}, {"context", context->description()}};
                        if (!values.empty()) report.json["view"]["parameters_last_frame"] = values;
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
