#pragma once
/// Helpers of the CLI test programs (each defines QUADRIX_BINARY, the quadrix under test).
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/support.h"

namespace quadrix::test_support {

/// Runs the quadrix under test with args (a shell command line); exit code and all output.
inline CmdResult quadrix_run(const std::string& args) { return run_command(QUADRIX_BINARY, args); }
/// A path quoted for the shell.
inline std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }
inline nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

}  // namespace quadrix::test_support
