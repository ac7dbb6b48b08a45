#include <imgui.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "desktop_impl.h"
#include "sphxr/app/param_registry.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::app {
namespace {

// Parameters: the one registry (app/src/param_registry.h) that scene files and --set read too. True
// when an edit of `p` in `setup` is finished (the scene is then rebuilt).
bool EditParam(const ParamDesc& p, sim::SceneSetup& setup) {
  bool edited = false;
  if (p.integer) {
    int v = static_cast<int>(p.Get(setup));
    ImGui::DragInt(p.name.c_str(), &v, 0.2f, static_cast<int>(p.min), static_cast<int>(p.max), "%d",
                   ImGuiSliderFlags_AlwaysClamp);
    if (ImGui::IsItemDeactivatedAfterEdit() || (ImGui::IsItemEdited() && !ImGui::IsItemActive())) edited = true;
    if (ImGui::IsItemEdited()) p.Set(&setup, v);
  } else {
    float v = static_cast<float>(p.Get(setup));
    const float lo = static_cast<float>(p.min), hi = static_cast<float>(p.max);
    if (p.name == "spacing") {
      // A spacing that would make millions of particles is refused by the solver with a message.
      ImGui::SliderFloat("spacing (m)", &v, std::max(lo, 5e-4f), std::min(hi, 0.05f), "%.4f",
                         ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp);
    } else {
      ImGui::DragFloat(p.name.c_str(), &v, 0.005f * std::max(std::abs(v), 0.1f), lo, hi, "%.4g",
                       ImGuiSliderFlags_AlwaysClamp);
    }
    if (ImGui::IsItemEdited()) p.Set(&setup, v);
    edited = ImGui::IsItemDeactivatedAfterEdit();
  }
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip("%s\nrange %g to %g %s, default %g", p.help.c_str(), p.min, p.max, p.unit.c_str(), p.defaultValue);
  }
  return edited;
}

}  // namespace

