#pragma once
// The progress of a long run on stderr: a bar on a terminal, a line a minute in a log file.
#include <chrono>
#include <cstdint>
#include <string>

namespace sphxr::app {

/// Progress of a long run: a bar redrawn in place on a terminal, or (`lines`: stderr is a log file, the
/// default when it is not a terminal) one line a minute, so a run logged to a file is not silent for
/// minutes. Both say how long is left, extrapolated from the wall time so far.
class Progress {
 public:
  explicit Progress(bool enabled, const char* label = "", bool lines = false)
      : m_enabled(enabled), m_lines(lines && !enabled), m_label(label) {}
  void Update(double fraction, double simTime, int64_t steps, double msPerStep);
  /// Ends a bar left unfinished (a run stopped early), so that the next line starts on its own.
  void Finish();

 private:
  std::string Left(double fraction, std::chrono::steady_clock::time_point now) const;

  bool m_enabled;
  bool m_lines;
  const char* m_label;
  bool m_open = false;
  std::chrono::steady_clock::time_point m_start{}, m_last{};
};

}  // namespace sphxr::app
