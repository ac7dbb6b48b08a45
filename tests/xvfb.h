#pragma once
// A private X server for a test (render and xr suites): Xvfb picks a free display number itself and
// writes it to -displayfd, so tests started at once (ctest -j) never race for one. (The render tests
// used to pick the first number without a lock file; two of them could both take :90, and the one
// whose own server had exited ran on the other's until it went away.)
//
// Start it from the thread that stays (the test's main thread): PR_SET_PDEATHSIG, which takes the
// server down with a crashed test, fires when the thread that forked it ends.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>

namespace sphxr::test {

class Xvfb {
 public:
  /// Starts Xvfb with one screen of `screen` (e.g. "1024x768x24") and waits up to `timeoutMs` for it to
  /// accept connections; Display() is empty if it could not (not installed, failed, or too slow).
  explicit Xvfb(const char* screen = "1024x768x24", int timeoutMs = 20000) {
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) return;  // no other fork inherits the write end
    // Everything the child needs is made before the fork: after it, only async-signal-safe calls.
    const std::string fd = std::to_string(fds[1]);
    const pid_t parent = getpid();
    m_pid = fork();
    if (m_pid == 0) {
      prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (getppid() != parent) _exit(125);  // the parent died before prctl
      close(fds[0]);
      fcntl(fds[1], F_SETFD, 0);  // the one descriptor Xvfb keeps
      const int null = open("/dev/null", O_WRONLY);
      if (null >= 0) dup2(null, STDERR_FILENO);
      execlp("Xvfb", "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", screen, "-nolisten", "tcp", static_cast<char*>(nullptr));
      _exit(127);
    }
    close(fds[1]);
    if (m_pid < 0) {
      close(fds[0]);
      return;
    }
    std::string number;  // written once the server accepts connections, then a newline
    pollfd p{fds[0], POLLIN, 0};
    while (poll(&p, 1, timeoutMs) == 1) {
      char c;
      if (read(fds[0], &c, 1) != 1 || c == '\n') break;
      number += c;
    }
    close(fds[0]);
    if (number.empty()) {  // it exited, or did not answer in time
      Stop();
      return;
    }
    m_display = ":" + number;
  }
  ~Xvfb() { Stop(); }
  Xvfb(const Xvfb&) = delete;
  Xvfb& operator=(const Xvfb&) = delete;

  const std::string& Display() const { return m_display; }
  /// Whether the server still runs (a server found dead is reaped here, and not signalled later).
  bool Alive() const {
    if (m_pid <= 0) return false;
    if (waitpid(m_pid, nullptr, WNOHANG) == 0) return true;
    m_pid = -1;
    return false;
  }

 private:
  void Stop() {
    if (m_pid <= 0) return;
    kill(m_pid, SIGTERM);
    waitpid(m_pid, nullptr, 0);
    m_pid = -1;
  }
  mutable pid_t m_pid = -1;
  std::string m_display;
};

}  // namespace sphxr::test
