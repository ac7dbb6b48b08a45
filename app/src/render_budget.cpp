#include "sphxr/app/render_budget.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <unistd.h>

#include "sphxr/common/log.h"

namespace sphxr::app {

bool RenderBudget::Observe(double frameMs, double periodMs) {
  if (!m_adaptive || m_quality == render::RenderQuality::kLow || !(frameMs > 0.0) || !(periodMs > 0.0)) return false;
  m_frames.push_back(frameMs);
  if (static_cast<int>(m_frames.size()) < kWindow) return false;
  std::vector<double> sorted = m_frames;
  m_frames.clear();
  std::nth_element(sorted.begin(), sorted.begin() + kWindow / 2, sorted.end());
  const double median = sorted[kWindow / 2];
  if (median <= kHeadroom * periodMs) return false;
  const render::RenderQuality from = m_quality;
  m_quality = m_quality == render::RenderQuality::kHigh ? render::RenderQuality::kMedium : render::RenderQuality::kLow;
  m_why = Format("render quality %s -> %s: frames take %.1f ms (median of %d) against a %.1f ms display period",
                 render::RenderQualityName(from), render::RenderQualityName(m_quality), median, kWindow, periodMs);
  return true;
}

std::string RenderSummary(render::RenderQuality quality, const render::DrawStats& stats) {
  std::string text = Format("render quality %s", render::RenderQualityName(quality));
  if (stats.passes.empty() || stats.views <= 0) return text;
  text += Format("; GPU per view %.2f ms:", stats.GpuMs() / stats.views);
  for (const render::PassTime& p : stats.passes) text += Format(" %s %.2f,", p.name.c_str(), p.gpuMs / stats.views);
  text.pop_back();
  return text;
}

FrameStatsCsv::~FrameStatsCsv() {
  if (m_file) std::fclose(m_file);
}

Status FrameStatsCsv::Open(const std::string& path) {
  m_path = path;
  m_file = std::fopen(path.c_str(), "w");
  if (!m_file) return Status::Error(Format("--frame-stats %s: cannot write (%s)", path.c_str(), std::strerror(errno)));
  return Status::Ok();
}

Status FrameStatsCsv::Append(int64_t frame, double intervalMs, render::RenderQuality quality,
                             const render::DrawStats& stats) {
  if (!m_file) return Status::Ok();
  std::string text;
  if (m_columns.empty() && !stats.passes.empty()) {
    for (const render::PassTime& p : stats.passes) m_columns.push_back(p.name);
    text += "frame,interval_ms,render_quality,views,gpu_ms";
    for (const std::string& c : m_columns) {
      std::string column = c;
      std::replace(column.begin(), column.end(), ' ', '_');
      text += ",gpu_" + column + "_ms";
    }
    text += "\n";
  }
  if (m_columns.empty()) return Status::Ok();  // no pass timed yet (the first frames' queries are pending)
  text += Format("%lld,%.3f,%s,%d,%.4f", static_cast<long long>(frame), intervalMs, render::RenderQualityName(quality),
                 stats.views, stats.GpuMs());
  for (const std::string& c : m_columns) {
    const auto it = std::find_if(stats.passes.begin(), stats.passes.end(), [&](const render::PassTime& p) { return p.name == c; });
    text += it == stats.passes.end() ? std::string(",") : Format(",%.4f", it->gpuMs);
  }
  text += "\n";
  // One fwrite of the whole row and a flush: on a full disk the row is refused and the file closed,
  // so it never ends mid-row after a row that made it.
  const long before = std::ftell(m_file);
  if (std::fwrite(text.data(), 1, text.size(), m_file) != text.size() || std::fflush(m_file) != 0) {
    if (before >= 0) {
      const int ignored = ftruncate(fileno(m_file), before);  // drop the partial row; the file ends at the last whole one
      (void)ignored;
    }
    std::fclose(m_file);
    m_file = nullptr;
    return Status::Error(Format("--frame-stats %s: write failed (%s); the frame rows stop here", m_path.c_str(),
                                std::strerror(errno)));
  }
  return Status::Ok();
}

}  // namespace sphxr::app
