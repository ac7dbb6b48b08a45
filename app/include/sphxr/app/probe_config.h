#pragma once
// The scene's "probes" section (docs/user/scenes.md#probes): what is measured and how often. The scene
// file reads it; the --probes CSV (probe_csv.h) writes its rows.
#include <cstdint>

#include "sphxr/sim/probes.h"

namespace sphxr::app {

/// The shortest probes.every, and the most rows one step may write. Together they bound a step's rows:
/// a much shorter interval would make millions of rows per step and the run would never finish its first
/// step; a step longer than kMaxProbeRowsPerStep intervals is refused.
inline constexpr double kMinProbeInterval = 1e-6;     // s
inline constexpr int64_t kMaxProbeRowsPerStep = 10000;

/// The scene's "probes" section.
struct ProbeConfig {
  double every = 0.001;  // s of simulated time between rows
  sim::ProbeSet set;     // force probes carry the index of their paddle's body
};

}  // namespace sphxr::app
