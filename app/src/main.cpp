// sphxr: the command line. Picks the mode: --xr (the default when an OpenXR runtime answers and a display
// is present), else --desktop (the default when a display is present), else --headless. Each fallback is
// one line saying why: no runtime -> the desktop window; no window -> headless; a session lost mid-run ->
// the desktop window (or exit when there is no display or the --frame-limit is reached).
#include <cstdio>
#include <exception>
#include <filesystem>
#include <new>
#include <optional>
#include <string>

#include "sphxr/app/cli.h"
#include "sphxr/app/run_start.h"
#include "sphxr/app/desktop.h"
#include "sphxr/app/display.h"
#include "sphxr/app/headless.h"
#include "sphxr/app/param_registry.h"
#include "sphxr/app/run_arguments.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/xr_mode.h"
#include "sphxr/common/host_memory.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace {

using sphxr::app::Mode;
using sphxr::app::Options;

// A bad scene is one error, whatever the mode (a window failing on it is not "unavailable"). False
// after printing it.
bool SceneLoads(const Options& options) {
  // (Only a regular file: a pipe, --scene /dev/stdin, can be read once, by the mode.)
  std::error_code regularError;
  if (!std::filesystem::is_regular_file(options.scenePath, regularError)) return true;
  // (Quietly: the mode loads it again and logs its warnings then, once.)
  const sphxr::LogLevel level = sphxr::GetLogLevel();
  sphxr::SetLogLevel(sphxr::LogLevel::kError);
  sphxr::app::SceneFile scene;
  const sphxr::Status s = sphxr::app::LoadSceneWithOptions(options, &scene);
  sphxr::SetLogLevel(level);
  if (!s) std::fprintf(stderr, "sphxr: error: %s\n", sphxr::app::ShownMessage(s.message()).c_str());
  return static_cast<bool>(s);
}

// Without a mode: files only a headless run writes pick it; else the headset when a runtime answers
// (asked without creating a session).
void PickModeFromOutputsAndRuntime(Options* options) {
  if (options->mode == Mode::kAuto &&
      (!options->statsPath.empty() || options->exportEvery > 0 || options->exportSurfaceEvery > 0 ||
       options->exportInterval > 0.0 || options->exportSurfaceInterval > 0.0 || !options->probesPath.empty() ||
       !options->saveState.empty())) {
    SPHXR_LOG_INFO("--stats/--export-every/--export-interval/--probes/--save-state asked for without a mode: running headless");
    options->mode = Mode::kHeadless;
  }
  if (options->mode == Mode::kAuto && sphxr::app::DisplayAvailable() && sphxr::app::XrRuntimeAvailable(nullptr)) {
    options->mode = Mode::kXr;
  }
}

// --xr: the exit code when the headset's run ends the program; else (a fallback) the mode that takes
// over, set in `options`. `lostStateFor` is set when the window takes over a lost headset's water.
std::optional<int> RunHeadset(Options* options, std::optional<std::string>* lostStateFor) {
  sphxr::app::XrOutcome outcome;
  const sphxr::Status s = sphxr::app::RunXr(*options, &outcome);
  const bool display = sphxr::app::DisplayAvailable();
  if (s && outcome.interrupted) return 128 + outcome.interrupted;  // the shell's convention, as headless
  if (s && !outcome.lost) return 0;
  if (!s && !outcome.fallback) {
    std::fprintf(stderr, "sphxr: error: %s\n", sphxr::app::ShownMessage(s.message()).c_str());
    return 1;
  }
  const std::string why = s ? "the XR session was lost (" + outcome.message + ")" : s.message();
  if (s && (!display || (options->frameLimit > 0 && outcome.frames >= options->frameLimit))) {
    SPHXR_LOG_WARN("%s: exiting", why.c_str());
    return 0;
  }
  SPHXR_LOG_WARN("%s: %s", why.c_str(), display ? "using the desktop window" : "running headless");
  // The window goes on with the water the headset left (saved by RunXr); a headless run starts from the
  // scene (its --time would count from the saved clock), and the file stays for --load-state.
  if (display && !outcome.savedState.empty()) {
    SPHXR_LOG_INFO("the window continues from the headset's water (%s)", outcome.savedState.c_str());
    lostStateFor->emplace(options->loadState);  // what a headless fallback goes back to
    options->loadState = outcome.savedState;
  }
  if (options->frameLimit > 0) options->frameLimit -= static_cast<int>(outcome.frames);
  options->mode = display ? Mode::kDesktop : Mode::kHeadless;
  return std::nullopt;
}

