#include "sphxr/app/probe_history.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace sphxr::app {

ProbeHistory::ProbeHistory(const sim::ProbeSet& set, double span) : m_interval(span / kPoints) {
  for (const sim::PressureProbe& p : set.pressure) m_traces.push_back({p.name + " (Pa)", {}});
  for (const sim::LevelGauge& g : set.level) m_traces.push_back({g.name + " (m)", {}});
  for (const sim::ForceProbe& f : set.force) m_traces.push_back({f.name + " |F| (N)", {}});
}

void ProbeHistory::Add(const sim::ProbeSample& sample) {
  if (m_traces.empty() || sample.time < m_next) return;
  m_next = sample.time + m_interval;
  size_t k = 0;
  auto push = [&](float v) {
    std::vector<float>& values = m_traces[k++].values;
    if (values.size() >= static_cast<size_t>(kPoints)) values.erase(values.begin());
    values.push_back(v);
  };
  for (float p : sample.pressure) push(p);
  for (float l : sample.level) push(l);
  for (const sim::BodyLoad& load : sample.load) push(Length(load.force));
}

void DrawProbePlots(const std::vector<ProbeTrace>& traces, float width) {
  for (const ProbeTrace& t : traces) {
    // Dry points are drawn at the trace's floor (ImGui draws no gaps); the label says dry.
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (float v : t.values) {
      if (std::isnan(v)) continue;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    if (!(lo <= hi)) lo = hi = 0.0f;
    std::vector<float> shown(t.values);
    for (float& v : shown) {
      if (std::isnan(v)) v = lo;
    }
    const float last = t.values.empty() ? std::nanf("") : t.values.back();
    char overlay[64];
    if (std::isnan(last)) {
      std::snprintf(overlay, sizeof(overlay), "dry");
    } else {
      std::snprintf(overlay, sizeof(overlay), "%.4g", last);
    }
    ImGui::PlotLines(t.label.c_str(), shown.data(), static_cast<int>(shown.size()), 0, overlay, lo,
                     hi > lo ? hi : lo + 1.0f, ImVec2(width, 34));
  }
}

}  // namespace sphxr::app
