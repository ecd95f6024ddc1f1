#include "core/child_process.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>

#include <fcntl.h>
#include <poll.h>
#include <sys/resource.h>

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

namespace quadrix {

bool ChildRun::succeeded() const { return ran() && !timed_out && WIFEXITED(status) && WEXITSTATUS(status) == 0; }

int ChildRun::exit_code() const { return ran() && !timed_out && WIFEXITED(status) ? WEXITSTATUS(status) : -1; }

std::string ChildRun::how() const {
  if (!ran()) return not_run;
  if (timed_out) return fmt::format("ran past its deadline of {:.0f} s", deadline);
  if (WIFSIGNALED(status)) return fmt::format("crashed (signal {})", WTERMSIG(status));
  if (WIFEXITED(status))
    return WEXITSTATUS(status) == 0 ? std::string("exited normally") : fmt::format("exited with status {}", WEXITSTATUS(status));
  return "ended abnormally";
}

bool write_all(int fd, const void* data, std::size_t n) {
  const char* c = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, c, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    c += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

ChildRun run_in_child(const std::function<int(int fd)>& work, double deadline_seconds) {
  ChildRun r;
  r.deadline = deadline_seconds;
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    r.not_run = fmt::format("cannot create a pipe: {}", std::strerror(errno));
    return r;
  }
  const pid_t pid = ::fork();
  if (pid < 0) {
    r.not_run = fmt::format("cannot fork: {}", std::strerror(errno));
    ::close(fds[0]);
    ::close(fds[1]);
    return r;
  }
  if (pid == 0) {
    ::close(fds[0]);
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);  // a crash here is expected now and then: no dump of a copy of the whole process
    int code = 4;
    try {
      code = work(fds[1]);
    } catch (...) {
      code = 4;
    }
    ::close(fds[1]);
    ::_exit(code);
  }
  ::close(fds[1]);
  const auto start = std::chrono::steady_clock::now();
  std::array<char, 1 << 16> chunk{};
  try {
    for (;;) {
      if (deadline_seconds > 0) {
        const double left = deadline_seconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        pollfd p{fds[0], POLLIN, 0};
        const int ready = left > 0 ? ::poll(&p, 1, static_cast<int>(std::min(left * 1000.0, 1e9)) + 1) : 0;
        if (ready < 0 && errno == EINTR) continue;
        if (ready == 0) {
          ::kill(pid, SIGKILL);
          r.timed_out = true;
          break;
        }
      }
      const ssize_t n = ::read(fds[0], chunk.data(), chunk.size());
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      r.output.append(chunk.data(), static_cast<std::size_t>(n));
    }
  } catch (...) {  // no memory for the output: the child is ended, and reaped
    ::kill(pid, SIGKILL);
    ::close(fds[0]);
    while (::waitpid(pid, &r.status, 0) < 0 && errno == EINTR) {
    }
    throw;
  }
  ::close(fds[0]);
  while (::waitpid(pid, &r.status, 0) < 0 && errno == EINTR) {
  }
  return r;
}

}  // namespace quadrix