// Still no mode: the window when a display is present, else headless with a picture. True when that
// picture is one nobody asked for (it must not cost the run when EGL is missing).
bool PickWindowOrHeadless(Options* options) {
  if (options->mode != Mode::kAuto) return false;
  options->mode = sphxr::app::DisplayAvailable() ? Mode::kDesktop : Mode::kHeadless;
  if (options->mode != Mode::kHeadless) return false;
  SPHXR_LOG_INFO("no display (DISPLAY is not set): running headless; a picture goes to %s",
                 options->screenshotPath.empty() ? "sphxr_screenshot.png" : options->screenshotPath.c_str());
  if (!options->screenshotPath.empty()) return false;
  options->screenshotPath = "sphxr_screenshot.png";
  return true;
}

// An explicit --headless refuses the window's options (cli.cpp); a headless run that sphxr chose (no
// display, no runtime, a lost window) says in one line which of them it cannot honour.
void WarnWindowOptionsUnused(const Options& options) {
  const Options defaults;
  std::string unused;
  if (options.windowWidth != defaults.windowWidth || options.windowHeight != defaults.windowHeight) unused += " --window-size";
  if (options.frameLimit != defaults.frameLimit) unused += " --frame-limit";
  if (options.vsync != defaults.vsync) unused += " --no-vsync";
  if (!unused.empty()) SPHXR_LOG_WARN("running headless: no window, so%s %s no effect", unused.c_str(),
                                      unused.find(' ', 1) == std::string::npos ? "has" : "have");
}

int RunHeadlessToTheEnd(Options& options, bool autoPicture) {
  sphxr::app::RunSummary summary;
  sphxr::Status run = sphxr::app::RunHeadless(options, &summary);
  if (!run && autoPicture && run.message().rfind("--screenshot", 0) == 0) {  // also "--screenshot/--frames:"
    SPHXR_LOG_WARN("no picture (%s): running without one", run.message().c_str());
    options.screenshotPath.clear();
    run = sphxr::app::RunHeadless(options, &summary);
  }
  if (sphxr::Status s = run; !s) {
    std::fprintf(stderr, "sphxr: error: %s\n", sphxr::app::ShownMessage(s.message()).c_str());
    return 1;
  }
  return summary.interrupted ? 128 + summary.interrupted : 0;  // the shell's convention: 130 after Ctrl-C
}

int Main(int argc, char** argv) {
  Options options;
  if (sphxr::Status s = sphxr::app::ParseCommandLine(argc, argv, &options); !s) {
    std::fprintf(stderr, "sphxr: %s\n", sphxr::app::ShownMessage(s.message()).c_str());
    return 2;
  }
  const bool headlessAsked = options.mode == Mode::kHeadless;
  if (options.help) {
    std::fputs(sphxr::app::UsageText().c_str(), stdout);
    return 0;
  }
  if (options.printSceneReference) {
    std::fputs(sphxr::app::SceneParameterReference().c_str(), stdout);
    return 0;
  }
  if (!SceneLoads(options)) return 1;
  PickModeFromOutputsAndRuntime(&options);
  std::optional<std::string> lostStateFor;  // set when the window takes over a lost headset's water
  if (options.mode == Mode::kXr) {
    if (const std::optional<int> code = RunHeadset(&options, &lostStateFor)) return *code;
  }
  const bool autoPicture = PickWindowOrHeadless(&options);
  if (options.mode == Mode::kDesktop) {
    const sphxr::Status s = sphxr::app::RunDesktop(options);
    if (s) return 0;
    SPHXR_LOG_WARN("desktop window unavailable (%s): running headless", s.message().c_str());
    options.mode = Mode::kHeadless;
    // A headless run starts from the scene (or the user's --load-state), not from a lost headset's water:
    // its --time and --settle mean the scene's run; the saved file stays for --load-state.
    if (lostStateFor) options.loadState = *lostStateFor;
  }
  if (!headlessAsked) WarnWindowOptionsUnused(options);
  return RunHeadlessToTheEnd(options, autoPicture);
}

}  // namespace

int main(int argc, char** argv) {
  // The memory check before allocating (sim's Solver::Create) counts what the particles need; what it
  // cannot see (other processes, fragmentation) ends here as one line instead of an abort.
  try {
    return Main(argc, argv);
  } catch (const std::bad_alloc&) {
    // The stack is unwound here: what was being allocated is known only if it said so (MemoryUse).
    const char* what = sphxr::CurrentMemoryUse();
    std::fprintf(stderr, "sphxr: error: out of memory in %s\n",
                 what ? what : "the particles (use a larger --spacing or a smaller scene)");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sphxr: error: %s\n", sphxr::app::ShownMessage(e.what()).c_str());
  }
  return 1;
}
