#include "sphxr/app/cli.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string_view>
#include <vector>

#include "sphxr/app/probe_config.h"
#include "sphxr/app/run_arguments.h"
#include "sphxr/app/scene_file.h"
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

// ---- the options ----------------------------------------------------------------------------------

// What an option does with its value (null for a flag without one); `flag` as given, for messages.
using Apply = Status (*)(const std::string& flag, const char* v, Options* o);

struct OptionSpec {
  const char* flag;
  // Options of one group exclude each other ("--headless and --desktop: give one of them"); null: the
  // option is a group of its own.
  const char* group;
  bool takesValue;
  Apply apply;
};

Status NonEmpty(const std::string& flag, const char* v, const char* why, std::string* out) {
  if (*v == '\0') return Status::Error(flag + why);
  *out = v;
  return Status::Ok();
}

Status ParseCount(const std::string& flag, const char* v, int64_t lo, int64_t hi, int* out) {
  int64_t n = 0;
  if (Status s = ParseInt(flag, v, lo, hi, &n); !s) return s;
  *out = static_cast<int>(n);
  return Status::Ok();
}

// WIDTHxHEIGHT, each from `lo` to 8192.
Status ParseSize(const std::string& flag, const char* v, int lo, int* width, int* height) {
  int w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(v, "%dx%d%c", &w, &h, &tail) != 2 || w < lo || h < lo || w > 8192 || h > 8192) {
    return Status::Error(Format("%s %s: must be WIDTHxHEIGHT, each from %d to 8192 (e.g. 1280x720)", flag.c_str(),
                                ShowText(v).c_str(), lo));
  }
  *width = w;
  *height = h;
  return Status::Ok();
}

// One of `names` ("ply", "vtk"), else "FLAG VALUE: must be `choices`".
Status OneOf(const std::string& flag, const char* v, std::initializer_list<const char*> names, const char* choices,
             std::string* out) {
  for (const char* name : names) {
    if (std::string(v) == name) {
      *out = v;
      return Status::Ok();
    }
  }
  return Status::Error(flag + " " + ShowText(v) + ": must be " + choices);
}

// A flag without a value: sets `member` to `value`.
template <auto member, auto value>
Status SetFlag(const std::string&, const char*, Options* o) {
  o->*member = value;
  return Status::Ok();
}

// A value kept as given (a file or folder name).
template <auto member>
Status Store(const std::string&, const char* v, Options* o) {
  o->*member = v;
  return Status::Ok();
}

Status ApplySet(const std::string&, const char* v, Options* o) {
  o->sets.emplace_back(v);
  return Status::Ok();
}

Status ApplyReuse(const std::string&, const char* v, Options* o) {
  const std::string r = v;
  sim::ReuseParams probe;
  if (r != "on" && r != "off" && !sim::ApplyReusePreset(r, &probe)) {
    return Status::Error("--reuse " + ShowText(r) + ": must be on, off or a preset (" + sim::ReusePresetNames() + ")");
  }
  o->reuse = r == "off" ? 0 : 1;
  o->reusePreset = (r == "on" || r == "off") ? "" : r;
  return Status::Ok();
}

Status ApplyDevice(const std::string& flag, const char* v, Options* o) {
  if (!sim::ParseDevice(v, &o->device)) return Status::Error(flag + " " + ShowText(v) + ": must be auto, cpu or cuda (or cpu-reference)");
  return Status::Ok();
}

Status ApplySpacing(const std::string& flag, const char* v, Options* o) {
  double h;
  const sim::ParamInfo* info = sim::FindSolverParam("spacing");
  if (Status s = ParseDouble(flag, v, info->min, info->max, &h); !s) return s;
  o->spacing = static_cast<float>(h);
  return Status::Ok();
}

Status ApplyQuality(const std::string&, const char* v, Options* o) {
  const std::string q = v;
  if (q != "auto" && q != "scene") return Status::Error("--quality " + ShowText(q) + ": must be auto or scene");
  o->quality = q == "auto" ? 1 : 0;
  return Status::Ok();
}

Status ApplyRenderQuality(const std::string& flag, const char* v, Options* o) {
  render::RenderQuality q;
  if (!render::ParseRenderQuality(v, &q)) return Status::Error(flag + " " + ShowText(v) + ": must be high, medium or low");
  o->renderQuality = v;
  return Status::Ok();
}

