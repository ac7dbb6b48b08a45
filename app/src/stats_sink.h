#pragma once
// `--stats FILE.csv`, a sink of the Simulation (simulation.h): one row per step, the method's own
// statistics (its solver-table row) among the columns.
#include <chrono>
#include <cstdint>
#include <fstream>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "sphxr/app/scene_file.h"
#include "sphxr/app/simulation.h"
#include "sphxr/sim/launch_counts.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::app {

/// --stats FILE.csv: one row per step. The rows are held and handed to the file at least once a second of
/// wall time (and before each checkpoint, and at the end, also of a run stopped by a signal), so that a
/// kill loses at most a second of rows and never leaves half a row.
class StatsSink : public SimulationSink {
 public:
  explicit StatsSink(std::string path) : m_path(std::move(path)) {}
  /// Before the solver exists: the file is opened without truncating it (a run continued from a state
  /// file keeps the first half's rows; a run refused at start-up leaves the file as it was).
  Status Open();
  /// After Create: the header, or the first half's rows kept when they continue into this run.
  Status WriteHeader(Simulation& simulation, const std::optional<DamBreakProbe>& probe);
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  /// Hands the held rows to the file; an error names --stats.
  Status Flush();
  Status Finish(Simulation& simulation, bool interrupted) override;

 private:
  /// After a failed write: the file cut after its last whole row (a full disk leaves no half row).
  void CutToWholeRows();

  std::string m_path;
  std::ofstream m_out;
  int64_t m_whole = -1;  // bytes of the file known to end at a whole row; -1: not a regular file
  std::optional<DamBreakProbe> m_probe;
  std::span<const sim::SolveColumn> m_stats;  // the method's own columns (its solver-table row)
  std::string m_pending;
  std::chrono::steady_clock::time_point m_last = std::chrono::steady_clock::now();
  sim::HostFluid m_host;
  sim::LaunchCounts m_counts;  // the solver's counts at the last row (launches, waits, ... since it)
};

}  // namespace sphxr::app
