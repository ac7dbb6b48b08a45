#include "sphxr/app/simulation.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "sphxr/app/scene_file.h"
#include "sphxr/app/state_file.h"
#include "sphxr/common/log.h"

namespace sphxr::app {

SimScene SimSceneFromFile(const SceneFile& scene, std::initializer_list<int> hands) {
  SimScene out;
  out.name = scene.name;
  out.setup = scene.setup;
  out.paddles = scene.paddles;
  out.paddleFrameRate = scene.paddleFrameRate;
  out.surface.params = scene.surface.value_or(sim::SurfaceParams{});
  if (scene.probes) out.probes = scene.probes->set;
  for (int hand : hands) {
    const interaction::Holder holder = hand == 0 ? interaction::Holder::kLeftHand : interaction::Holder::kRightHand;
    bool held = false;
    for (const interaction::PaddleDesc& d : out.paddles) held = held || d.holder == holder;
    if (!held) out.paddles.push_back(DefaultHandPaddle(out.setup, hand));
  }
  return out;
}

interaction::PaddleDesc DefaultHandPaddle(const sim::SceneSetup& setup, int hand) {
  interaction::PaddleDesc d;
  d.name = hand == 0 ? "left hand" : "right hand";
  d.holder = hand == 0 ? interaction::Holder::kLeftHand : interaction::Holder::kRightHand;
  const sim::Aabb& t = setup.tank;
  // At most 10 cm wide, and no wider than a third of the tank's narrower horizontal side.
  const float width = std::min(0.1f, std::min(t.max.x - t.min.x, t.max.z - t.min.z) / 3.0f);
  const float spacing = setup.params.spacing;
  d.shapes = interaction::BladeOnHandle(1.5f * width, std::max(0.6f * spacing, 0.12f * width), width, 1.2f * width,
                                        std::max(1.2f * spacing, 0.12f * width));
  // Full scale at the drag of a brisk 1.4 m/s stroke, 1/2 rho Cd A v^2 with Cd = 2 for a flat plate:
  // 2 rho A (the blade held still in the water then shows about a tenth, its buoyancy).
  d.haptics.fullScaleForce = std::max(0.05f, 2.0f * setup.params.restDensity * width * 1.2f * width);
  return d;
}

Status Simulation::Create(const SimScene& scene, const SimulationConfig& config, std::unique_ptr<Simulation>* out) {
  out->reset();
  std::unique_ptr<Simulation> run(new Simulation());
  run->m_scene = scene;
  run->m_setup = scene.setup;
  // One frame clock: PBF substeps the displayed frame, whose period is the paddles' (pbf_frame is the
  // period only where no Simulation sets it: the sim library alone).
  const float period = 1.0f / static_cast<float>(scene.paddleFrameRate);  // (float: 90 Hz is the default's bits)
  float& pbfFrame = run->m_setup.params.pbfFrame;
  if (pbfFrame != sim::SolverParams{}.pbfFrame && std::abs(pbfFrame - period) > 1e-6f * period) {
    SPHXR_LOG_WARN("pbf_frame %.4g s is not used: PBF substeps the displayed frame, 1 / paddles.frame_rate = %.4g s",
                   pbfFrame, period);
  }
  pbfFrame = period;
  // Paddles: sampled at the final spacing, added to the scene as moving bodies.
  if (!scene.paddles.empty()) {
    if (Status s = interaction::PaddleSystem::Create(scene.paddles, run->m_setup, &run->m_paddles); !s) {
      return Status::Error(config.errorPrefix + s.message());
    }
    run->m_paddles->AddBodies(&run->m_setup);
  }
  if (Status s = sim::Solver::Create(run->m_setup, config.solver, &run->m_solver); !s) {
    return Status::Error(config.errorPrefix + s.message());
  }
  if (!scene.probes.Empty()) {
    if (Status s = run->m_solver->SetProbes(scene.probes); !s) return Status::Error(config.errorPrefix + s.message());
  }
  if (scene.start) {
    // Not strict (a reset after the panel changed the spacing): a mismatch falls back to the scene's own
    // start, with a fresh solver: a refused restore may have changed nothing, but not provably so.
    if (Status s = RestoreState(*scene.start, run->m_solver.get()); !s) {
      if (config.strictStart) return Status::Error("--load-state " + s.message());
      SPHXR_LOG_WARN("%s; starting from the scene instead", s.message().c_str());
      if (Status c = sim::Solver::Create(run->m_setup, config.solver, &run->m_solver); !c) {
        return Status::Error(config.errorPrefix + c.message());
      }
    } else {
      run->m_restored = true;
      run->m_stepsBefore = scene.start->step;  // -1 (unknown) stays unknown in what it saves
    }
  }
  run->m_nextFrame = run->m_solver->Time();  // the first step begins the first frame
  if (run->m_paddles) {
    if (Status s = run->m_paddles->Attach(run->m_solver.get()); !s) return s;
    if (run->m_restored) RestorePaddles(*scene.start, *run->m_solver, run->m_paddles.get(), &run->m_nextFrame);
  }
  *out = std::move(run);
  return Status::Ok();
}

int64_t Simulation::WholeStep() const { return std::max<int64_t>(m_stepsBefore, 0) + m_solver->GetTotals().steps; }

Status Simulation::AdvanceFrame(const std::vector<interaction::HandInput>& hands,
                                const std::function<bool()>& afterStep) {
  do {
    if (Status s = Step(hands); !s) return s;
    if (afterStep && !afterStep()) return Status::Ok();
  } while (m_solver->Time() < m_nextFrame - 1e-9);
  return Status::Ok();
}

Status Simulation::SetFrameRate(double hz) {
  if (!(hz >= kMinFrameRate && hz <= kMaxFrameRate)) {
    return Status::Error(Format("frame rate %g Hz is out of range [%g, %g]", hz, kMinFrameRate, kMaxFrameRate));
  }
  m_pendingFrameRate = hz;
  return Status::Ok();
}

Status Simulation::BeginFrameRate() {
  if (m_pendingFrameRate <= 0.0) return Status::Ok();
  const double hz = std::exchange(m_pendingFrameRate, 0.0);
  if (Status s = m_solver->SetPbfFrame(1.0f / static_cast<float>(hz)); !s) return s;  // PBF substeps the new frame
  m_scene.paddleFrameRate = hz;
  return Status::Ok();
}

Status Simulation::Step(const std::vector<interaction::HandInput>& hands) {
  if (m_solver->Time() >= m_nextFrame - 1e-9) {
    // A frame: at the display's newest rate, the hands the paddles' targets one frame ahead.
    if (Status s = BeginFrameRate(); !s) return s;
    m_nextFrame += FramePeriod();
    if (m_paddles) {
      std::vector<interaction::HandInput> framed = hands;
      for (interaction::HandInput& h : framed) h.time = m_nextFrame;
      if (Status s = m_paddles->BeginFrame(m_nextFrame, framed); !s) return s;
    }
  }
  const Status stepped = m_solver->Step();
  if (stepped && m_paddles) m_paddles->AfterStep();
  if (!stepped) {
    // --validate names the step by the solver's count, this run's; after a state file, say which step
    // of the whole run (the CSV's numbering) that is.
    const int64_t before = std::max<int64_t>(m_stepsBefore, 0);
    if (before == 0 || stepped.message().rfind("validate:", 0) != 0) return stepped;
    return Status::Error(Format("%s (counted in this run; step %lld of the whole run, as the CSV numbers it)",
                                stepped.message().c_str(), static_cast<long long>(WholeStep() + 1)));
  }
  const sim::StepInfo& info = m_solver->LastStep();
  if (!std::isfinite(info.maxSpeed)) {
    return Status::Error(Format("the simulation became non-finite at step %lld (t = %.4g s); rerun with --validate "
                                "to find the stage and particle, and lower solver.fixed_dt or raise solver.stiffness",
                                static_cast<long long>(WholeStep()), info.time));
  }
  for (SimulationSink* sink : m_sinks) {
    if (Status s = sink->OnStep(*this, info); !s) return s;
  }
  return Status::Ok();
}

Status Simulation::Start() {
  for (SimulationSink* sink : m_sinks) {
    if (Status s = sink->OnStart(*this); !s) return s;
  }
  return Status::Ok();
}

Status Simulation::Finish(bool interrupted) {
  for (SimulationSink* sink : m_sinks) {
    if (Status s = sink->Finish(*this, interrupted); !s) return s;
  }
  return Status::Ok();
}

Status Simulation::WriteState(const std::string& path, const std::string& sceneName) const {
  return WriteStateFile(path, *m_solver, sceneName, m_paddles.get(), m_nextFrame, m_stepsBefore);
}

}  // namespace sphxr::app
