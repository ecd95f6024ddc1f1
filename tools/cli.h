#pragma once
/// Shared pieces of the `quadrix` subcommands: exit codes, common options, the JSON report
/// and the progress bar. One file per subcommand (tools/cmd_*.cpp) registers itself through
/// a `void add_NAME(CLI::App& root, Commands& commands)` function listed in main.cpp.
#include <chrono>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "core/camera.h"
#include "core/model.h"
#include "core/model_io.h"

namespace quadrix::cli {

/// Documented in the README; distinct per failure kind.
enum ExitCode : int {
  kOk = 0,
  kInternal = 1,     ///< a bug: unexpected exception
  kUsage = 2,        ///< bad command line
  kBadInput = 3,     ///< an input file is malformed, or input data is unusable (InvalidInput)
  kComputation = 4,  ///< a solver or computation failed (SolverError)
  kIo = 5,           ///< a file could not be read or written (IoError)
  kGl = 6,           ///< no usable OpenGL context or GL failure (GlError)
  kExceeded = 7,     ///< finished, output written, but outside the requested bound
};

/// Options every subcommand has.
struct CommonOptions {
  bool quiet = false;
  int verbose = 0;
  std::string report;  ///< --report FILE.json
};

/// Figures a command measured; written to --report FILE.json (temporary file + rename).
struct Report {
  nlohmann::json json = nlohmann::json::object();
  /// Seconds since the command started.
  double elapsed() const;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  /// One line main prints on stderr after a success unless --quiet: what was written, counts
  /// (main appends the time).
  std::string summary;
  /// Exit 7 (finished outside the requested bound): what was not reached, the report's "error".
  std::string exceeded;
};

/// A text progress bar on stderr, shown only when stderr is a terminal, not --quiet, and the work
/// has run for more than about a second; redrawn every 250 ms with the last fraction reported
/// and the elapsed time, so it moves between fractions too. Thread-safe update().
class Progress {
public:
  Progress(std::string label, bool enabled);
  /// Work that reports no fractions (a fit, a skin): a background thread shows the label, a
  /// moving marker and the elapsed time until destruction.
  struct Indeterminate {};
  Progress(std::string label, bool enabled, Indeterminate);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void update(double fraction);
  std::function<void(double)> callback() {
    return [this](double f) { update(f); };
  }

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A registered subcommand: its CLI11 app and the action run after parsing.
struct Command {
  CLI::App* app = nullptr;
  std::function<int(const CommonOptions&, Report&)> run;
};
using Commands = std::vector<Command>;

/// Adds --quiet, --verbose and --report to a subcommand.
void add_common_options(CLI::App& app, CommonOptions& options);

/// Adds --encoding compact|double (the .qxm encoding, core/model_io.h) to a command that writes
/// a model; the default is WriteModelOptions's.
void add_encoding_option(CLI::App& app, WriteModelOptions& options);

/// The view as reports record it, enough for another tool to reproduce it: eye, target, up
/// (world units), fov_y_deg (vertical), width and height (pixels), near and far (world units).
/// A right-handed look-at camera; pixel (i, j) is centred at (i + ½, j + ½), row 0 at the top.
nlohmann::json camera_json(const Camera& camera);

/// Bounds of a numeric option; unset ends are unbounded. Open ends exclude the bound: (0, 1) is
/// {.lo = 0, .hi = 1, .open_lo = true, .open_hi = true}.
struct NumberRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool open_lo = false;
  bool open_hi = false;
};

/// A CLI11 validator for every numeric option (each element of a list option): the value must be a
/// finite number (no nan, inf) inside the range; the message names the value and the range as
/// "[lo, hi]" / "(lo, hi)". CLI11 puts the option's name in front, and main maps it to exit 2.
CLI::Validator number(NumberRange range = {});
/// Shorthands: any finite number; > 0; ≥ 0.
inline CLI::Validator finite() { return number(); }
inline CLI::Validator positive() { return number({.lo = 0, .open_lo = true}); }
inline CLI::Validator non_negative() { return number({.lo = 0}); }

/// A CLI11 validator for an output model file: its name must end in .qxm (any case), so a typo
/// such as `-o bunny.ply` (a mesh is `quadrix mesh`'s output) is refused with exit 2 instead of
/// writing a .qxm under another name.
CLI::Validator qxm_output();

/// Parses "WxH" (e.g. 1024x768). \throws CLI::ValidationError.
std::pair<int, int> parse_size(const std::string& text);

/// Parses "R,G,B" with components 0..255 (option names the option in the message).
/// \throws CLI::ValidationError.
Rgb parse_rgb(const std::string& text, const std::string& option = "--colour");

/// The command line as typed ("quadrix fit 'my scan.ply' -o m.qxm"; arguments with spaces or
/// shell characters single-quoted), for the `producer` metadata of written models. Set by main.
const std::string& command_line();
void set_command_line(int argc, const char* const* argv);

/// True when progress output is allowed (stderr is a terminal and not quiet).
bool progress_allowed(const CommonOptions& options);

}  // namespace quadrix::cli
