#pragma once
// Shared test fixtures: a per-test temporary folder, and running the built `quadrix` binary.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace quadrix::test_support {

/// A fresh folder per test (named after the suite, test and process), removed afterwards.
class TempDir : public ::testing::Test {
protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           (std::string("quadrix_") + info->test_suite_name() + "_" + info->name() + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  /// Writes text (bytes as given) to dir/name and returns the path.
  std::filesystem::path write_text(const std::string& name, const std::string& text) const {
    const std::filesystem::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  std::filesystem::path write(const std::string& name, const std::string& text) const { return write_text(name, text); }
  std::filesystem::path dir_;
};

struct CmdResult {
  int code = -1;
  std::string out;  // stdout and stderr together
};

/// Runs `binary args` through the shell; exit code (128 + signal when killed) and all output.
inline CmdResult run_command(const std::string& binary, const std::string& args) {
  const std::string cmd = binary + " " + args + " 2>&1";
  CmdResult r;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = ::pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

/// A tiny PDB file: two chains of three atoms each (A: GLY, B: ALA; bonds left to inference),
/// different elements in each chain.
inline constexpr const char* kTwoChainPdb =
    "ATOM      1  N   GLY A   1       0.000   0.000   0.000  1.00  0.00           N\n"
    "ATOM      2  CA  GLY A   1       1.458   0.000   0.000  1.00  0.00           C\n"
    "ATOM      3  O   GLY A   1       2.009   1.420   0.000  1.00  0.00           O\n"
    "ATOM      4  N   ALA B   2       0.000   0.000   4.000  1.00  0.00           N\n"
    "ATOM      5  CA  ALA B   2       1.458   0.000   4.000  1.00  0.00           C\n"
    "ATOM      6  O   ALA B   2       2.009   1.420   4.000  1.00  0.00           O\n"
    "END\n";

}  // namespace quadrix::test_support
