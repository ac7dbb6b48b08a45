#include "run.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numeric>
#include <sstream>

#include "sphxr/app/run_arguments.h"
#include "sphxr/app/state_file.h"
#include "sphxr/common/log.h"
#include "sphxr/common/text_file.h"
#include "sphxr/sim/measure.h"

namespace sphxr::python {

/// The run's own record, a sink of the Simulation: every step's figures, the wall time spent stepping,
/// and (for a dam-break scene) the surge front and column height after every step.
class Run::Recorder : public app::SimulationSink {
 public:
  Recorder(const app::SceneFile& scene, bool damBreak) : m_scene(scene), m_damBreak(damBreak && scene.damBreak) {}
  Status OnStart(app::Simulation& simulation) override {
    if (m_damBreak) Measure(simulation);
    return Status::Ok();
  }
  Status OnStep(app::Simulation& simulation, const sim::StepInfo& info) override {
    StepRecord r;
    r.time = info.time;
    r.dt = info.dt;
    r.maxSpeed = info.maxSpeed;
    r.meanDensityError = info.meanDensityError;
    r.maxDensityError = info.maxDensityError;
    r.activeFraction = info.activeFraction;
    r.solve = info.solve;
    steps.push_back(r);
    if (m_damBreak) Measure(simulation);
    return Status::Ok();
  }
  std::vector<StepRecord> steps;
  std::vector<std::array<double, 3>> damBreak;
  double wallSeconds = 0.0;  // inside Step and Run, the recording included

