#pragma once
// `--probes FILE.csv`: the scene's probes (the "probes" section, sphxr/sim/probes.h) sampled at a fixed
// simulated-time interval. One row per sample: time, step, then one column per probe quantity (a
// pressure sensor's p in Pa, a gauge's level in m, a force probe's fx, fy, fz in N and tx, ty, tz in N m);
// an empty cell where a sensor is dry or a gauge finds no water.
//
// Rows come exactly `every` apart: row k is at t = k every. The solver reads its probes in every step,
// on the state at the step's start (Solver::LastProbes), and dt does not divide `every`, so row k is the
// linear interpolation between the two readings whose times bracket k every (a dry reading on either side
// leaves the cell empty). A row's step is that of the earlier of the two. Rows are written whole.
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "sphxr/app/probe_config.h"
#include "sphxr/app/simulation.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/probes.h"

namespace sphxr::app {

/// The CSV header for `set`: time,step, then per probe `NAME_p` | `NAME_level` | `NAME_fx` ... `NAME_tz`.
std::string ProbeCsvHeader(const sim::ProbeSet& set);

class ProbeCsv {
 public:
  /// Opens `path` and writes the header; rows start at the first multiple of `every` at or after
  /// `start` (s: a continued run's start time). A continued run (start > 0) whose file is a regular
  /// file with the same header and rows in time order continues it: the earlier run's rows before the
  /// first new row are kept, any after it (an earlier continuation's) cut off, and rows appended.
  static Status Open(const std::string& path, const ProbeConfig& config, double start, std::unique_ptr<ProbeCsv>* out);
  ~ProbeCsv();
  ProbeCsv(const ProbeCsv&) = delete;
  ProbeCsv& operator=(const ProbeCsv&) = delete;

  /// One reading (the solver's LastProbes after a step): the rows whose times lie between the previous
  /// reading and this one. Rows leave for the file at least once a second of wall time.
  Status Add(const sim::ProbeSample& sample);
  /// Hands the rows held to the file (at the end, before a checkpoint).
  Status Flush();
  int64_t Rows() const { return m_rows; }
  double NextTime() const { return static_cast<double>(m_next) * m_every; }
  /// The rows start at the first multiple of `every` at or after `start` (before any Add).
  void StartAt(double start);

 private:
  ProbeCsv() = default;
  void Row(double t, const sim::ProbeSample& a, const sim::ProbeSample* b);
  std::string m_path;
  std::FILE* m_file = nullptr;
  double m_every = 0.0;
  int64_t m_next = 0;  // the next row's index k (time k every)
  int64_t m_rows = 0;
  std::optional<sim::ProbeSample> m_previous;
  std::string m_pending;
  double m_lastFlush = 0.0;  // s of wall time (steady clock)
};

/// --probes FILE.csv as a sink of the Simulation: the file made (and its header written) by Create,
/// before the solver exists; OnStart sets the probes on the solver and starts the rows at its time;
/// every step adds the solver's LastProbes; Finish adds a reading of the final state (the rows up to the
/// run's end) and hands the last rows to the file.
class ProbeSink : public SimulationSink {
 public:
  /// `start`: the run's start time (a state file's; 0 for a new run), as ProbeCsv::Open takes it.
  static Status Create(const std::string& path, const ProbeConfig& config, double start,
                       std::unique_ptr<ProbeSink>* out);
  Status OnStart(Simulation& simulation) override;
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  Status Finish(Simulation& simulation, bool interrupted) override;
  /// Writes the rows made so far (those up to the last reading; the rest need the next step's).
  Status Flush() { return m_csv->Flush(); }
  int64_t Rows() const { return m_csv ? m_csv->Rows() : 0; }

 private:
  ProbeSink() = default;
  std::string m_path;
  ProbeConfig m_config;
  std::unique_ptr<ProbeCsv> m_csv;
};

}  // namespace sphxr::app