Status ApplyRender(const std::string&, const char* v, Options* o) {
  const std::string r = v;
  if (r != "water" && r != "particles") return Status::Error("--render " + ShowText(r) + ": must be water or particles");
  o->particleImages = r == "particles";
  return Status::Ok();
}

// A number of the run's own table (run_arguments.h): --time, --settle, --steps, --threads.
template <typename T, T Options::*member>
Status ApplyRunArgument(const std::string& flag, const char* v, Options* o) {
  double value = 0.0;
  if (Status s = ParseRunArgument(flag, v, &value); !s) return s;
  o->*member = static_cast<T>(value);
  return Status::Ok();
}

// Every option of the command line, as UsageText lists them.
const OptionSpec kOptions[] = {
    {"--help", nullptr, false, SetFlag<&Options::help, true>},
    {"-h", nullptr, false, SetFlag<&Options::help, true>},
    {"--print-scene-reference", nullptr, false,
     SetFlag<&Options::printSceneReference, true>},
    {"--headless", "mode", false, SetFlag<&Options::mode, Mode::kHeadless>},
    {"--desktop", "mode", false, SetFlag<&Options::mode, Mode::kDesktop>},
    {"--xr", "mode", false, SetFlag<&Options::mode, Mode::kXr>},
    {"--reuse", nullptr, true, ApplyReuse},
    {"--validate", nullptr, false, SetFlag<&Options::validate, true>},
    {"--progress", "progress", false, SetFlag<&Options::progress, 1>},
    {"--no-progress", "progress", false, SetFlag<&Options::progress, 0>},
    {"--scene", nullptr, true,
     [](const std::string& f, const char* v, Options* o) {
       return NonEmpty(f, v, ": give a file name (without --scene: the default scene)", &o->scenePath);
     }},
    {"--time", nullptr, true, ApplyRunArgument<double, &Options::time>},
    {"--settle", nullptr, true, ApplyRunArgument<double, &Options::settle>},
    {"--steps", nullptr, true, ApplyRunArgument<int64_t, &Options::steps>},
    {"--threads", nullptr, true, ApplyRunArgument<int, &Options::threads>},
    {"--load-state", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return NonEmpty(f, v, ": give a file name", &o->loadState); }},
    {"--save-state", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return NonEmpty(f, v, ": give a file name", &o->saveState); }},
    {"--device", nullptr, true, ApplyDevice},
    {"--spacing", nullptr, true, ApplySpacing},
    {"--set", nullptr, true, ApplySet},
    {"--export-every", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return ParseInt(f, v, 1, int64_t{1} << 40, &o->exportEvery); }},
    {"--out", nullptr, true, Store<&Options::outDir>},
    {"--export-format", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return OneOf(f, v, {"ply", "vtk"}, "ply or vtk", &o->exportFormat); }},
    {"--export-surface-every", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return ParseInt(f, v, 1, int64_t{1} << 40, &o->exportSurfaceEvery); }},
    {"--surface-format", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return OneOf(f, v, {"ply", "obj"}, "ply or obj", &o->surfaceFormat); }},
    {"--screenshot", nullptr, true,
     [](const std::string& f, const char* v, Options* o) {
       return NonEmpty(f, v, ": give a file name (without --screenshot: no picture)", &o->screenshotPath);
     }},
    {"--frames", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return NonEmpty(f, v, ": give a folder name", &o->framesDir); }},
    {"--fps", nullptr, true, [](const std::string& f, const char* v, Options* o) { return ParseDouble(f, v, 0.1, 1000.0, &o->fps); }},
    {"--image-size", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return ParseSize(f, v, 16, &o->imageWidth, &o->imageHeight); }},
    {"--window-size", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return ParseSize(f, v, 64, &o->windowWidth, &o->windowHeight); }},
    {"--frame-limit", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return ParseCount(f, v, 1, 1 << 30, &o->frameLimit); }},
    {"--quality", nullptr, true, ApplyQuality},
    {"--render-quality", nullptr, true, ApplyRenderQuality},
    {"--frame-stats", nullptr, true, Store<&Options::frameStatsPath>},
    {"--gl-debug", nullptr, false, SetFlag<&Options::glDebug, true>},
    {"--no-vsync", nullptr, false, SetFlag<&Options::vsync, false>},
    {"--render", nullptr, true, ApplyRender},
    {"--checkpoint-every", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return ParseDouble(f, v, 1e-6, 1e6, &o->checkpointEvery); }},
    {"--checkpoint-keep", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return ParseCount(f, v, 1, 100, &o->checkpointKeep); }},
    // (As probes.every: an interval below a microsecond exports every step of any run.)
    {"--export-interval", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return ParseDouble(f, v, kMinProbeInterval, 1e6, &o->exportInterval); }},
    {"--export-surface-interval", nullptr, true,
     [](const std::string& f, const char* v, Options* o) {
       return ParseDouble(f, v, kMinProbeInterval, 1e6, &o->exportSurfaceInterval);
     }},
    {"--probes", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return NonEmpty(f, v, ": needs a file name", &o->probesPath); }},
    {"--stats", nullptr, true,
     [](const std::string& f, const char* v, Options* o) { return NonEmpty(f, v, ": needs a file name", &o->statsPath); }},
};