 private:
  void Measure(app::Simulation& simulation) {
    // As the headless summary measures them (app/src/dam_break_measure.cpp MeasureDamBreak, private to
    // app/), the height divided in double.
    simulation.Solver().Download(&m_host);
    const app::DamBreakProbe& probe = *m_scene.damBreak;
    const float spacing = simulation.Setup().params.spacing;
    const int minPerBin = app::DamBreakMinPerBin(probe, spacing);
    const double front = sim::SurgeFront(m_host, probe.wallX, spacing, minPerBin) / probe.columnWidth;
    const double height = sim::ColumnHeight(m_host, probe.floorY, probe.wallX, spacing, std::max(1, minPerBin / 2)) /
                          (2.0 * probe.columnWidth);
    damBreak.push_back({simulation.Solver().Time(), front, height});
  }
  const app::SceneFile& m_scene;
  bool m_damBreak;
  sim::HostFluid m_host;
};

namespace {

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

Status ReadScene(const RunOptions& options, app::SceneFile* scene) {
  if (!options.sceneJson.empty()) return app::ParseScene(options.sceneJson, options.origin, scene);
  std::string path;
  if (Status s = app::FindScene(options.scene, &path, options.installDir); !s) return s;
  return app::LoadScene(path, scene);
}

Status CheckOptions(const RunOptions& options) {
  if (options.sceneJson.empty()) {
    if (Status s = app::CheckPathArgument("scene", options.scene); !s) return s;
  }
  if (Status s = app::CheckPathArgument("base_dir", options.origin, false); !s) return s;
  if (Status s = app::CheckPathArgument("load_state", options.loadState, false); !s) return s;
  if (Status s = app::CheckPathArgument("probes_csv", options.probesCsv, false); !s) return s;
  if (Status s = app::CheckPathArgument("install_dir", options.installDir, false); !s) return s;
  if (Status s = app::CheckRunArgument("threads", options.threads); !s) return s;
  if (options.settle != -1.0) {
    if (Status s = app::CheckRunArgument("settle", options.settle); !s) return s;
  }
  return Status::Ok();
}

}  // namespace

Run::~Run() {
  m_probes.reset();  // closes the file
  if (m_probesTemporary) std::remove(m_probesPath.c_str());
}

Status Run::Create(const RunOptions& options, std::unique_ptr<Run>* out, const KeepGoing& keepGoing) {
  out->reset();
  if (Status s = CheckOptions(options); !s) return s;
  std::unique_ptr<Run> run(new Run());
  app::SceneFile& scene = run->m_scene;
  if (Status s = ReadScene(options, &scene); !s) return s;
  for (const std::string& set : options.sets) {
    if (Status s = app::SetSolverParam(&scene.setup, set); !s) return s;
  }
  app::SimulationConfig config;
  if (!sim::ParseDevice(options.device, &config.solver.device)) {
    return Status::Error("device " + options.device + ": must be auto, cpu or cuda (or cpu-reference)");
  }
  config.solver.threads = options.threads;
  config.solver.validate = options.validate;
  config.errorPrefix = scene.path + ": ";
  if (!options.loadState.empty() && options.settle > 0.0) {
    return Status::Error("settle and load_state: the state file is the start; settle in the run that saves it");
  }
  // A spacing among the overrides must be the state file's, as --set spacing=... on the command line.
  float spacing = 0.0f;
  for (const std::string& set : options.sets) {
    if (set.rfind("spacing=", 0) == 0) spacing = scene.setup.params.spacing;
  }
  std::shared_ptr<const app::StateFile> state;
  if (Status s = app::ReadStartState(options.loadState, spacing, scene.name, &scene.setup, &state); !s) return s;

  // The probe rows, as --probes writes them (a temporary file when no file is asked for).
  if (scene.probes) {
    run->m_probesPath = options.probesCsv;
    if (run->m_probesPath.empty()) {
      const char* tmp = std::getenv("TMPDIR");
      std::string name = std::string(tmp && *tmp ? tmp : "/tmp") + "/sphxr_probes_XXXXXX";
      const int fd = mkstemp(name.data());
      if (fd < 0) return Status::Error("probes: cannot make a temporary file in " + name.substr(0, name.rfind('/')));
      close(fd);
      run->m_probesPath = name;
      run->m_probesTemporary = true;
    }
    if (Status s = app::ProbeSink::Create(run->m_probesPath, *scene.probes, state ? state->clock.time : 0.0,
                                          &run->m_probes);
        !s) {
      return s;
    }
  } else if (!options.probesCsv.empty()) {
    return Status::Error("probes_csv " + options.probesCsv + ": " + scene.path +
                         " has no \"probes\" section (docs/user/scenes.md#probes)");
  }

  app::SimScene simScene = app::SimSceneFromFile(scene);
  simScene.start = state;
  if (Status s = app::Simulation::Create(simScene, config, &run->m_simulation); !s) return s;
  sim::Solver& solver = run->m_simulation->Solver();
  run->m_device = sim::DeviceName(solver.ActiveDevice());
  run->m_fluid = solver.FluidCount();
  run->m_boundary = solver.BoundaryCount();

  const double settle = options.loadState.empty() ? (options.settle >= 0.0 ? options.settle : scene.runSettle) : 0.0;
  if (settle > 0.0) {
    bool stopped = false;
    const sim::SettleProgress progress = [&](double) { return !(stopped = keepGoing && !keepGoing()); };
    if (Status s = solver.Settle(settle, &run->m_settle, progress); !s) return Status::Error("settle: " + s.message());
    if (stopped) return Status::Ok();
  }
  run->m_startTime = solver.Time();
  run->m_recorder = std::make_unique<Recorder>(scene, options.recordDamBreak != 0);
  run->m_simulation->AddSink(run->m_recorder.get());
  if (run->m_probes) run->m_simulation->AddSink(run->m_probes.get());
  if (Status s = run->m_simulation->Start(); !s) return s;
  *out = std::move(run);
  return Status::Ok();
}

Status Run::Step(int64_t steps, double untilTime, const KeepGoing& keepGoing) {
  std::lock_guard<std::mutex> lock(m_mutex);
  sim::Solver& solver = m_simulation->Solver();
  const auto t0 = std::chrono::steady_clock::now();
  Status status;
  bool stopped = false;  // keepGoing said no (a signal): asked once after every step
  const auto goOn = [&] { return !(stopped = keepGoing && !keepGoing()); };
  if (steps >= 0) {
    for (int64_t k = 0; k < steps && !stopped; ++k) {
      if (status = m_simulation->Step(); !status) break;
      goOn();
    }
  } else {  // by frames, the last one ending at the first step at or past the time
    const auto running = [&] { return goOn() && solver.Time() < untilTime - 1e-9; };
    while (!stopped && solver.Time() < untilTime - 1e-9) {
      if (status = m_simulation->AdvanceFrame({}, running); !status) break;
    }
  }
  m_recorder->wallSeconds += Seconds(t0);
  if (m_probes && status) status = m_probes->Flush();
  return status;
}

Status Run::RunScene(const KeepGoing& keepGoing) {
  if (m_scene.runTime > 0.0) return Step(-1, m_scene.runTime, keepGoing);
  if (m_scene.runSteps > 0) return Step(std::max<int64_t>(0, m_scene.runSteps - Steps()), 0.0, keepGoing);
  return Status::Error(m_scene.path + ": the scene has no run.time or run.steps; give steps or a time");
}

Status Run::SaveState(const std::string& path) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (Status s = app::CheckPathArgument("save_state", path); !s) return s;
  return m_simulation->WriteState(path, m_scene.name);
}

