#pragma once
// SIGINT, SIGTERM and SIGHUP while a run goes on: a headless run (headless.cpp) and a headset session
// (xr_mode.cpp) check g_interrupt between steps or frames and end as they would at their end, with
// their summary and their files.
#include <signal.h>

#include <csignal>

namespace sphxr::app {

/// The signal that asked the run to stop (0: none), set by InterruptScope's handler.
inline volatile std::sig_atomic_t g_interrupt = 0;

inline void OnInterrupt(int signal) { g_interrupt = signal; }

/// "SIGINT", "SIGHUP" or "SIGTERM", the signals InterruptScope catches.
inline const char* InterruptName(int signal) {
  return signal == SIGINT ? "SIGINT" : signal == SIGHUP ? "SIGHUP" : "SIGTERM";
}

/// SIGINT, SIGTERM and SIGHUP (a closed terminal, a dropped ssh session: long runs are started that
/// way) set g_interrupt while a run steps, however many arrive: a second Ctrl-C soon after the first
/// must not end the run by the default action, without its summary, cutting a row and leaving
/// FILE.state.tmp.
/// (SIGQUIT, Ctrl-\, still ends it at once.) The previous handlers come back afterwards, unless the run
/// was interrupted: the process is then ending, and the three stay ignored until it exits.
class InterruptScope {
 public:
  InterruptScope() {
    g_interrupt = 0;
    struct sigaction action {};
    action.sa_handler = OnInterrupt;
    sigemptyset(&action.sa_mask);
    action.sa_flags = 0;
    sigaction(SIGINT, nullptr, &m_int);
    sigaction(SIGTERM, nullptr, &m_term);
    sigaction(SIGHUP, nullptr, &m_hup);
    // A signal ignored on entry (a background job of a script, nohup) stays ignored.
    if (m_int.sa_handler != SIG_IGN) sigaction(SIGINT, &action, nullptr);
    if (m_term.sa_handler != SIG_IGN) sigaction(SIGTERM, &action, nullptr);
    if (m_hup.sa_handler != SIG_IGN) sigaction(SIGHUP, &action, nullptr);
  }
  ~InterruptScope() {
    // After an interrupt the process is ending (exit 128 + the signal): more of these signals may follow
    // (a second Ctrl-C, the hang-ups of a closed terminal) while the run's end is written or the process
    // exits, so they are ignored until it does instead of ending it by the default action.
    if (g_interrupt != 0) {
      struct sigaction ignore {};
      ignore.sa_handler = SIG_IGN;
      sigemptyset(&ignore.sa_mask);
      for (int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &ignore, nullptr);
      return;
    }
    sigaction(SIGINT, &m_int, nullptr);
    sigaction(SIGTERM, &m_term, nullptr);
    sigaction(SIGHUP, &m_hup, nullptr);
  }
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  struct sigaction m_int {
  }, m_term{}, m_hup{};
};

}  // namespace sphxr::app
