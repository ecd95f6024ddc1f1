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
  // Every option's default in --help ("=VALUE"); options whose default is decided at run time say
  // so in their description instead.
  app.option_defaults()->always_capture_default();
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
  set_command_line(argc, argv);
  // The report, written on success and on failure alike, with the error and the exit code.
  Report report;
  std::string error;
  const auto write_report = [&](int rc) {
    if (common.report.empty()) return rc;
    report.json["exit_code"] = rc;
    report.json["seconds"] = report.elapsed();
    const std::string& what = !error.empty() ? error : rc == kExceeded ? report.exceeded : error;
    report.json["error"] = what.empty() ? nlohmann::json(nullptr) : nlohmann::json(what);
    try {
      write_file_atomically(common.report, [&](std::ostream& out) { out << report.json.dump(2) << "\n"; });
    } catch (const std::exception& e) {
      std::cerr << "quadrix: i/o error: cannot write report: " << printable(e.what()) << "\n";
      if (rc == kOk) rc = kIo;
    }
    return rc;
  };

  // A subcommand's name as typed after `quadrix` ("convert quads", not "quads").
  const auto full_name = [&app](const CLI::App* c) {
    std::string name;
    for (const CLI::App* a = c; a && a != &app; a = a->get_parent()) name = a->get_name() + (name.empty() ? "" : " " + name);
    return name;
  };
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    if (rc == 0) return kOk;
    // --report may have been read before the error: the usage error goes into it too.
    // The options' values are stored only after every option validated: read --report's raw text.
    for (auto& c : commands)
      if (c.app->parsed()) {
        report.json["command"] = full_name(c.app);
        if (const CLI::Option* o = c.app->get_option_no_throw("--report"); o && !o->results().empty())
          common.report = o->results().front();
      }
    error = e.what();
    return write_report(kUsage);
  }
  log::set_level(common.quiet ? log::Level::error
                 : common.verbose >= 2 ? log::Level::debug
                 : common.verbose == 1 ? log::Level::info
                                       : log::Level::warn);
  int rc = kInternal;
  std::string command_name;
  const char* kind = "internal error";
  try {
    // Every output of the command lands together at the end, or none does.
    OutputTransaction outputs;
    for (auto& c : commands) {
      if (!c.app->parsed()) continue;
      command_name = full_name(c.app);
      report.json["command"] = command_name;
      // An output into a folder that does not exist fails now, before the work (a fit of
      // minutes failed at its end). `bench` writes into a folder of its own making.
      if (!command_name.starts_with("bench"))
        if (const CLI::Option* o = c.app->get_option_no_throw("--out"); o && o->count() > 0)
          check_output_folder(o->as<std::string>());
      rc = c.run(common, report);
      kind = nullptr;
      break;
    }
    kind = "internal error";
    if (rc == kOk || rc == kExceeded) outputs.commit();
    kind = nullptr;
  } catch (const FormatError& e) {
    error = "bad input: " + printable(e.what());
    rc = kBadInput;
  } catch (const InvalidInput& e) {
    error = "invalid input: " + printable(e.what());
    rc = kBadInput;
  } catch (const IoError& e) {
    error = "i/o error: " + printable(e.what());
    rc = kIo;
  } catch (const SolverError& e) {
    error = "computation failed: " + printable(e.what());
    rc = kComputation;
  } catch (const GlError& e) {
    error = "OpenGL: " + printable(e.what());
    rc = kGl;
  } catch (const CLI::ValidationError& e) {
    error = "usage: " + printable(e.what());
    rc = kUsage;
  } catch (const std::bad_alloc&) {
    error = "out of memory";
    rc = kComputation;
  } catch (const std::exception& e) {
    error = std::string(kind ? kind : "internal error") + ": " + printable(e.what());
    rc = kInternal;
  }
  if (!error.empty()) std::cerr << "quadrix: " << error << "\n";
  rc = write_report(rc);
  // One line on success: what was written, counts, time.
  if ((rc == kOk || rc == kExceeded) && !common.quiet && !report.summary.empty())
    std::cerr << fmt::format("quadrix {}: {} in {:.2f} s\n", command_name, report.summary,
                             report.elapsed());
  return rc;
}
