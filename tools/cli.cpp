#include "tools/cli.h"

#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <cstdlib>
#include <cstdio>
#include <condition_variable>
#include <mutex>
#include <thread>

#include <fmt/format.h>

namespace quadrix::cli {

double Report::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Progress::Impl {
  std::string label;
  bool enabled;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  std::mutex mutex;
  int last_percent = -1;
  bool drawn = false;
  // The last fraction reported; < 0: indeterminate work.
  double fraction = -1;
  // A ticker thread until `stop`: redraws every 250 ms, so the elapsed time moves between
  // fractions too (a mesh reports one per resolution, minutes apart).
  std::thread ticker;
  std::condition_variable wake;
  bool stop = false;
  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); }
  // Seconds of work before the bar appears: 1, or QUADRIX_PROGRESS_DELAY (tests set 0).
  double delay = [] {
    const char* v = std::getenv("QUADRIX_PROGRESS_DELAY");
    return v && *v ? std::strtod(v, nullptr) : 1.0;
  }();
};

namespace {
// The bar for a fraction of the work done (the caller holds the mutex).
void draw_fraction(const std::string& label, double fraction, double secs) {
  const int percent = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 100.0);
  constexpr int width = 30;
  const int filled = percent * width / 100;
  std::fprintf(stderr, "\r%s [%s%s] %3d%% %.1fs", label.c_str(), std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), percent, secs);
  std::fflush(stderr);
}
}  // namespace

Progress::Progress(std::string label, bool enabled) : impl_(std::make_unique<Impl>()) {
  impl_->label = std::move(label);
  impl_->enabled = enabled;
  if (!enabled) return;
  impl_->ticker = std::thread([impl = impl_.get()] {
    std::unique_lock lock(impl->mutex);
    // Drawn at once, then every 250 ms: short work (under `delay`) stays silent.
    for (int tick = 0; tick == 0 || !impl->wake.wait_for(lock, std::chrono::milliseconds(250), [impl] { return impl->stop; });
         ++tick) {
      const double secs = impl->seconds();
      if (secs < impl->delay) continue;
      if (impl->fraction >= 0) {
        draw_fraction(impl->label, impl->fraction, secs);
      } else {
        constexpr int width = 30;
        std::string bar(width, '.');
        const int at = tick % (2 * width - 2);
        bar[at < width ? at : 2 * width - 2 - at] = '#';
        std::fprintf(stderr, "\r%s [%s] %.1fs", impl->label.c_str(), bar.c_str(), secs);
        std::fflush(stderr);
      }
      impl->drawn = true;
    }
  });
}

Progress::Progress(std::string label, bool enabled, Indeterminate) : Progress(std::move(label), enabled) {}

Progress::~Progress() {
  if (impl_->ticker.joinable()) {
    {
      std::lock_guard lock(impl_->mutex);
      impl_->stop = true;
    }
    impl_->wake.notify_all();
    impl_->ticker.join();
  }
  if (impl_->drawn) std::fprintf(stderr, "\r\033[K");
}

void Progress::update(double fraction) {
  if (!impl_->enabled) return;
  std::lock_guard lock(impl_->mutex);
  impl_->fraction = std::clamp(fraction, 0.0, 1.0);
  const double secs = impl_->seconds();
  if (secs < impl_->delay) return;  // short work stays silent
  const int percent = static_cast<int>(impl_->fraction * 100.0);
  if (percent == impl_->last_percent) return;
  impl_->last_percent = percent;
  draw_fraction(impl_->label, impl_->fraction, secs);
  impl_->drawn = true;
}

void add_common_options(CLI::App& app, CommonOptions& o) {
  app.add_flag("-q,--quiet", o.quiet, "No progress bar, no informational messages");
  app.add_flag("-v,--verbose", o.verbose, "More messages on stderr (repeat for debug)");
  app.add_option("--report", o.report, "Write the measured figures as JSON to this file");
}

