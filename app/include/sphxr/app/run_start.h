#pragma once
// What every mode does with the command line's options before it runs: the scene with the command
// line's changes, an output refused when it would overwrite an input, the state file, the solver's
// threads, --quality auto. The headless runner, the desktop window and --xr all start from PrepareStart.
#include <memory>
#include <string>

#include "sphxr/app/options.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {

struct StateFile;

/// Loads options.scenePath and applies the command line's changes to it, in the order every mode uses:
/// a --reuse preset replaces the scene's reuse parameters, then each --set, then --spacing, then
/// --reuse on|off. The headless runner, the desktop window and --xr all start from this.
Status LoadSceneWithOptions(const Options& options, SceneFile* scene);

/// The options given that only a headless run honours (--stats, --export-every, --export-surface-every,
/// --time, --steps, --settle), e.g. "--stats, --time"; empty when none. The desktop window and --xr warn
/// with it once their window is open (a fallback to headless still honours them). --save-state is not
/// one: every mode writes its file (the window's and the headset's saves).
std::string HeadlessOnlyOptions(const Options& options);
/// The spacing the command line asks for (--spacing, else --set spacing=...), 0 when it asks for none.
float ExplicitSpacing(const Options& options);
/// --quality auto, where the mode wants it (`wanted`: headless with --quality auto; the window and --xr
/// unless --quality scene): `setup`'s spacing from ChooseQuality for `config`, unless --spacing is given
/// or a state file (`start`, may be null) fixes it (logged). Errors name the scene file.
Status ApplyAutoQuality(const Options& options, bool wanted, const StateFile* start, const sim::SolverConfig& config,
                        sim::SceneSetup* setup);

/// What every mode starts from: the scene with the command line's changes (LoadSceneWithOptions), its
/// setup with a --load-state file's spacing, and that file, read before anything is allocated (a bad
/// one is one line before any window opens; ReadStartState).
struct RunStart {
  SceneFile scene;
  sim::SceneSetup setup;
  std::shared_ptr<const StateFile> state;  // null without --load-state
};
Status PrepareStart(const Options& options, RunStart* out);
/// The solver's device and threads for the window and --xr: without --threads, one core is left to the
/// frame loop (logged when `log`).
sim::SolverConfig InteractiveSolverConfig(const Options& options, bool log);

}  // namespace sphxr::app
