#include "sim_worker.h"

#include <chrono>
#include <cmath>

#include "sphxr/common/log.h"

namespace sphxr::app {
namespace {
using Clock = std::chrono::steady_clock;
double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }
}  // namespace

SimWorker::SimWorker(const sim::SolverConfig& config) : m_config(config) {}

SimWorker::~SimWorker() { Stop(); }

Status SimWorker::Start(const sim::SceneSetup& setup) {
  if (Status s = sim::Solver::Create(setup, m_config, &m_solver); !s) return s;
  m_setup = setup;
  double zero[static_cast<int>(sim::Stage::kCount)] = {};
  Publish(zero, 0.0);
  m_thread = std::thread([this] { Run(); });
  return Status::Ok();
}

void SimWorker::Reset(const sim::SceneSetup& setup) {
  std::lock_guard lock(m_mutex);
  m_pendingReset = std::make_unique<sim::SceneSetup>(setup);
  m_wake.notify_all();
}

void SimWorker::SetPaused(bool paused) {
  m_paused = paused;
  m_wake.notify_all();
}

void SimWorker::StepOnce() {
  ++m_stepRequests;
  m_wake.notify_all();
}

std::shared_ptr<const SimSnapshot> SimWorker::Latest() const {
  std::lock_guard lock(m_mutex);
  return m_latest;
}

std::string SimWorker::LastError() const {
  std::lock_guard lock(m_mutex);
  return m_error;
}

void SimWorker::Stop() {
  m_stop = true;
  m_wake.notify_all();
  if (m_thread.joinable()) m_thread.join();
}

void SimWorker::Publish(double stageMs[], double stepMs) {
  auto snap = std::make_shared<SimSnapshot>();
  m_solver->Download(&snap->fluid);
  snap->setup = m_setup;
  snap->last = m_solver->LastStep();
  snap->steps = m_solver->GetTotals().steps;
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) snap->stageMs[s] = stageMs[s];
  snap->stepMs = stepMs;
  snap->stepsPerSecond = m_rateSteps;
  snap->simSecondsPerWallSecond = m_rateSim;
  snap->fluidCount = m_solver->FluidCount();
  snap->boundaryCount = m_solver->BoundaryCount();
  std::lock_guard lock(m_mutex);
  m_latest = std::move(snap);
}

void SimWorker::Run() {
  // Real-time pacing: simulated time may not run ahead of wall time (anchored again after a pause).
  Clock::time_point anchorWall = Clock::now();
  double anchorSim = m_solver->Time();
  Clock::time_point lastPublish = Clock::now(), rateWindow = Clock::now();
  int64_t rateSteps0 = m_solver->GetTotals().steps;
  double rateSim0 = m_solver->Time();
  sim::Totals published = m_solver->GetTotals();
  bool dirty = false;
  auto publishNow = [&](Clock::time_point now) {
    const sim::Totals& t = m_solver->GetTotals();
    const double n = std::max<double>(1.0, static_cast<double>(t.steps - published.steps));
    double stageMs[static_cast<int>(sim::Stage::kCount)];
    for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) {
      stageMs[s] = 1e3 * (t.stageSeconds[s] - published.stageSeconds[s]) / n;
    }
    Publish(stageMs, 1e3 * (t.stepSeconds - published.stepSeconds) / n);
    published = t;
    lastPublish = now;
    dirty = false;
  };
  while (!m_stop) {
    std::unique_ptr<sim::SceneSetup> reset;
    {
      std::lock_guard lock(m_mutex);
      reset = std::move(m_pendingReset);
    }
    if (reset) {
      std::unique_ptr<sim::Solver> fresh;
      const Status s = sim::Solver::Create(*reset, m_config, &fresh);
      if (!s) {
        SPHXR_LOG_WARN("scene rebuild refused: %s", s.message().c_str());
        std::lock_guard lock(m_mutex);
        m_error = s.message();
      } else {
        m_solver = std::move(fresh);
        m_setup = *reset;
        {
          std::lock_guard lock(m_mutex);
          m_error.clear();
        }
        anchorWall = Clock::now();
        anchorSim = m_solver->Time();
        published = m_solver->GetTotals();
        rateSteps0 = published.steps;
        rateSim0 = 0.0;
        double zero[static_cast<int>(sim::Stage::kCount)] = {};
        Publish(zero, 0.0);
      }
    }
    const bool stepRequested = m_stepRequests.load() > 0;
    if (m_paused && !stepRequested) {
      if (dirty) publishNow(Clock::now());  // the last steps before the pause are shown
      std::unique_lock lock(m_mutex);
      m_wake.wait_for(lock, std::chrono::milliseconds(20));
      anchorWall = Clock::now();
      anchorSim = m_solver->Time();
      continue;
    }
    if (!stepRequested && m_solver->Time() - anchorSim > Seconds(Clock::now() - anchorWall)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // ahead of real time
    } else {
      if (stepRequested) --m_stepRequests;
      if (Status s = m_solver->Step(); !s) {
        std::lock_guard lock(m_mutex);
        m_error = s.message();
        m_paused = true;
      }
      if (!std::isfinite(m_solver->LastStep().maxSpeed)) {
        std::lock_guard lock(m_mutex);
        m_error = "the simulation became non-finite: press reset, and lower the time step or raise the stiffness";
        m_paused = true;
      }
      dirty = true;
    }
    const Clock::time_point now = Clock::now();
    if (Seconds(now - rateWindow) >= 0.5) {  // rates over half-second windows
      m_rateSteps = (m_solver->GetTotals().steps - rateSteps0) / Seconds(now - rateWindow);
      m_rateSim = (m_solver->Time() - rateSim0) / Seconds(now - rateWindow);
      rateWindow = now;
      rateSteps0 = m_solver->GetTotals().steps;
      rateSim0 = m_solver->Time();
    }
    if (dirty && (Seconds(now - lastPublish) >= 1.0 / 60.0 || m_paused)) publishNow(now);
  }
}

}  // namespace sphxr::app
