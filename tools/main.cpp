// quadrix: one command for fitting, converting, rendering and inspecting quadric models.
#include <exception>
#include <iostream>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "tools/cli.h"

namespace quadrix::cli {
void add_info(CLI::App& root, Commands& commands);
void add_render(CLI::App& root, Commands& commands);
void add_synth(CLI::App& root, Commands& commands);
void add_fit(CLI::App& root, Commands& commands);
void add_view(CLI::App& root, Commands& commands);
void add_convert(CLI::App& root, Commands& commands);
void add_bench(CLI::App& root, Commands& commands);
void add_mesh(CLI::App& root, Commands& commands);
void add_tetrahedralize(CLI::App& root, Commands& commands);

namespace {
// An error message as printed: control bytes (a file's content echoed by a reader that did not
// escape it) as \xNN, so nothing reaches the terminal raw; newlines kept.
std::string printable(std::string_view message) {
  std::string out;
  out.reserve(message.size());
  for (const char c : message) {
    const auto u = static_cast<unsigned char>(c);
    if ((u < 0x20 && c != '\n' && c != '\t') || u == 0x7f) out += fmt::format("\\x{:02x}", u);
    else out += c;
  }
  return out;
}
}  // namespace
}  // namespace quadrix::cli

int main(int argc, char** argv) {
  using namespace quadrix;
  using namespace quadrix::cli;
  CLI::App app{"quadrix — fit, convert and ray-cast quadric surface models"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "quadrix 0.1.0");
  Commands commands;
  add_info(app, commands);
  add_render(app, commands);
  add_synth(app, commands);
  add_fit(app, commands);
  add_view(app, commands);
  add_convert(app, commands);
  add_bench(app, commands);
  add_mesh(app, commands);
  add_tetrahedralize(app, commands);
  CommonOptions common;
  for (auto& c : commands) add_common_options(*c.app, common);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? kOk : kUsage;
  }
  log::set_level(common.quiet ? log::Level::error
                 : common.verbose >= 2 ? log::Level::debug
                 : common.verbose == 1 ? log::Level::info
                                       : log::Level::warn);
  Report report;
  int rc = kInternal;
  const char* kind = "internal error";
  try {
    // Every output of the command lands together at the end, or none does.
    OutputTransaction outputs;
    for (auto& c : commands) {
      if (!c.app->parsed()) continue;
      report.json["command"] = c.app->get_name();
      rc = c.run(common, report);
      kind = nullptr;
      break;
    }
    kind = "internal error";
    if (rc == kOk || rc == kExceeded) outputs.commit();
    kind = nullptr;
  } catch (const FormatError& e) {
    std::cerr << "quadrix: bad input: " << printable(e.what()) << "\n";
    rc = kBadInput;
  } catch (const InvalidInput& e) {
    std::cerr << "quadrix: invalid input: " << printable(e.what()) << "\n";
    rc = kBadInput;
  } catch (const IoError& e) {
    std::cerr << "quadrix: i/o error: " << printable(e.what()) << "\n";
    rc = kIo;
  } catch (const SolverError& e) {
    std::cerr << "quadrix: computation failed: " << printable(e.what()) << "\n";
    rc = kComputation;
  } catch (const GlError& e) {
    std::cerr << "quadrix: OpenGL: " << printable(e.what()) << "\n";
    rc = kGl;
  } catch (const CLI::ValidationError& e) {
    std::cerr << "quadrix: usage: " << printable(e.what()) << "\n";
    rc = kUsage;
  } catch (const std::bad_alloc&) {
    std::cerr << "quadrix: out of memory\n";
    rc = kComputation;
  } catch (const std::exception& e) {
    std::cerr << "quadrix: " << kind << ": " << printable(e.what()) << "\n";
    rc = kInternal;
  }
  if (!common.report.empty()) {
    report.json["exit_code"] = rc;
    report.json["seconds"] = report.elapsed();
    try {
      write_file_atomically(common.report, [&](std::ostream& out) { out << report.json.dump(2) << "\n"; });
    } catch (const std::exception& e) {
      std::cerr << "quadrix: i/o error: cannot write report: " << printable(e.what()) << "\n";
      if (rc == kOk) rc = kIo;
    }
  }
  return rc;
}