void add_encoding_option(CLI::App& app, WriteModelOptions& o) {
  app.add_option_function<std::string>(
         "--encoding",
         [&o](const std::string& name) { o.encoding = name == "double" ? ModelEncoding::full : ModelEncoding::compact; },
         "Model encoding: compact (float32, positions relative to an origin in the header; falls back to double "
         "for a model float32 cannot hold) or double (lossless)")
      ->check(CLI::IsMember({"compact", "double"}))
      ->default_str(std::string(encoding_name(o.encoding)));
}

nlohmann::json camera_json(const Camera& c) {
  const auto vec = [](const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
  return {{"eye", vec(c.eye)},       {"target", vec(c.target)}, {"up", vec(c.up)},
          {"fov_y_deg", c.fov_y_deg}, {"width", c.width},        {"height", c.height},
          {"near", c.near_plane},     {"far", c.far_plane}};
}

namespace {
/// A typed value as echoed in a refusal: cut to 40 characters.
std::string shown_value(const std::string& text) { return text.size() > 40 ? text.substr(0, 40) + "…" : text; }
}  // namespace

CLI::Validator number(NumberRange r) {
  const bool open_lo = r.open_lo || std::isinf(r.lo), open_hi = r.open_hi || std::isinf(r.hi);
  const std::string range = fmt::format("{}{}, {}{}", open_lo ? '(' : '[', r.lo, r.hi, open_hi ? ')' : ']');
  const std::string description = open_lo && open_hi && std::isinf(r.lo) && std::isinf(r.hi) ? "finite NUMBER" : "NUMBER in " + range;
  return CLI::Validator(
      [r, range](std::string& text) -> std::string {
        const std::string shown = shown_value(text);
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size()) return fmt::format("'{}' is not a number", shown);
        if (!std::isfinite(v))
          return fmt::format("'{}' is not a finite number (expected a number in {})", shown, range);
        const bool low_ok = r.open_lo ? v > r.lo : v >= r.lo;
        const bool high_ok = r.open_hi ? v < r.hi : v <= r.hi;
        if (!low_ok || !high_ok) return fmt::format("{} is outside {}", shown, range);
        return {};
      },
      description, "number");
}

CLI::Validator qxm_output() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::string ext = std::filesystem::path(text).extension().string();
        for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
        if (ext == ".qxm") return {};
        return fmt::format("'{}' does not end in .qxm: the output is a Quadrix model (a triangle mesh is `quadrix mesh "
                           "MODEL -o FILE.ply`)",
                           shown_value(text));
      },
      "FILE.qxm", "qxm_output");
}

std::pair<int, int> parse_size(const std::string& text) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  const int read = std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra);
  if (read == 1 && text.find_first_not_of("0123456789") == std::string::npos) h = w;  // "512": a square
  else if (read != 3 || (x != 'x' && x != 'X')) w = 0;
  if (w < 1 || h < 1 || w > 16384 || h > 16384) {
    throw CLI::ValidationError("--size",
                               fmt::format("'{}' is not WxH (or N for N×N) with 1 ≤ W, H ≤ 16384", shown_value(text)));
  }
  return {w, h};
}

Rgb parse_rgb(const std::string& text, const std::string& option) {
  int r = -1, g = -1, b = -1;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%d,%d,%d%c", &r, &g, &b, &tail) != 3 || r < 0 || r > 255 || g < 0 || g > 255 ||
      b < 0 || b > 255)
    throw CLI::ValidationError(option, fmt::format("expected R,G,B with components 0..255, got '{}'", text));
  return {static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g), static_cast<std::uint8_t>(b)};
}

namespace {
std::string& typed_command_line() {
  static std::string line = "quadrix";
  return line;
}
}  // namespace

const std::string& command_line() { return typed_command_line(); }

void set_command_line(int argc, const char* const* argv) {
  std::string line = "quadrix";
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool plain = !arg.empty() && arg.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                             "0123456789-_.,/:=+@%^") == std::string_view::npos;
    line += ' ';
    if (plain) {
      line += arg;
    } else {
      line += '\'';
      for (const char c : arg) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
      line += '\'';
    }
  }
  typed_command_line() = line;
}

bool progress_allowed(const CommonOptions& o) { return !o.quiet && ::isatty(STDERR_FILENO); }

}  // namespace quadrix::cli
