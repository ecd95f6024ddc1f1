// Work run in a child process (core/child_process.h): what it writes comes back whole, and a
// crash, a failure or a child that runs on is reported, not suffered.
#include <gtest/gtest.h>

#include <csignal>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "core/child_process.h"

using namespace quadrix;

TEST(ChildProcess, OutputComesBackWholeAndEveryEndingIsTold) {
  // More than a pipe holds (64 KiB): the parent reads while the child writes.
  const std::string big(1 << 20, 'q');
  ChildRun r = run_in_child([&](int fd) { return write_all(fd, big.data(), big.size()) ? 0 : 3; });
  ASSERT_TRUE(r.ran()) << r.not_run;
  EXPECT_TRUE(r.succeeded()) << r.how();
  EXPECT_EQ(r.output, big);
  EXPECT_EQ(r.how(), "exited normally");

  r = run_in_child([](int fd) { return write_all(fd, "ab", 2) ? 2 : 3; });
  EXPECT_FALSE(r.succeeded());
  EXPECT_EQ(r.exit_code(), 2);
  EXPECT_EQ(r.output, "ab");
  EXPECT_EQ(r.how(), "exited with status 2");

  // A crash (SIGKILL: no sanitizer or handler turns it into an exit) keeps what was written.
  r = run_in_child([](int fd) {
    write_all(fd, "x", 1);
    ::raise(SIGKILL);
    return 0;
  });
  EXPECT_FALSE(r.succeeded());
  EXPECT_EQ(r.exit_code(), -1);
  EXPECT_EQ(r.output, "x");
  EXPECT_EQ(r.how(), "crashed (signal 9)");

  // A throw is exit 4.
  r = run_in_child([](int) -> int { throw std::runtime_error("no"); });
  EXPECT_EQ(r.exit_code(), 4);

  // One that runs on is killed at its deadline.
  r = run_in_child([](int) {
    ::sleep(30);
    return 0;
  }, 0.3);
  EXPECT_TRUE(r.timed_out);
  EXPECT_FALSE(r.succeeded());
  EXPECT_NE(r.how().find("deadline"), std::string::npos) << r.how();
}
