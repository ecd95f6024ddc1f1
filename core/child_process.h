#pragma once
/// Work that may crash the process run in a fork()ed child instead: TetGen (an invalid input
/// segfaults it) and CGAL's experimental autorefinement (it asserts nothing in release builds and
/// crashed on some glyph sets). The child writes its result into a pipe; the parent reads every
/// byte, then waits for it, and learns how it ended.
#include <cstddef>
#include <functional>
#include <string>

namespace quadrix {

struct ChildRun {
  std::string output;     ///< every byte the child wrote to its end of the pipe
  int status = 0;         ///< waitpid's status
  bool timed_out = false; ///< killed (SIGKILL) at the deadline
  double deadline = 0;    ///< the deadline it had, in seconds (0: none)
  std::string not_run;    ///< why no child ran (no pipe, no fork); empty when one ran
  bool ran() const { return not_run.empty(); }
  /// Whether the child exited with status 0.
  bool succeeded() const;
  /// The child's exit status, or −1 where it did not exit (a signal killed it).
  int exit_code() const;
  /// How it ended, in words: "crashed (signal 11)", "exited with status 2", "exited normally",
  /// "ran past its deadline of 300 s".
  std::string how() const;
};

/// Forks; the child runs work(fd), fd being the write end of the pipe, and exits at once
/// (_exit, no destructors or atexit handlers) with work's return value, or 4 where work throws;
/// it writes no core file. The parent reads the pipe to its end while the child runs, so the
/// child may write any amount; past `deadline_seconds` (0: none) it kills the child.
/// The child is single-threaded (fork copies only the calling thread): work must not wait on
/// other threads (no TBB).
ChildRun run_in_child(const std::function<int(int fd)>& work, double deadline_seconds = 0);

/// Writes all n bytes to fd, retrying on EINTR; false on an error or a closed pipe.
bool write_all(int fd, const void* data, std::size_t n);

}  // namespace quadrix