Status Run::Download(Particles* out) {
  std::lock_guard<std::mutex> lock(m_mutex);
  sim::HostFluid host;
  m_simulation->Solver().Download(&host);
  const size_t n = host.size();
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return host.id[a] < host.id[b]; });
  out->position.resize(3 * n);
  out->velocity.resize(3 * n);
  out->density.resize(n);
  out->pressure.resize(n);
  out->id.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const size_t i = order[k];
    const sim::Vec4& p = host.position[i];
    const sim::Vec4& v = host.velocity[i];
    out->position[3 * k] = p.x, out->position[3 * k + 1] = p.y, out->position[3 * k + 2] = p.z;
    out->velocity[3 * k] = v.x, out->velocity[3 * k + 1] = v.y, out->velocity[3 * k + 2] = v.z;
    out->density[k] = host.density[i];
    out->pressure[k] = host.pressure[i];
    out->id[k] = host.id[i];
  }
  return Status::Ok();
}

Status Run::Probes(ProbeTable* out) {
  std::lock_guard<std::mutex> lock(m_mutex);
  *out = ProbeTable{};
  if (!m_probes) return Status::Error(m_scene.path + " has no \"probes\" section (docs/user/scenes.md#probes)");
  // The rows up to now: what --probes has at the end of a run (a reading of the state now added; the
  // solver's next step is the same, sim::Solver::SampleProbes), handed to the file and read back.
  if (Status s = m_probes->Finish(*m_simulation, false); !s) return s;
  std::string text;
  if (Status s = ReadTextFile(m_probesPath, "probe file", size_t{1} << 30, &text); !s) return s;
  std::istringstream in(text);
  std::string line;
  // A continued file (a state file's run) starts with the earlier run's rows: they are its rows too.
  std::getline(in, line);
  for (size_t a = 0, b; a <= line.size(); a = b + 1) {
    b = line.find(',', a);
    if (b == std::string::npos) b = line.size();
    out->columns.push_back(line.substr(a, b - a));
  }
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<double> row;
    for (size_t a = 0, b; a <= line.size(); a = b + 1) {
      b = line.find(',', a);
      if (b == std::string::npos) b = line.size();
      row.push_back(b > a ? std::strtod(line.c_str() + a, nullptr) : NAN);
    }
    row.resize(out->columns.size(), NAN);
    out->rows.push_back(std::move(row));
  }
  return Status::Ok();
}

double Run::Time() {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_simulation->Solver().Time();
}

int64_t Run::Steps() {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_simulation->WholeStep();
}

std::map<std::string, double> Run::Summary() {
  std::lock_guard<std::mutex> lock(m_mutex);
  const sim::Solver& solver = m_simulation->Solver();
  const sim::Totals& totals = solver.GetTotals();
  const std::vector<StepRecord>& steps = m_recorder->steps;
  std::map<std::string, double> s;
  s["fluid"] = m_fluid;
  s["boundary"] = m_boundary;
  s["steps"] = static_cast<double>(totals.steps);
  s["whole_steps"] = static_cast<double>(m_simulation->WholeStep());
  s["start_time"] = m_startTime;
  s["time"] = solver.Time();
  s["spacing"] = m_simulation->Setup().params.spacing;
  s["wall_seconds"] = m_recorder->wallSeconds;
  s["step_seconds"] = totals.stepSeconds;
  s["ms_per_step"] = totals.steps > 0 ? 1e3 * totals.stepSeconds / static_cast<double>(totals.steps) : 0.0;
  double peak = 0.0, weighted = 0.0, span = 0.0, speed = 0.0, active = 0.0;
  for (const StepRecord& r : steps) {
    peak = std::max<double>(peak, r.meanDensityError);
    weighted += static_cast<double>(r.meanDensityError) * r.dt;
    span += r.dt;
    speed = std::max<double>(speed, r.maxSpeed);
    active += r.activeFraction;
  }
  s["mean_density_error"] = solver.LastStep().meanDensityError;
  s["max_density_error"] = solver.LastStep().maxDensityError;
  s["peak_mean_density_error"] = peak;
  s["time_mean_density_error"] = span > 0.0 ? weighted / span : 0.0;
  s["max_speed"] = speed;
  s["mean_active_fraction"] = steps.empty() ? 1.0 : active / static_cast<double>(steps.size());
  s["clamped_events"] = static_cast<double>(totals.clampedEvents);
  s["dt_clamped_steps"] = static_cast<double>(totals.dtClampedSteps);
  if (totals.steps > 0) {
    s["density_iterations"] = static_cast<double>(totals.densityIterations) / static_cast<double>(totals.steps);
    s["divergence_iterations"] = static_cast<double>(totals.divergenceIterations) / static_cast<double>(totals.steps);
  }
  s["settle_time"] = m_settle.time;
  if (!m_recorder->damBreak.empty()) {
    s["surge_front"] = m_recorder->damBreak.back()[1];
    s["column_height"] = m_recorder->damBreak.back()[2];
  }
  return s;
}

std::vector<StepRecord> Run::StepHistory() {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_recorder->steps;
}

std::vector<std::array<double, 3>> Run::DamBreakHistory() {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_recorder->damBreak;
}

}  // namespace sphxr::python