const OptionSpec* FindOption(const std::string& arg) {
  for (const OptionSpec& spec : kOptions) {
    if (arg == spec.flag) return &spec;
  }
  return nullptr;
}

// Each option once, except --set; the options of a group (the modes, --progress/--no-progress) count as
// one. `seen` holds "GROUP FLAG" of the options given so far.
Status CheckGivenOnce(const std::string& arg, const OptionSpec* spec, std::vector<std::string>* seen) {
  if (arg == "--set" || arg.rfind("--", 0) != 0) return Status::Ok();
  const std::string group = spec && spec->group ? spec->group : arg;
  for (const std::string& earlier : *seen) {
    if (earlier.substr(0, earlier.find(' ')) != group) continue;
    const std::string first = earlier.substr(earlier.find(' ') + 1);
    if (first == arg) return Status::Error(ShowText(arg) + " is given twice: give it once");
    return Status::Error(first + " and " + arg + ": give one of them");
  }
  seen->push_back(group + " " + arg);
  return Status::Ok();
}

// The value after argv[*i] (moving *i on to it). An option is never another option's value (`--stats
// --validate` must not write a file named --validate); a file whose name starts with "--" is given as
// ./--name.
Status TakeValue(const std::string& arg, int argc, const char* const* argv, int* i, const char** v) {
  if (*i + 1 >= argc) return Status::Error(arg + ": missing value (see --help)");
  const std::string next = argv[*i + 1];
  if (next.size() > 2 && next.rfind("--", 0) == 0) {
    return Status::Error(arg + ": missing value before " + ShowText(next) + " (a value that starts with -- is "
                               "written ./" + ShowText(next) + " for a file)");
  }
  *v = argv[++*i];
  return Status::Ok();
}

// Options that exclude each other's values.
Status CheckExclusions(const Options& o) {
  if (o.time > 0.0 && o.steps > 0) return Status::Error("--time and --steps: give one, not both");
  if (o.exportEvery > 0 && o.exportInterval > 0.0) {
    return Status::Error("--export-every and --export-interval: give one, not both");
  }
  if (o.exportSurfaceEvery > 0 && o.exportSurfaceInterval > 0.0) {
    return Status::Error("--export-surface-every and --export-surface-interval: give one, not both");
  }
  for (const std::string& set : o.sets) {
    if (o.spacing > 0.0f && set.rfind("spacing=", 0) == 0) {
      return Status::Error("--spacing and --set " + ShowText(set, 40) + ": give one of them");
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
  std::vector<std::string> seen;  // "GROUP FLAG" of each option given (CheckGivenOnce)
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const OptionSpec* spec = FindOption(arg);
    if (Status s = CheckGivenOnce(arg, spec, &seen); !s) return s;
    if (!spec) return Status::Error("unknown argument '" + ShowText(arg) + "' (see --help)");
    const char* v = nullptr;
    if (spec->takesValue) {
      if (Status s = TakeValue(arg, argc, argv, &i, &v); !s) return s;
    }
    if (Status s = spec->apply(arg, v, out); !s) return s;
  }
  if (Status s = CheckExclusions(*out); !s) return s;
  if (Status s = CheckOptionsTakeEffect(*out, seen); !s) return s;

  // A scene by name: the current directory, the installed scenes, the build's (scene_search.cpp). The
  // command line only names it: a name found nowhere stays as given, and reading it says where it was
  // looked for (LoadSceneWithOptions).
  const std::string name = out->scenePath.empty() ? "dam_break" : out->scenePath;
  if (!FindScene(name, &out->scenePath)) out->scenePath = name;
  return Status::Ok();
}

}  // namespace sphxr::app
