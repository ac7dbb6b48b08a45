#include "sphxr/app/run_start.h"

#include <algorithm>
#include <filesystem>
#include <thread>
#include <utility>
#include <vector>

#include "sphxr/app/quality.h"
#include "sphxr/app/state_file.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace sphxr::app {
namespace {

// Where a path leads: its symbolic links followed, dangling ones too (weakly_canonical stops at a
// dangling link, so `link.csv -> z.csv` and `z.csv` would look like two files until z.csv exists).
std::filesystem::path Resolve(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path p = fs::absolute(path, ec);
  for (int hops = 0; hops < 40 && fs::is_symlink(fs::symlink_status(p, ec)); ++hops) {
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) break;
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  return fs::weakly_canonical(p, ec);
}

// Two paths name the same file: the same inode when both exist (hard links, "./a" and "a"), else the
// same path once links are followed.
bool SameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) return std::filesystem::equivalent(a, b, ec);
  return Resolve(a) == Resolve(b);
}

// An output that is one of the run's inputs, or another output, would be destroyed by it (a typo in
// --stats would wipe a state file that took minutes to settle): refused before anything runs. A state saved
// over the one the run started from is allowed: it was read whole at the start, and is replaced
// atomically (a checkpoint carried forward).
Status CheckOutputsAreNotInputs(const Options& options, const SceneFile& scene) {
  std::vector<std::pair<std::string, std::string>> inputs = {{"the scene", options.scenePath}};
  if (!options.loadState.empty()) inputs.push_back({"--load-state", options.loadState});
  for (const std::string& t : scene.inputs) inputs.push_back({"the trajectory", t});
  const std::pair<const char*, std::string> outputs[] = {
      {"--stats", options.statsPath}, {"--save-state", options.saveState}, {"--screenshot", options.screenshotPath},
      {"--probes", options.probesPath}};
  for (size_t k = 0; k < std::size(outputs); ++k) {
    const auto& [flag, path] = outputs[k];
    if (path.empty()) continue;
    for (const auto& [what, input] : inputs) {
      if (std::string(flag) == "--save-state" && what == "--load-state") continue;
      if (SameFile(path, input)) {
        return Status::Error(Format("%s %s is %s (%s): it would be overwritten; give another file", flag,
                                    ShowText(path).c_str(), what.c_str(), ShowText(input).c_str()));
      }
    }
    for (size_t j = 0; j < k; ++j) {
      if (!outputs[j].second.empty() && SameFile(path, outputs[j].second)) {
        return Status::Error(Format("%s %s is also %s's file: one would overwrite the other; give another file", flag,
                                    ShowText(path).c_str(), outputs[j].first));
      }
    }
  }
  return Status::Ok();
}

}  // namespace

Status LoadSceneWithOptions(const Options& options, SceneFile* scene) {
  if (Status s = LoadScene(options.scenePath, scene); !s) {
    std::string path;
    if (Status where = FindScene(options.scenePath, &path); !where) return where;  // a name found nowhere
    return s;
  }
  if (Status s = CheckOutputsAreNotInputs(options, *scene); !s) return s;
  // A preset from the command line replaces the scene's reuse parameters; --set reuse.* then overrides.
  if (!options.reusePreset.empty()) sim::ApplyReusePreset(options.reusePreset, &scene->setup.reuse);
  for (const std::string& set : options.sets) {
    if (Status s = SetSolverParam(&scene->setup, set); !s) return s;
  }
  if (options.spacing > 0.0f) scene->setup.params.spacing = options.spacing;
  if (options.reuse >= 0) scene->setup.reuse.enabled = options.reuse == 1;
  return Status::Ok();
}

std::string HeadlessOnlyOptions(const Options& options) {
  std::string out;
  auto add = [&](bool given, const char* flag) {
    if (given) out += (out.empty() ? "" : ", ") + std::string(flag);
  };
  add(!options.statsPath.empty(), "--stats");
  add(options.exportEvery > 0, "--export-every");
  add(options.exportSurfaceEvery > 0, "--export-surface-every");
  add(options.exportInterval > 0.0, "--export-interval");
  add(options.exportSurfaceInterval > 0.0, "--export-surface-interval");
  add(!options.probesPath.empty(), "--probes");
  add(options.time > 0.0, "--time");
  add(options.steps > 0, "--steps");
  add(options.settle >= 0.0, "--settle");
  add(options.checkpointEvery > 0.0, "--checkpoint-every");
  return out;
}

float ExplicitSpacing(const Options& options) {
  if (options.spacing > 0.0f) return options.spacing;
  // --set spacing=...: parsed as LoadSceneWithOptions parses it (the last one wins).
  float spacing = 0.0f;
  for (const std::string& set : options.sets) {
    sim::SceneSetup probe;
    probe.params.spacing = 0.0f;
    if (set.rfind("spacing=", 0) == 0 && SetSolverParam(&probe, set)) spacing = probe.params.spacing;
  }
  return spacing;
}

Status ApplyAutoQuality(const Options& options, bool wanted, const StateFile* start, const sim::SolverConfig& config,
                        sim::SceneSetup* setup) {
  if (!wanted || options.spacing > 0.0f) return Status::Ok();
  if (start) {
    SPHXR_LOG_INFO("--quality auto: not with --load-state, whose spacing (%g m) is the file's", start->spacing);
    return Status::Ok();
  }
  QualityChoice choice;
  if (Status s = ChooseQuality(*setup, config, 1.0, 1.0, &choice); !s) return Status::Error(options.scenePath + ": " + s.message());
  setup->params = choice.params;  // the chosen spacing and the method's own parameters for it
  setup->method = choice.method;
  const bool diffuseSet = std::any_of(options.sets.begin(), options.sets.end(),
                                      [](const std::string& kv) { return kv.rfind("diffuse=", 0) == 0; });
  if (TurnOffDiffuseOutOfRealTime(choice.realtime, diffuseSet, &setup->params)) {
    SPHXR_LOG_INFO("--quality auto: spray, foam and bubbles off (the water runs at %.2f of real time here without "
                   "them); --set diffuse=1 keeps them",
                   choice.realtime);
  }
  return Status::Ok();
}

Status PrepareStart(const Options& options, RunStart* out) {
  if (Status s = LoadSceneWithOptions(options, &out->scene); !s) return s;
  out->setup = out->scene.setup;
  return ReadStartState(options.loadState, ExplicitSpacing(options), out->scene.name, &out->setup, &out->state);
}

sim::SolverConfig InteractiveSolverConfig(const Options& options, bool log) {
  sim::SolverConfig config;
  config.device = options.device;
  config.threads = options.threads;
  if (options.threads == 0) {
    // One core is left to the frame loop (and llvmpipe's rasteriser, on machines without a GPU).
    config.threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
    if (log) SPHXR_LOG_INFO("simulation on %d CPU threads, one core left for drawing (--threads to change)", config.threads);
  }
  return config;
}

}  // namespace sphxr::app
