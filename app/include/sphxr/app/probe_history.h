#pragma once
// The probes' recent past for the live plots (the window's panel, the headset's mirror panel): one trace
// per probe (a sensor's pressure in Pa, a gauge's level in m, the magnitude of a force probe's force in
// N) over the last `span` simulated seconds, a point every span / kPoints. Plain data, copied into each
// snapshot (snapshot.h).
#include <cstdint>
#include <string>
#include <vector>

#include "sphxr/sim/probes.h"

namespace sphxr::app {

struct ProbeTrace {
  std::string label;           // "P1 (Pa)"
  std::vector<float> values;   // oldest first; NaN: dry
};

/// Simulated seconds the panels' probe plots cover.
inline constexpr double kProbePlotSeconds = 5.0;

class ProbeHistory {
 public:
  static constexpr int kPoints = 300;
  ProbeHistory() = default;
  ProbeHistory(const sim::ProbeSet& set, double span);
  /// A reading (Solver::LastProbes after a step): kept when a point is due.
  void Add(const sim::ProbeSample& sample);
  const std::vector<ProbeTrace>& Traces() const { return m_traces; }
  bool Empty() const { return m_traces.empty(); }

 private:
  std::vector<ProbeTrace> m_traces;
  double m_interval = 0.0;  // simulated s between points
  double m_next = -1.0;     // the next point's time (-1: the first reading)
};

/// ImGui: a plot line per trace with its last value ("dry" for NaN). Call inside an ImGui window.
void DrawProbePlots(const std::vector<ProbeTrace>& traces, float width);

}  // namespace sphxr::app
