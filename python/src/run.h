#pragma once
// One run of a scene for Python (sphxr.Run): the scene read as the command line reads it (a file or a
// scene's name, or the JSON text of a dict), the --set overrides, a state file to start from, the
// settle, then an app::Simulation stepped by steps or simulated time. Plain C++ (no pybind11 here):
// module.cpp turns its results into NumPy arrays and its Status errors into sphxr.Error.
//
// Every method takes the run's mutex, so that two Python threads sharing a Run (the GIL is released
// while it steps) take turns instead of stepping one solver at once.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "sphxr/app/probe_csv.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/simulation.h"
#include "sphxr/common/status.h"

namespace sphxr::python {

struct RunOptions {
  std::string scene;       // a file or a scene's name (app::FindScene), when sceneJson is empty
  std::string sceneJson;   // a dict's JSON text (json.dumps) instead of a file
  std::string origin;      // names the dict's scene in messages; relative paths in it are from its folder
  std::string installDir;  // the installed scenes of the module's own prefix (searched before the build's)
  std::vector<std::string> sets;  // "key=value", as --set
  std::string device = "auto";
  int threads = 0;
  bool validate = false;
  double settle = -1.0;    // s; -1: the scene's run.settle (not with a state file), as the command line
  std::string loadState;   // --load-state
  std::string probesCsv;   // --probes: the file the probe rows go to (empty: a temporary file)
  int recordDamBreak = -1; // the surge front and column height after every step: -1 when the scene probes one
};

/// One step's figures (the stats' columns that need no download).
struct StepRecord {
  double time = 0.0;
  float dt = 0.0f, maxSpeed = 0.0f, meanDensityError = 0.0f, maxDensityError = 0.0f, activeFraction = 1.0f;
  sim::SolveReport solve;  // the pressure solver's own (sphxr/sim/solve_report.h)
};

/// The fluid's fields in particle-id order (the solver keeps them in grid order, which changes).
struct Particles {
  std::vector<float> position, velocity;  // 3 per particle
  std::vector<float> density, pressure;
  std::vector<uint32_t> id;
};

/// The probe rows of the run so far (app::ProbeCsv's: a row every probes.every s, interpolated).
struct ProbeTable {
  std::vector<std::string> columns;  // time, step, then ProbeCsvHeader's
  std::vector<std::vector<double>> rows;  // NaN: an empty cell (dry)
};

/// Checks for a signal (Ctrl-C) now and then during a long step loop; false stops the loop.
using KeepGoing = std::function<bool()>;

class Run {
 public:
  /// The options are checked first (app/run_arguments.h: threads, settle, the file names); `keepGoing`
  /// is asked after every step of the settle, which stops when it says no (status ok, *out empty).
  static Status Create(const RunOptions& options, std::unique_ptr<Run>* out, const KeepGoing& keepGoing = {});
  ~Run();

  /// `steps` steps; or, with steps < 0, frames (Simulation::AdvanceFrame) until the clock reaches
  /// `untilTime` (s), the last frame ending at the first step at or past it. `keepGoing` is asked
  /// after every step; when it says no, the loop stops there (status ok). The probe rows the steps made
  /// are written before it returns: a write that fails (a full disk) is its error.
  Status Step(int64_t steps, double untilTime, const KeepGoing& keepGoing);
  /// The scene's run: to run.time (or run.steps) from the start, as `sphxr --headless` without --time.
  Status RunScene(const KeepGoing& keepGoing);
  Status SaveState(const std::string& path);
  Status Download(Particles* out);
  Status Probes(ProbeTable* out);

  double Time();
  int64_t Steps();  // the whole run's step count (a state file's steps included)
  int FluidCount() const { return m_fluid; }
  int BoundaryCount() const { return m_boundary; }
  const app::SceneFile& Scene() const { return m_scene; }
  const sim::SceneSetup& Setup() const { return m_simulation->Setup(); }
  const std::string& Device() const { return m_device; }
  const sim::SettleReport& Settled() const { return m_settle; }
  /// The summary's numbers (names as in `sphxr --headless`'s summary).
  std::map<std::string, double> Summary();
  std::vector<StepRecord> StepHistory();
  /// (t, Z = front / a, H = height / 2a) after every step from the start; empty without recording.
  std::vector<std::array<double, 3>> DamBreakHistory();

 private:
  Run() = default;
  class Recorder;

  std::mutex m_mutex;
  app::SceneFile m_scene;
  std::unique_ptr<app::Simulation> m_simulation;
  std::unique_ptr<Recorder> m_recorder;
  std::unique_ptr<app::ProbeSink> m_probes;
  std::string m_probesPath;
  bool m_probesTemporary = false;
  std::string m_device;
  int m_fluid = 0, m_boundary = 0;
  double m_startTime = 0.0;
  sim::SettleReport m_settle;
};

}  // namespace sphxr::python