void DesktopApp::Impl::Panel(const SimSnapshot& snap) {
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(360, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSizeConstraints(ImVec2(260, 80), ImVec2(700, std::max(100.0f, ImGui::GetIO().DisplaySize.y - 20)));
  ImGui::Begin("sphxr");
  PanelStatus(snap);
  PanelTiming(snap);
  PanelProbesAndPaddles(snap);
  PanelSolver(snap);
  PanelReuse(snap);
  PanelRender();
  ImGui::TextDisabled("left drag: paddle  right drag: orbit  middle drag: pan  wheel: zoom  f: frame");
  if (hand.active) {
    ImGui::Text("hand target [%.3f %.3f %.3f] m, speed %.2f m/s", hand.position[0], hand.position[1], hand.position[2],
                std::sqrt(hand.velocity[0] * hand.velocity[0] + hand.velocity[1] * hand.velocity[1] +
                          hand.velocity[2] * hand.velocity[2]));
  }
  ImGui::End();
}

// The scene, the run's buttons, the messages and the rates.
void DesktopApp::Impl::PanelStatus(const SimSnapshot& snap) {
  // Scene
  if (!sceneFiles.empty()) {
    const std::string current = sceneIndex >= 0 ? std::filesystem::path(sceneFiles[sceneIndex]).stem().string() : "(other)";
    if (ImGui::BeginCombo("scene", current.c_str())) {
      for (size_t i = 0; i < sceneFiles.size(); ++i) {
        if (ImGui::Selectable(std::filesystem::path(sceneFiles[i]).stem().string().c_str(), static_cast<int>(i) == sceneIndex)) {
          sceneIndex = static_cast<int>(i);
          LoadSceneFile(sceneFiles[i]);
        }
      }
      ImGui::EndCombo();
    }
  }
  if (ImGui::Button(worker->Paused() ? "run (space)" : "pause (space)")) worker->SetPaused(!worker->Paused());
  ImGui::SameLine();
  if (ImGui::Button("step (n)")) {
    worker->SetPaused(true);
    worker->StepOnce();
  }
  ImGui::SameLine();
  if (ImGui::Button("reset (r)")) Rebuild();
  ImGui::SameLine();
  if (ImGui::Button("save state (s)")) SaveState();
  if (!saveMessage.empty()) ImGui::TextWrapped("%s", saveMessage.c_str());
  const std::string error = worker->LastError();
  if (!error.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", error.c_str());

  ImGui::Text("%d fluid + %d boundary particles", snap.fluidCount, snap.boundaryCount);
  ImGui::Text("t = %.3f s, step %lld, dt %.2e s", snap.last.time, static_cast<long long>(snap.steps), snap.last.dt);
  ImGui::Text("simulation %.1f steps/s, %.3g simulated s per wall s", snap.stepsPerSecond, snap.simSecondsPerWallSecond);
  // The worker never runs ahead of wall time; when it falls behind, the water is shown slower than real.
  if (snap.simSecondsPerWallSecond > 0.0 && snap.simSecondsPerWallSecond < 0.95) {
    ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "x%.2f real time (this machine cannot keep up)",
                       snap.simSecondsPerWallSecond);
  }
  ImGui::Text("display %.1f fps, render %.2f ms", ImGui::GetIO().Framerate, renderMs);
}

// Timing graph per stage
void DesktopApp::Impl::PanelTiming(const SimSnapshot& snap) {
  if (ImGui::CollapsingHeader("timing (ms per step / frame)", ImGuiTreeNodeFlags_DefaultOpen)) {
    for (int s = 0; s <= static_cast<int>(sim::Stage::kCount) + 1; ++s) {
      const std::deque<float>& h = stageHistory[s];
      std::vector<float> values(h.begin(), h.end());
      const int n = static_cast<int>(sim::Stage::kCount);
      const char* name = s < n ? sim::StageName(static_cast<sim::Stage>(s)) : s == n ? "surface" : "render";
      const float last = values.empty() ? 0.0f : values.back();
      const float top = values.empty() ? 1.0f : std::max(1e-3f, *std::max_element(values.begin(), values.end()));
      const std::string label = Format("%-9s %6.2f", name, last);
      ImGui::PlotLines(label.c_str(), values.data(), static_cast<int>(values.size()), 0, nullptr, 0.0f, top, ImVec2(180, 22));
    }
    if (mode == render::RenderMode::kWater) {
      ImGui::TextDisabled("surface: HPMC, %lld triangles, cell %.4f m, %.2f ms per extraction",
                          static_cast<long long>(snap.SurfaceTriangles()), snap.surfaceCellSize, snap.surfaceMs);
    } else {
      ImGui::TextDisabled("surface: not extracted in particle mode");
    }
  }
}

void DesktopApp::Impl::PanelProbesAndPaddles(const SimSnapshot& snap) {
  // The scene's probes over the last seconds (its "probes" section).
  if (!snap.probes.empty() && ImGui::CollapsingHeader("probes (last 5 s)", ImGuiTreeNodeFlags_DefaultOpen)) {
    DrawProbePlots(snap.probes, 180.0f);
  }

  // Paddles: where they are, what the water does to them, what a hand would feel.
  if (ImGui::CollapsingHeader("paddles", ImGuiTreeNodeFlags_DefaultOpen)) {
    for (size_t k = 0; k < snap.paddles.size(); ++k) {
      const PaddlePose& p = snap.paddles[k];
      const char* who = p.hand == 0 ? "left hand" : p.hand == 1 ? "right hand" : "script";
      ImGui::Text("%s%s: %s, fluid force %.3f N", who, p.hand == hand.index ? " (mouse)" : "",
                  interaction::PaddleModeName(p.mode), Length(p.force));
    }
    panelHaptic = snap.haptic[hand.index];
    ImGui::ProgressBar(panelHaptic, ImVec2(180, 0), Format("%.2f", panelHaptic).c_str());
    ImGui::SameLine();
    ImGui::Text("haptic (%s)", hand.index == 0 ? "left" : "right");
  }
}

void DesktopApp::Impl::PanelSolver(const SimSnapshot& snap) {
  auto editor = [&](const ParamDesc& p) { return EditParam(p, setup); };
  if (ImGui::CollapsingHeader("solver (edits rebuild the scene)")) {
    // The pressure solver by name, as the scene's solver.method: one button per row of the solver table.
    bool first = true;
    for (const sim::SolverInfo& row : sim::SolverTable()) {
      if (!first) ImGui::SameLine();
      first = false;
      if (ImGui::RadioButton(row.name, setup.method == row.method) && setup.method != row.method) {
        setup.method = row.method;
        Rebuild();
      }
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s\n%s", row.summary, row.paper);
    }
    // The method's own statistics of the last step (its row's columns, as in the stats CSV).
    const sim::SolverInfo& method = sim::SolverInfoOf(setup.method);
    if (!method.columns.empty()) {
      std::string line = "last step:";
      for (const sim::SolveColumn& column : method.columns) {
        const double value = column.Value(snap.last.solve);
        const bool fraction = column.fraction != nullptr;
        line += Format(" %s %.3g%s", column.name, fraction ? 100.0 * value : value, fraction ? " %" : "");
      }
      ImGui::TextUnformatted(line.c_str());
    }
    for (const ParamDesc& p : ParamRegistry()) {
      if (p.group == "solver" && editor(p)) Rebuild();
    }
  }
}

void DesktopApp::Impl::PanelReuse(const SimSnapshot& snap) {
  auto editor = [&](const ParamDesc& p) { return EditParam(p, setup); };
  if (ImGui::CollapsingHeader("activity-based reuse", ImGuiTreeNodeFlags_DefaultOpen)) {
    sim::ReuseParams& r = setup.reuse;
    if (ImGui::Checkbox("reuse on", &r.enabled)) Rebuild();
    ImGui::SameLine();
    ImGui::Text("active fraction %.1f %%", 100.0 * snap.last.activeFraction);
    ImGui::TextUnformatted("preset:");
    for (const char* preset : {"accurate", "balanced", "fast"}) {
      ImGui::SameLine();
      if (ImGui::SmallButton(preset) && sim::ApplyReusePreset(preset, &r)) Rebuild();  // turns reuse on
    }
    for (const ParamDesc& p : ParamRegistry()) {
      if (p.group == "reuse" && editor(p) && r.enabled) Rebuild();
    }
  }
}

void DesktopApp::Impl::PanelRender() {
  if (ImGui::CollapsingHeader("render", ImGuiTreeNodeFlags_DefaultOpen)) {
    int m = static_cast<int>(mode);
    ImGui::RadioButton("water", &m, 0);
    ImGui::SameLine();
    ImGui::RadioButton("particles (m)", &m, 1);
    mode = static_cast<render::RenderMode>(m);
    int c = static_cast<int>(color);
    ImGui::Combo("colour (c)", &c, "speed\0density error\0reuse activity\0");
    color = static_cast<render::ParticleColor>(c);
    int q = static_cast<int>(renderer->Config().quality);
    if (ImGui::Combo("render quality", &q, "low\0medium\0high\0")) renderer->SetQuality(static_cast<render::RenderQuality>(q));
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("high: shadows 2048, spray and foam; medium: shadows 1024; low: neither");
    // The GPU time of each pass (GL_TIME_ELAPSED, a frame or two old).
    const render::DrawStats& drawn = renderer->LastStats();
    if (!drawn.passes.empty() && ImGui::TreeNodeEx("GPU per pass", ImGuiTreeNodeFlags_DefaultOpen)) {
      for (const render::PassTime& pass : drawn.passes) ImGui::Text("%-16s %7.3f ms", pass.name.c_str(), pass.gpuMs);
      ImGui::Text("%-16s %7.3f ms", "all", drawn.GpuMs());
      ImGui::TreePop();
    }
    ImGui::SliderFloat("surface cell (spacings)", &surfaceCell, 0.5f, 2.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("edge of a marching-cubes cell of the water surface, in particle spacings (%.4f m);\n"
                        "finer is smoother and slower (the scene's surface.cell_size sets the start)",
                        surfaceCell * setup.params.spacing);
    }
  }
}

}  // namespace sphxr::app
