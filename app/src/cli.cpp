#include "sphxr/app/cli.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string_view>
#include <thread>

#include "sphxr/app/probe_config.h"
#include "sphxr/app/quality.h"
#include "sphxr/app/run_arguments.h"
#include "sphxr/app/state_file.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/render/renderer.h"

namespace sphxr::app {
namespace {

Status ParseDouble(const std::string& flag, const char* text, double lo, double hi, double* out) {
  char* end = nullptr;
  // Decimal only: strtod also reads hexadecimal ("0x10" would be 16 s) and "inf".
  const std::string_view t(text);
  const std::string shown = ShowText(text);
  if (t.find_first_of("xXpP") != std::string_view::npos) return Status::Error(flag + " " + shown + ": not a decimal number");
  const double v = std::strtod(text, &end);
  if (!*text || *end != '\0') return Status::Error(flag + " " + shown + ": not a number");
  if (!std::isfinite(v)) return Status::Error(flag + " " + shown + ": not a finite number");
  if (v < lo || v > hi) return Status::Error(Format("%s %s: must be from %g to %g", flag.c_str(), shown.c_str(), lo, hi));
  *out = v;
  return Status::Ok();
}

Status ParseInt(const std::string& flag, const char* text, int64_t lo, int64_t hi, int64_t* out) {
  char* end = nullptr;
  const long long v = std::strtoll(text, &end, 10);
  const std::string shown = ShowText(text);
  if (!*text || *end != '\0') return Status::Error(flag + " " + shown + ": not an integer");
  if (v < lo || v > hi) {
    return Status::Error(Format("%s %s: must be from %lld to %lld", flag.c_str(), shown.c_str(), static_cast<long long>(lo),
                                static_cast<long long>(hi)));
  }
  *out = v;
  return Status::Ok();
}

// An option that does nothing in the run asked for is refused in one line, naming what it needs
// (ignoring it silently would let a user believe it acted).
Status CheckOptionsTakeEffect(const Options& o, const std::vector<std::string>& seen) {
  auto given = [&](const char* flag) {
    for (const std::string& s : seen) {
      if (s.substr(s.find(' ') + 1) == flag) return true;
    }
    return false;
  };
  if (given("--checkpoint-keep") && !given("--checkpoint-every")) {
    return Status::Error("--checkpoint-keep: only with --checkpoint-every S (it keeps the last N checkpoints)");
  }
  if (given("--fps") && o.framesDir.empty()) return Status::Error("--fps: only with --frames DIR (the pictures' rate)");
  if (given("--surface-format") && o.exportSurfaceEvery <= 0 && o.exportSurfaceInterval <= 0.0) {
    return Status::Error("--surface-format: only with --export-surface-every K or --export-surface-interval S");
  }
  if (given("--export-format") && o.exportEvery <= 0 && o.exportInterval <= 0.0) {
    return Status::Error("--export-format: only with --export-every K or --export-interval S");
  }
  if (o.mode == Mode::kHeadless) {
    for (const char* flag : {"--window-size", "--frame-limit", "--no-vsync"}) {
      if (given(flag)) return Status::Error(std::string(flag) + ": --headless has no window (it is for --desktop and --xr)");
    }
    if (given("--render") && o.screenshotPath.empty() && o.framesDir.empty()) {
      return Status::Error("--render: --headless makes no picture without --screenshot FILE.png or --frames DIR");
    }
  }
  return Status::Ok();
}

}  // namespace

std::string UsageText() {
  return "usage: sphxr [--xr | --desktop | --headless] [--scene FILE] [--time S | --steps N] [--settle S]\n"
         "             [--load-state FILE] [--save-state FILE [--checkpoint-every S [--checkpoint-keep N]]]\n"
         "             [--device auto|cpu|cuda|cpu-reference] [--threads T] [--spacing H] [--set KEY=VALUE]... [--export-every K --out DIR]\n"
         "             [--export-interval S] [--export-surface-interval S] [--probes FILE.csv]\n"
         "             [--export-format ply|vtk] [--stats FILE.csv] [--validate] [--reuse on|off|PRESET]\n"
         "             [--export-surface-every K [--surface-format ply|obj]] [--progress | --no-progress]\n"
         "             [--screenshot FILE.png] [--frames DIR [--fps F]]\n"
         "             [--image-size WxH] [--render water|particles] [--quality auto|scene] [--gl-debug]\n"
         "             [--render-quality high|medium|low] [--frame-stats FILE.csv]\n"
         "\n"
         "  --xr              the headset (OpenXR), with a mirror window; the default when a runtime answers.\n"
         "                    No runtime: one line, then the desktop window. --frame-limit N ends after N\n"
         "                    frames, --screenshot FILE.png the last mirror image (the left eye);\n"
         "                    XR_RUNTIME_JSON=build/xr/sim_runtime/sphxr_sim_runtime.json: the simulated\n"
         "                    headset (docs/dev/xr.md)\n"
         "  --desktop         a window with the water, a panel and a mouse-driven hand (the default when a\n"
         "                    display is present); --window-size WxH, --frame-limit N, --no-vsync\n"
         "  --headless        run without a window (the default without a display); Ctrl-C stops it after\n"
         "                    the step in progress, keeping the summary, whole CSV rows and a last export\n"
         "  --quality Q       auto: measure this machine and pick the spacing that runs in real time\n"
         "                    (the window's default), and lower the render quality while frames do not\n"
         "                    fit; scene: the scene's spacing (the headless default)\n"
         "  --render-quality L  where the drawing starts: high (shadows 2048, spray and foam), medium\n"
         "                    (shadows 1024), low (no shadows, no spray or foam); pictures use it too\n"
         "  --frame-stats F   window and headset: a CSV row per frame with the GPU time of each pass\n"
         "  --scene FILE      JSON scene: a file, or a scene's name (stir) looked for in the current\n"
         "                    directory, then the installed scenes (PREFIX/share/sphxr/scenes) or, run\n"
         "                    from the build tree, the source tree's scenes/ (default: dam_break)\n"
         "  --time S          simulated seconds to run (default: the scene's run.time)\n"
         "  --steps N         number of steps instead of a time\n"
         "  --settle S        before the run, relax the water to rest for S simulated seconds (energy\n"
         "                    minimisation on the solver's steps; the run then starts at t = 0 from that\n"
         "                    state; default: the scene's run.settle; 0: none)\n"
         "  --save-state FILE write the fluid and the clock to FILE at the end of the run (also when it is\n"
         "                    stopped early), to start another run from; in the window and --xr, the\n"
         "                    file their save writes (the s key, the panel, the headset's save button)\n"
         "  --checkpoint-every S  also save the state to the --save-state FILE every S simulated seconds\n"
         "                    during a headless run (atomically; a kill loses at most S), keeping the last N\n"
         "                    (--checkpoint-keep, default 2: FILE and FILE.1)\n"
         "  --load-state FILE start from a state file instead of the scene's fluid (the same scene; its\n"
         "                    spacing is the file's); --time is then the end time on the file's clock\n"
         "  --device D        auto (CUDA when a GPU answers, else CPU), cpu, or cuda; cpu-reference: the\n"
         "                    CUDA backend's step run on the CPU (slow; for checking, docs/dev/backends.md)\n"
         "  --threads T       CPU backend threads (0 = all cores)\n"
         "  --spacing H       particle spacing in m (rescales the particle count of the scene)\n"
         "  --set KEY=VALUE   a parameter of the scene's \"solver\" section (stiffness=2e5) or \"reuse\" section\n"
         "                    (reuse.threshold=0.8)\n"
         "  --export-every K  write the particles every K steps to DIR (PLY or VTK: ParaView, Blender)\n"
         "  --export-surface-every K  write the water surface (HPMC mesh, the scene's \"surface\" section) every K\n"
         "                    steps to DIR as surface_NNNNNN.ply (binary, with normals) or .obj (--surface-format)\n"
         "  --stats FILE.csv  one CSV row per step (time, dt, speeds, density errors, probes)\n"
         "  --export-interval S, --export-surface-interval S  the particles, the surface every S simulated\n"
         "                    seconds (the first step at or after each multiple of S) instead of every K steps;\n"
         "                    every export names its step and time (PLY comment, VTK field data, OBJ comment)\n"
         "  --probes FILE.csv the scene's \"probes\" section (pressure sensors, level gauges, paddle forces): a\n"
         "                    row every probes.every simulated seconds, interpolated between steps\n"
         "  --progress, --no-progress  a progress bar with the time left, or none (default: the bar on a\n"
         "                    terminal, a progress line a minute when stderr is a log file)\n"
         "  --validate        check every stage for non-finite values; stop at the first, naming it\n"
         "  --reuse on|off|accurate|balanced|fast\n"
         "                    activity-based reuse: on/off keeps the scene's \"reuse\" parameters, a preset\n"
         "                    replaces them; --set reuse.threshold=1.3 etc. override them\n"
         "                    (docs/design/impulse_hold.md)\n"

         "  --screenshot FILE.png  a picture of the last state (OpenGL through EGL, no display needed);\n"
         "                    with --desktop, the window (panel included) when it closes\n"
         "  --frames DIR      a PNG every 1/F simulated seconds (--fps F, default 30); DIR/movie.mp4 when\n"
         "                    ffmpeg is on the PATH\n"
         "  --image-size WxH  size of the pictures (default 1280x720)\n"
         "  --render MODE     water (default) or particles (coloured by speed)\n"
         "  --gl-debug        OpenGL debug output on (as in debug builds): any GL error aborts, naming the call\n"
         "  --print-scene-reference  the scene parameters' reference (markdown, from the parameter registry;\n"
         "                    docs/user/scenes.md holds it)\n";
}

Status ParseCommandLine(int argc, const char* const* argv, Options* out) {
  *out = Options{};
  // Each option once (a repeated --steps kept the last without a word), except --set; the mode flags
  // and --progress/--no-progress count as one option each.
  std::vector<std::string> seen;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg != "--set" && arg.rfind("--", 0) == 0) {
      const bool modeFlag = arg == "--headless" || arg == "--desktop" || arg == "--xr";
      const bool progressFlag = arg == "--progress" || arg == "--no-progress";
      const std::string group = modeFlag ? "mode" : progressFlag ? "progress" : arg;
      for (const std::string& earlier : seen) {
        if (earlier.substr(0, earlier.find(' ')) != group) continue;
        const std::string first = earlier.substr(earlier.find(' ') + 1);
        if (first == arg) return Status::Error(ShowText(arg) + " is given twice: give it once");
        return Status::Error(first + " and " + arg + ": give one of them");
      }
      seen.push_back(group + " " + arg);
    }
    auto value = [&](const char** v) -> Status {
      if (i + 1 >= argc) return Status::Error(arg + ": missing value (see --help)");
      // An option is never another option's value (--stats --validate wrote a file named --validate); a
      // file whose name starts with "--" is given as ./--name.
      const std::string next = argv[i + 1];
      if (next.size() > 2 && next.rfind("--", 0) == 0) {
        return Status::Error(arg + ": missing value before " + ShowText(next) + " (a value that starts with -- is "
                                   "written ./" + ShowText(next) + " for a file)");
      }
      *v = argv[++i];
      return Status::Ok();
    };
    const char* v = nullptr;
    if (arg == "--help" || arg == "-h") {
      out->help = true;
    } else if (arg == "--print-scene-reference") {
      out->printSceneReference = true;
    } else if (arg == "--headless") {
      out->mode = Mode::kHeadless;
    } else if (arg == "--desktop") {
      out->mode = Mode::kDesktop;
    } else if (arg == "--xr") {
      out->mode = Mode::kXr;
    } else if (arg == "--reuse") {
      if (Status s = value(&v); !s) return s;
      const std::string r = v;
      sim::ReuseParams probe;
      if (r != "on" && r != "off" && !sim::ApplyReusePreset(r, &probe)) {
        return Status::Error("--reuse " + ShowText(r) + ": must be on, off or a preset (" + sim::ReusePresetNames() + ")");
      }
      out->reuse = r == "off" ? 0 : 1;
      out->reusePreset = (r == "on" || r == "off") ? "" : r;
    } else if (arg == "--validate") {
      out->validate = true;
    } else if (arg == "--progress") {
      out->progress = 1;
    } else if (arg == "--no-progress") {
      out->progress = 0;
    } else if (arg == "--scene") {
      if (Status s = value(&v); !s) return s;
      if (*v == '\0') return Status::Error("--scene: give a file name (without --scene: the default scene)");
      out->scenePath = v;
    } else if (arg == "--time") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseRunArgument(arg, v, &out->time); !s) return s;
    } else if (arg == "--settle") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseRunArgument(arg, v, &out->settle); !s) return s;
    } else if (arg == "--load-state" || arg == "--save-state") {
      if (Status s = value(&v); !s) return s;
      if (*v == '\0') return Status::Error(arg + ": give a file name");
      (arg == "--load-state" ? out->loadState : out->saveState) = v;
    } else if (arg == "--steps") {
      if (Status s = value(&v); !s) return s;
      double steps = 0.0;
      if (Status s = ParseRunArgument(arg, v, &steps); !s) return s;
      out->steps = static_cast<int64_t>(steps);
    } else if (arg == "--device") {
      if (Status s = value(&v); !s) return s;
      if (!sim::ParseDevice(v, &out->device)) return Status::Error(arg + " " + ShowText(v) + ": must be auto, cpu or cuda (or cpu-reference)");
    } else if (arg == "--threads") {
      if (Status s = value(&v); !s) return s;
      double t = 0.0;
      if (Status s = ParseRunArgument(arg, v, &t); !s) return s;
      out->threads = static_cast<int>(t);
    } else if (arg == "--spacing") {
      if (Status s = value(&v); !s) return s;
      double h;
      const sim::ParamInfo* info = sim::FindSolverParam("spacing");
      if (Status s = ParseDouble(arg, v, info->min, info->max, &h); !s) return s;
      out->spacing = static_cast<float>(h);
    } else if (arg == "--set") {
      if (Status s = value(&v); !s) return s;
      out->sets.emplace_back(v);
    } else if (arg == "--export-every") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseInt(arg, v, 1, int64_t{1} << 40, &out->exportEvery); !s) return s;
    } else if (arg == "--out") {
      if (Status s = value(&v); !s) return s;
      out->outDir = v;
    } else if (arg == "--export-format") {
      if (Status s = value(&v); !s) return s;
      out->exportFormat = v;
      if (out->exportFormat != "ply" && out->exportFormat != "vtk") {
        return Status::Error(arg + " " + ShowText(v) + ": must be ply or vtk");
      }
    } else if (arg == "--export-surface-every") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseInt(arg, v, 1, int64_t{1} << 40, &out->exportSurfaceEvery); !s) return s;
    } else if (arg == "--surface-format") {
      if (Status s = value(&v); !s) return s;
      out->surfaceFormat = v;
      if (out->surfaceFormat != "ply" && out->surfaceFormat != "obj") {
        return Status::Error(arg + " " + ShowText(v) + ": must be ply or obj");
      }
    } else if (arg == "--screenshot") {
      if (Status s = value(&v); !s) return s;
      if (*v == '\0') return Status::Error("--screenshot: give a file name (without --screenshot: no picture)");
      out->screenshotPath = v;
    } else if (arg == "--frames") {
      if (Status s = value(&v); !s) return s;
      if (*v == '\0') return Status::Error("--frames: give a folder name");
      out->framesDir = v;
    } else if (arg == "--fps") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseDouble(arg, v, 0.1, 1000.0, &out->fps); !s) return s;
    } else if (arg == "--image-size") {
      if (Status s = value(&v); !s) return s;
      int w = 0, h = 0;
      char tail = 0;
      if (std::sscanf(v, "%dx%d%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192) {
        return Status::Error(arg + " " + ShowText(v) + ": must be WIDTHxHEIGHT, each from 16 to 8192 (e.g. 1280x720)");
      }
      out->imageWidth = w;
      out->imageHeight = h;
    } else if (arg == "--window-size") {
      if (Status s = value(&v); !s) return s;
      int w = 0, h = 0;
      char tail = 0;
      if (std::sscanf(v, "%dx%d%c", &w, &h, &tail) != 2 || w < 64 || h < 64 || w > 8192 || h > 8192) {
        return Status::Error(arg + " " + ShowText(v) + ": must be WIDTHxHEIGHT, each from 64 to 8192 (e.g. 1280x720)");
      }
      out->windowWidth = w;
      out->windowHeight = h;
    } else if (arg == "--frame-limit") {
      if (Status s = value(&v); !s) return s;
      int64_t n = 0;
      if (Status s = ParseInt(arg, v, 1, 1 << 30, &n); !s) return s;
      out->frameLimit = static_cast<int>(n);
    } else if (arg == "--quality") {
      if (Status s = value(&v); !s) return s;
      const std::string q = v;
      if (q != "auto" && q != "scene") return Status::Error("--quality " + ShowText(q) + ": must be auto or scene");
      out->quality = q == "auto" ? 1 : 0;
    } else if (arg == "--render-quality") {
      if (Status s = value(&v); !s) return s;
      render::RenderQuality q;
      if (!render::ParseRenderQuality(v, &q)) return Status::Error(arg + " " + ShowText(v) + ": must be high, medium or low");
      out->renderQuality = v;
    } else if (arg == "--frame-stats") {
      if (Status s = value(&v); !s) return s;
      out->frameStatsPath = v;
    } else if (arg == "--gl-debug") {
      out->glDebug = true;
    } else if (arg == "--no-vsync") {
      out->vsync = false;
    } else if (arg == "--render") {
      if (Status s = value(&v); !s) return s;
      const std::string r = v;
      if (r != "water" && r != "particles") return Status::Error("--render " + ShowText(r) + ": must be water or particles");
      out->particleImages = r == "particles";
    } else if (arg == "--checkpoint-every") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseDouble(arg, v, 1e-6, 1e6, &out->checkpointEvery); !s) return s;
    } else if (arg == "--checkpoint-keep") {
      if (Status s = value(&v); !s) return s;
      int64_t n = 0;
      if (Status s = ParseInt(arg, v, 1, 100, &n); !s) return s;
      out->checkpointKeep = static_cast<int>(n);
    } else if (arg == "--export-interval" || arg == "--export-surface-interval") {
      if (Status s = value(&v); !s) return s;
      double* target = arg == "--export-interval" ? &out->exportInterval : &out->exportSurfaceInterval;
      // (As probes.every: an interval below a microsecond exports every step of any run.)
      if (Status s = ParseDouble(arg, v, kMinProbeInterval, 1e6, target); !s) return s;
    } else if (arg == "--probes") {
      if (Status s = value(&v); !s) return s;
      if (v[0] == '\0') return Status::Error("--probes: needs a file name");
      out->probesPath = v;
    } else if (arg == "--stats") {
      if (Status s = value(&v); !s) return s;
      if (v[0] == '\0') return Status::Error("--stats: needs a file name");
      out->statsPath = v;
    } else {
      return Status::Error("unknown argument '" + ShowText(arg) + "' (see --help)");
    }
  }
  if (out->time > 0.0 && out->steps > 0) return Status::Error("--time and --steps: give one, not both");
  if (out->exportEvery > 0 && out->exportInterval > 0.0) {
    return Status::Error("--export-every and --export-interval: give one, not both");
  }
  if (out->exportSurfaceEvery > 0 && out->exportSurfaceInterval > 0.0) {
    return Status::Error("--export-surface-every and --export-surface-interval: give one, not both");
  }
  for (const std::string& set : out->sets) {
    if (out->spacing > 0.0f && set.rfind("spacing=", 0) == 0) {
      return Status::Error("--spacing and --set " + ShowText(set, 40) + ": give one of them");
    }
  }
  if (Status s = CheckOptionsTakeEffect(*out, seen); !s) return s;

  // A scene by name: the current directory, the installed scenes, the build's (scene_search.cpp). The
  // command line only names it: a name found nowhere stays as given, and reading it says where it was
  // looked for (LoadSceneWithOptions).
  const std::string name = out->scenePath.empty() ? "dam_break" : out->scenePath;
  if (!FindScene(name, &out->scenePath)) out->scenePath = name;
  return Status::Ok();
}

namespace {

// Where a path leads: its symbolic links followed, dangling ones too (weakly_canonical stops at a
// dangling link, so `link.csv -> z.csv` and `z.csv` looked like two files until z.csv existed).
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
  setup->params.spacing = choice.spacing;
  setup->method = choice.method;
  if (choice.pbfSubsteps > 0.0f) setup->params.pbfSubsteps = choice.pbfSubsteps;
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
