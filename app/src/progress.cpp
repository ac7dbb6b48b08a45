#include "progress.h"

#include <algorithm>
#include <cstdio>

#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace sphxr::app {

void Progress::Update(double fraction, double simTime, int64_t steps, double msPerStep) {
  if (!m_enabled && !m_lines) return;
  const auto now = std::chrono::steady_clock::now();
  if (m_start == std::chrono::steady_clock::time_point{}) m_start = now;
  if (m_lines) {
    if (fraction >= 1.0 || now - m_last < std::chrono::seconds(60)) return;
    if (m_last == std::chrono::steady_clock::time_point{}) {  // the first line a minute in, not at once
      m_last = now;
      return;
    }
    m_last = now;
    SPHXR_LOG_INFO("%s%d %%: t = %.4f s, step %lld, %.2f ms/step%s", m_label, static_cast<int>(fraction * 100.0),
                   simTime, static_cast<long long>(steps), msPerStep, Left(fraction, now).c_str());
    return;
  }
  if (fraction < 1.0 && now - m_last < std::chrono::milliseconds(100)) return;
  m_last = now;
  const int width = 30;
  const int filled = std::clamp(static_cast<int>(fraction * width), 0, width);
  std::fprintf(stderr, "\r%s[%.*s%.*s] %3d%%  t = %.4f s  step %lld  %.2f ms/step%s ", m_label, filled,
               "##############################", width - filled, "                              ",
               static_cast<int>(fraction * 100.0), simTime, static_cast<long long>(steps), msPerStep,
               fraction < 1.0 ? Left(fraction, now).c_str() : "");
  m_open = fraction < 1.0;
  if (!m_open) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

void Progress::Finish() {
  if (m_open) std::fprintf(stderr, "\n");
  m_open = false;
}

// ", about 3 min left" once two seconds and a thousandth of the run have passed.
std::string Progress::Left(double fraction, std::chrono::steady_clock::time_point now) const {
  const double elapsed = std::chrono::duration<double>(now - m_start).count();
  if (elapsed < 2.0 || fraction < 1e-3) return {};
  const double left = elapsed * (1.0 - fraction) / fraction;
  if (left < 90.0) return Format(", about %.0f s left", left);
  if (left < 5400.0) return Format(", about %.0f min left", left / 60.0);
  return Format(", about %.1f h left", left / 3600.0);
}

}  // namespace sphxr::app
