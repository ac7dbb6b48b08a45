#pragma once
// The CPU backend's team size, chosen from the steps' own durations (docs/design/contention.md).
//
// A step of the CPU backend is a few dozen OpenMP regions; each ends at a barrier where every thread
// waits for the last. Alone on the machine all cores are fastest. Beside another busy process one
// thread of the team is descheduled in turn, and every barrier waits for it: a 2-thread step can take
// longer than a 1-thread one, by up to an order of magnitude (bench/contention.sh,
// docs/design/contention.md). No wait policy is right for both: sleeping at once
// (OMP_WAIT_POLICY=passive) is the best beside a busy process and slower alone.
//
// So the team is measured, not guessed: the step runs at one size of a ladder (all cores, half, ...,
// 1); after `interval` steps it tries a neighbouring size for kWindow steps and keeps whichever had the
// smaller median step (the other by at least kMargin). A confirmed size multiplies the interval by kGrowth (up to
// kMaxInterval), a change resets it; a step median that rises by half since the last decision tries at
// once. Every size gives the same bits (the stages never depend on the schedule:
// Conformance.TheSameBitsAtEveryThreadCount), so the choice changes only the speed.
#include <algorithm>
#include <array>
#include <vector>

namespace sphxr::sim {

class TeamSizer {
 public:
  static constexpr int kWindow = 8;            // steps per measurement
  static constexpr int kMinInterval = 64;      // steps at a size before the first try of another
  static constexpr int kMaxInterval = 4096;
  static constexpr int kGrowth = 4;            // a confirmed size: the next try kGrowth times later
  static constexpr double kMargin = 0.9;       // a try must be 10 % faster to win
  static constexpr double kRise = 1.5;         // a median this much above the decision's tries at once

  /// `cores`: the largest team; `adapt`: false keeps it (the user's --threads).
  TeamSizer(int cores, bool adapt) {
    for (int t = std::max(cores, 1);; t /= 2) {
      m_sizes.push_back(t);
      if (t == 1) break;
    }
    m_adapt = adapt && m_sizes.size() > 1;
  }

  /// The team for the next step.
  int Threads() const { return m_sizes[static_cast<size_t>(m_trying ? m_try : m_at)]; }

  /// The step just taken at Threads() took `seconds`.
  void Record(double seconds) {
    if (!m_adapt) return;
    m_window[static_cast<size_t>(m_filled++)] = seconds;
    if (m_filled < kWindow) return;
    m_filled = 0;
    const double median = Median();
    if (m_trying) {
      m_trying = false;
      if (median < kMargin * m_current) {
        m_at = m_try;
        m_interval = kMinInterval;
        m_decided = median;
      } else {
        m_interval = std::min(kGrowth * m_interval, kMaxInterval);
        m_decided = m_current;
      }
      m_since = 0;
      m_downNext = !m_downNext;
      return;
    }
    m_current = median;
    if (m_decided <= 0.0) m_decided = median;  // the first window (past the start's first one)
    m_since += kWindow;
    if (m_since >= m_interval || median > kRise * m_decided) Try();
  }

  /// The sizes of the ladder, largest first.
  const std::vector<int>& Sizes() const { return m_sizes; }

 private:
  void Try() {
    const int last = static_cast<int>(m_sizes.size()) - 1;
    bool down = m_downNext;
    if (m_at == 0) down = true;
    if (m_at == last) down = false;
    m_try = down ? m_at + 1 : m_at - 1;
    m_trying = true;
  }

  double Median() {
    std::array<double, kWindow> w = m_window;
    std::nth_element(w.begin(), w.begin() + kWindow / 2, w.end());
    return w[kWindow / 2];
  }

  std::vector<int> m_sizes;
  bool m_adapt = false;
  int m_at = 0, m_try = 0;  // indices into m_sizes
  bool m_trying = false, m_downNext = true;
  int m_interval = kMinInterval, m_since = 0, m_filled = 0;
  double m_current = 0.0, m_decided = 0.0;
  std::array<double, kWindow> m_window{};
};

}  // namespace sphxr::sim
