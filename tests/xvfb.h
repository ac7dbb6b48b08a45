#pragma once
// A private X server for a test (render and xr suites): Xvfb picks a free display number itself and
// writes it to -displayfd, so tests started at once (ctest -j) never race for one. (The render tests
// used to pick the first number without a lock file; two of them could both take :90, and the one
// whose own server had exited ran on the other's until it went away.)
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>

namespace sphxr::test {

class Xvfb {
 public:
  /// Starts Xvfb with one screen of `screen` (e.g. "1024x768x24"); Display() is empty if it could not.
  explicit Xvfb(const char* screen = "1024x768x24") {
    int fds[2];
    if (pipe(fds) != 0) return;
    m_pid = fork();
    if (m_pid == 0) {
      prctl(PR_SET_PDEATHSIG, SIGTERM);  // a crashed test takes its Xvfb with it
      close(fds[0]);
      if (!freopen("/dev/null", "w", stderr)) _exit(126);
      const std::string fd = std::to_string(fds[1]);
      execlp("Xvfb", "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", screen, "-nolisten", "tcp", static_cast<char*>(nullptr));
      _exit(127);
    }
    close(fds[1]);
    if (m_pid < 0) {
      close(fds[0]);
      return;
    }
    std::string number;  // written once the server accepts connections
    char c;
    while (read(fds[0], &c, 1) == 1 && c != '\n') number += c;
    close(fds[0]);
    if (number.empty()) {  // it exited (not installed, or failed)
      waitpid(m_pid, nullptr, 0);
      m_pid = -1;
      return;
    }
    m_display = ":" + number;
  }
  ~Xvfb() {
    if (m_pid > 0) {
      kill(m_pid, SIGTERM);
      waitpid(m_pid, nullptr, 0);
    }
  }
  Xvfb(const Xvfb&) = delete;
  Xvfb& operator=(const Xvfb&) = delete;

  const std::string& Display() const { return m_display; }
  bool Alive() const { return m_pid > 0 && waitpid(m_pid, nullptr, WNOHANG) == 0; }

 private:
  pid_t m_pid = -1;
  std::string m_display;
};

}  // namespace sphxr::test
