#include "sphxr/app/headless.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string_view>

#include "sphxr/app/export.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/quality.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/app/state_file.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/measure.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR "scenes"
#endif

namespace sphxr::app {
namespace {

volatile std::sig_atomic_t g_interrupt = 0;

extern "C" void OnInterrupt(int signal) { g_interrupt = signal; }

/// SIGINT, SIGTERM and SIGHUP (a closed terminal, a dropped ssh session: long runs are started that
/// way) set g_interrupt while a run steps; SA_RESETHAND makes a second signal act as if we had never
/// caught the first (the process ends). The previous handlers come back afterwards.
class InterruptScope {
 public:
  InterruptScope() {
    g_interrupt = 0;
    struct sigaction action {};
    action.sa_handler = OnInterrupt;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;
    sigaction(SIGINT, nullptr, &m_int);
    sigaction(SIGTERM, nullptr, &m_term);
    sigaction(SIGHUP, nullptr, &m_hup);
    // A signal ignored on entry (a background job of a script, nohup) stays ignored.
    if (m_int.sa_handler != SIG_IGN) sigaction(SIGINT, &action, nullptr);
    if (m_term.sa_handler != SIG_IGN) sigaction(SIGTERM, &action, nullptr);
    // SIGHUP without the one-shot reset: a closing terminal's shell and kernel may send it twice in a
    // moment, and the second must not end the run before its state is saved.
    struct sigaction hangUp = action;
    hangUp.sa_flags = 0;
    if (m_hup.sa_handler != SIG_IGN) sigaction(SIGHUP, &hangUp, nullptr);
  }
  ~InterruptScope() {
    sigaction(SIGINT, &m_int, nullptr);
    sigaction(SIGTERM, &m_term, nullptr);
    sigaction(SIGHUP, &m_hup, nullptr);
  }
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  struct sigaction m_int {}, m_term {}, m_hup {};
};

Status ParseDouble(const std::string& flag, const char* text, double lo, double hi, double* out) {
  char* end = nullptr;
  // Decimal only: strtod also reads hexadecimal ("0x10" was 16 s) and "inf".
  const std::string_view t(text);
  if (t.find_first_of("xXpP") != std::string_view::npos) return Status::Error(flag + " " + text + ": not a decimal number");
  const double v = std::strtod(text, &end);
  if (!*text || *end != '\0') return Status::Error(flag + " " + text + ": not a number");
  if (!std::isfinite(v)) return Status::Error(flag + " " + text + ": not a finite number");
  if (v < lo || v > hi) return Status::Error(Format("%s %s: must be from %g to %g", flag.c_str(), text, lo, hi));
  *out = v;
  return Status::Ok();
}

Status ParseInt(const std::string& flag, const char* text, int64_t lo, int64_t hi, int64_t* out) {
  char* end = nullptr;
  const long long v = std::strtoll(text, &end, 10);
  if (!*text || *end != '\0') return Status::Error(flag + " " + text + ": not an integer");
  if (v < lo || v > hi) {
    return Status::Error(Format("%s %s: must be from %lld to %lld", flag.c_str(), text, static_cast<long long>(lo),
                                static_cast<long long>(hi)));
  }
  *out = v;
  return Status::Ok();
}

/// Progress of a long run: a bar redrawn in place on a terminal, or (`lines`: stderr is a log file, the
/// default when it is not a terminal) one line a minute, so a run logged to a file is not silent for
/// minutes. Both say how long is left, extrapolated from the wall time so far.
class Progress {
 public:
  explicit Progress(bool enabled, const char* label = "", bool lines = false)
      : m_enabled(enabled), m_lines(lines && !enabled), m_label(label) {}
  void Update(double fraction, double simTime, int64_t steps, double msPerStep) {
    if (!m_enabled && !m_lines) return;
    const auto now = std::chrono::steady_clock::now();
    if (m_start == std::chrono::steady_clock::time_point{}) m_start = now;
    if (m_lines) {
      if (fraction >= 1.0 || now - m_last < std::chrono::seconds(60)) return;
      if (m_last == std::chrono::steady_clock::time_point{}) {  // the first line a minute in, not at once
        m_last = now;
        return;
      }
      m_last = now;
      SPHXR_LOG_INFO("%s%d %%: t = %.4f s, step %lld, %.2f ms/step%s", m_label, static_cast<int>(fraction * 100.0),
                     simTime, static_cast<long long>(steps), msPerStep, Left(fraction, now).c_str());
      return;
    }
    if (fraction < 1.0 && now - m_last < std::chrono::milliseconds(100)) return;
    m_last = now;
    const int width = 30;
    const int filled = std::clamp(static_cast<int>(fraction * width), 0, width);
    std::fprintf(stderr, "\r%s[%.*s%.*s] %3d%%  t = %.4f s  step %lld  %.2f ms/step%s ", m_label, filled,
                 "##############################", width - filled, "                              ",
                 static_cast<int>(fraction * 100.0), simTime, static_cast<long long>(steps), msPerStep,
                 fraction < 1.0 ? Left(fraction, now).c_str() : "");
    m_open = fraction < 1.0;
    if (!m_open) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }
  /// Ends a bar left unfinished (a run stopped early), so that the next line starts on its own.
  void Finish() {
    if (m_open) std::fprintf(stderr, "\n");
    m_open = false;
  }

 private:
  // ", about 3 min left" once two seconds and a thousandth of the run have passed.
  std::string Left(double fraction, std::chrono::steady_clock::time_point now) const {
    const double elapsed = std::chrono::duration<double>(now - m_start).count();
    if (elapsed < 2.0 || fraction < 1e-3) return {};
    const double left = elapsed * (1.0 - fraction) / fraction;
    if (left < 90.0) return Format(", about %.0f s left", left);
    if (left < 5400.0) return Format(", about %.0f min left", left / 60.0);
    return Format(", about %.1f h left", left / 3600.0);
  }

  bool m_enabled;
  bool m_lines;
  const char* m_label;
  bool m_open = false;
  std::chrono::steady_clock::time_point m_start{}, m_last{};
};

struct DamBreakMeasure {
  float front;   // Z = x_front / a
  float height;  // H = h / 2a
};

DamBreakMeasure MeasureDamBreak(const DamBreakProbe& probe, const sim::HostFluid& fluid, float spacing) {
  const int minPerBin = DamBreakMinPerBin(probe, spacing);
  DamBreakMeasure m;
  m.front = sim::SurgeFront(fluid, probe.wallX, spacing, minPerBin) / probe.columnWidth;
  m.height = sim::ColumnHeight(fluid, probe.floorY, probe.wallX, spacing, std::max(1, minPerBin / 2)) /
             (2.0f * probe.columnWidth);
  return m;
}

/// A file that `flag` writes after the run: not a directory, in a directory we may write into (an
/// empty path: nothing to check).
Status CheckPlaceToWrite(const std::string& flag, const std::string& path, const char* nameHint) {
  if (path.empty()) return Status::Ok();
  const std::filesystem::path file(path);
  const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    return Status::Error(flag + " " + path + ": is a directory; give a file name" + nameHint);
  }
  // (These files are replaced whole: a device or a pipe there is not a place for them.)
  if (std::filesystem::exists(file, ec) && !std::filesystem::is_regular_file(file, ec)) {
    return Status::Error(flag + " " + path + ": not a regular file (a device or pipe); give a file name" + nameHint);
  }
  if (!std::filesystem::is_directory(dir, ec) || access(dir.c_str(), W_OK) != 0) {
    return Status::Error(flag + " " + path + ": cannot write into " + dir.string());
  }
  return Status::Ok();
}

/// The stats CSV's rows, written whole: held here and handed to the file at least once a second of wall
/// time (and before each checkpoint, and at the end, also of a run stopped by a signal), so that a kill
/// loses at most a second of rows and never leaves half a row (the stream's own 8 kB blocks did).
class CsvRows {
 public:
  explicit CsvRows(std::ofstream* out) : m_out(out) {}
  ~CsvRows() { Flush(); }
  CsvRows(const CsvRows&) = delete;
  CsvRows& operator=(const CsvRows&) = delete;
  void Add(const std::string& row) { m_pending += row; }
  bool Due() const {
    return m_pending.size() > (size_t{1} << 20) || std::chrono::steady_clock::now() - m_last >= std::chrono::seconds(1);
  }
  /// False when the file refused the rows (disk full).
  bool Flush() {
    m_last = std::chrono::steady_clock::now();
    if (m_pending.empty() || !m_out->is_open()) return true;
    m_out->write(m_pending.data(), static_cast<std::streamsize>(m_pending.size()));
    m_out->flush();
    m_pending.clear();
    return static_cast<bool>(*m_out);
  }

 private:
  std::ofstream* m_out;
  std::string m_pending;
  std::chrono::steady_clock::time_point m_last = std::chrono::steady_clock::now();
};

/// --checkpoint-every: the state saved to `path` (atomically, WriteStateFile), the `keep` - 1 before it
/// moved to path.1 (the newest), path.2, ... first. `path` itself always holds a whole state.
Status WriteCheckpoint(const std::string& path, int keep, const sim::Solver& solver, const std::string& sceneName,
                       const interaction::PaddleSystem* paddles, double paddleClock, int64_t stepsBefore) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const std::string base = fs::is_symlink(fs::symlink_status(path, ec)) ? fs::weakly_canonical(path, ec).string() : path;
  if (keep > 1 && fs::is_regular_file(base, ec)) {
    for (int k = keep - 1; k >= 2; --k) {
      const std::string older = base + "." + std::to_string(k - 1);
      if (fs::exists(older, ec)) fs::rename(older, base + "." + std::to_string(k), ec);
    }
    // A second name for the current file, so that `path` is never missing while the next is written.
    const std::string previous = base + ".1";
    fs::remove(previous, ec);
    fs::create_hard_link(base, previous, ec);
    if (ec) fs::copy_file(base, previous, fs::copy_options::overwrite_existing, ec);
  }
  return WriteStateFile(path, solver, sceneName, paddles, paddleClock, stepsBefore);
}

/// An output directory: made when missing, but only in a directory that exists (a typo, or a path
/// under /, must not make a tree of directories, as root anywhere).
Status MakeOutputDirectory(const std::string& flag, const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return Status::Ok();
  if (fs::exists(dir, ec)) return Status::Error(flag + " " + dir + ": exists and is not a directory");
  fs::path normal = fs::path(dir).lexically_normal();
  if (!normal.has_filename()) normal = normal.parent_path();  // "out/"
  const fs::path parent = normal.parent_path();
  if (!parent.empty() && !fs::is_directory(parent, ec)) {
    return Status::Error(flag + " " + dir + ": " + parent.string() + " does not exist; make it first");
  }
  fs::create_directory(dir, ec);
  if (ec) return Status::Error(flag + " " + dir + ": cannot create the directory: " + ec.message());
  return Status::Ok();
}

/// How much of an earlier `--stats` file a run continued from a state saved at step `stepsBefore`
/// keeps: the bytes of the header and the rows up to that step, when it is a regular file with this
/// run's header, rows in step order and a row for that step (the first half's CSV); else -1, and the
/// file is written anew. `*dropped` counts the rows after that step (a second half run before).
int64_t StatsBytesToKeep(const std::string& path, const std::string& header, int64_t stepsBefore, int64_t* dropped) {
  *dropped = 0;
  std::error_code ec;
  if (stepsBefore <= 0 || !std::filesystem::is_regular_file(path, ec)) return -1;  // never read a pipe or device
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!in || !std::getline(in, line) || line != header || in.eof()) return -1;
  int64_t keep = static_cast<int64_t>(line.size()) + 1, at = keep;
  bool found = false;
  long long previous = 0;
  while (std::getline(in, line)) {
    const bool whole = !in.eof();  // ended by '\n' (a torn last row is not)
    char* end = nullptr;
    const long long step = std::strtoll(line.c_str(), &end, 10);
    if (end == line.c_str() || *end != ',' || step <= previous) return -1;  // not our rows, or not in order
    previous = step;
    at += static_cast<int64_t>(line.size()) + (whole ? 1 : 0);
    if (step <= stepsBefore) {
      if (!whole) return -1;
      keep = at;
      found = step == stepsBefore;
    } else {
      ++*dropped;
    }
  }
  return found ? keep : -1;
}

}  // namespace

std::string UsageText() {
  return "usage: sphxr [--xr | --desktop | --headless] [--scene FILE] [--time S | --steps N] [--settle S]\n"
         "             [--load-state FILE] [--save-state FILE [--checkpoint-every S [--checkpoint-keep N]]]\n"
         "             [--device auto|cpu|cuda|cpu-reference] [--threads T] [--spacing H] [--set KEY=VALUE]... [--export-every K --out DIR]\n"
         "             [--export-format ply|vtk] [--stats FILE.csv] [--validate] [--reuse on|off|PRESET]\n"
         "             [--export-surface-every K [--surface-format ply|obj]] [--progress | --no-progress]\n"
         "             [--screenshot FILE.png] [--frames DIR [--fps F]]\n"
         "             [--image-size WxH] [--render water|particles] [--quality auto|scene] [--gl-debug]\n"
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
         "                    (the window's default); scene: the scene's spacing (the headless default)\n"
         "  --scene FILE      JSON scene (default: " SPHXR_SCENES_DIR "/dam_break.json)\n"
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
         "  --gl-debug        OpenGL debug output on (as in debug builds): any GL error aborts, naming the call\n";
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
        if (first == arg) return Status::Error(arg + " is given twice: give it once");
        return Status::Error(first + " and " + arg + ": give one of them");
      }
      seen.push_back(group + " " + arg);
    }
    auto value = [&](const char** v) -> Status {
      if (i + 1 >= argc) return Status::Error(arg + ": missing value (see --help)");
      *v = argv[++i];
      return Status::Ok();
    };
    const char* v = nullptr;
    if (arg == "--help" || arg == "-h") {
      out->help = true;
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
        return Status::Error("--reuse " + r + ": must be on, off or a preset (" + sim::ReusePresetNames() + ")");
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
      if (Status s = ParseDouble(arg, v, 1e-9, 1e6, &out->time); !s) return s;
    } else if (arg == "--settle") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseDouble(arg, v, 0.0, 3600.0, &out->settle); !s) return s;
    } else if (arg == "--load-state" || arg == "--save-state") {
      if (Status s = value(&v); !s) return s;
      if (*v == '\0') return Status::Error(arg + ": give a file name");
      (arg == "--load-state" ? out->loadState : out->saveState) = v;
    } else if (arg == "--steps") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseInt(arg, v, 1, int64_t{1} << 40, &out->steps); !s) return s;
    } else if (arg == "--device") {
      if (Status s = value(&v); !s) return s;
      if (!sim::ParseDevice(v, &out->device)) return Status::Error(arg + " " + v + ": must be auto, cpu or cuda (or cpu-reference)");
    } else if (arg == "--threads") {
      if (Status s = value(&v); !s) return s;
      int64_t t;
      if (Status s = ParseInt(arg, v, 0, 1024, &t); !s) return s;
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
        return Status::Error(arg + " " + v + ": must be ply or vtk");
      }
    } else if (arg == "--export-surface-every") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseInt(arg, v, 1, int64_t{1} << 40, &out->exportSurfaceEvery); !s) return s;
    } else if (arg == "--surface-format") {
      if (Status s = value(&v); !s) return s;
      out->surfaceFormat = v;
      if (out->surfaceFormat != "ply" && out->surfaceFormat != "obj") {
        return Status::Error(arg + " " + v + ": must be ply or obj");
      }
    } else if (arg == "--screenshot") {
      if (Status s = value(&v); !s) return s;
      out->screenshotPath = v;
    } else if (arg == "--frames") {
      if (Status s = value(&v); !s) return s;
      out->framesDir = v;
    } else if (arg == "--fps") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseDouble(arg, v, 0.1, 1000.0, &out->fps); !s) return s;
    } else if (arg == "--image-size") {
      if (Status s = value(&v); !s) return s;
      int w = 0, h = 0;
      char tail = 0;
      if (std::sscanf(v, "%dx%d%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192) {
        return Status::Error(arg + " " + v + ": must be WIDTHxHEIGHT, each from 16 to 8192 (e.g. 1280x720)");
      }
      out->imageWidth = w;
      out->imageHeight = h;
    } else if (arg == "--window-size") {
      if (Status s = value(&v); !s) return s;
      int w = 0, h = 0;
      char tail = 0;
      if (std::sscanf(v, "%dx%d%c", &w, &h, &tail) != 2 || w < 64 || h < 64 || w > 8192 || h > 8192) {
        return Status::Error(arg + " " + v + ": must be WIDTHxHEIGHT, each from 64 to 8192 (e.g. 1280x720)");
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
      if (q != "auto" && q != "scene") return Status::Error("--quality " + q + ": must be auto or scene");
      out->quality = q == "auto" ? 1 : 0;
    } else if (arg == "--gl-debug") {
      out->glDebug = true;
    } else if (arg == "--no-vsync") {
      out->vsync = false;
    } else if (arg == "--render") {
      if (Status s = value(&v); !s) return s;
      const std::string r = v;
      if (r != "water" && r != "particles") return Status::Error("--render " + r + ": must be water or particles");
      out->particleImages = r == "particles";
    } else if (arg == "--checkpoint-every") {
      if (Status s = value(&v); !s) return s;
      if (Status s = ParseDouble(arg, v, 1e-6, 1e6, &out->checkpointEvery); !s) return s;
    } else if (arg == "--checkpoint-keep") {
      if (Status s = value(&v); !s) return s;
      int64_t n = 0;
      if (Status s = ParseInt(arg, v, 1, 100, &n); !s) return s;
      out->checkpointKeep = static_cast<int>(n);
    } else if (arg == "--stats") {
      if (Status s = value(&v); !s) return s;
      if (v[0] == '\0') return Status::Error("--stats: needs a file name");
      out->statsPath = v;
    } else {
      return Status::Error("unknown argument '" + arg + "' (see --help)");
    }
  }
  if (out->time > 0.0 && out->steps > 0) return Status::Error("--time and --steps: give one, not both");
  for (const std::string& set : out->sets) {
    if (out->spacing > 0.0f && set.rfind("spacing=", 0) == 0) {
      return Status::Error("--spacing and --set " + set.substr(0, 40) + ": give one of them");
    }
  }

  if (out->scenePath.empty()) out->scenePath = SPHXR_SCENES_DIR "/dam_break.json";
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
// --stats wiped a state file that took minutes to settle): refused before anything runs. A state saved
// over the one the run started from is allowed: it was read whole at the start, and is replaced
// atomically (a checkpoint carried forward).
Status CheckOutputsAreNotInputs(const Options& options, const SceneFile& scene) {
  std::vector<std::pair<std::string, std::string>> inputs = {{"the scene", options.scenePath}};
  if (!options.loadState.empty()) inputs.push_back({"--load-state", options.loadState});
  for (const std::string& t : scene.inputs) inputs.push_back({"the trajectory", t});
  const std::pair<const char*, std::string> outputs[] = {
      {"--stats", options.statsPath}, {"--save-state", options.saveState}, {"--screenshot", options.screenshotPath}};
  for (size_t k = 0; k < std::size(outputs); ++k) {
    const auto& [flag, path] = outputs[k];
    if (path.empty()) continue;
    for (const auto& [what, input] : inputs) {
      if (std::string(flag) == "--save-state" && what == "--load-state") continue;
      if (SameFile(path, input)) {
        return Status::Error(Format("%s %s is %s (%s): it would be overwritten; give another file", flag, path.c_str(),
                                    what.c_str(), input.c_str()));
      }
    }
    for (size_t j = 0; j < k; ++j) {
      if (!outputs[j].second.empty() && SameFile(path, outputs[j].second)) {
        return Status::Error(Format("%s %s is also %s's file: one would overwrite the other; give another file", flag,
                                    path.c_str(), outputs[j].first));
      }
    }
  }
  return Status::Ok();
}

}  // namespace

Status LoadSceneWithOptions(const Options& options, SceneFile* scene) {
  if (Status s = LoadScene(options.scenePath, scene); !s) return s;
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
  return Status::Ok();
}

Status RunHeadless(const Options& options, RunSummary* summary) {
  *summary = RunSummary{};
  SceneFile scene;
  if (Status s = LoadSceneWithOptions(options, &scene); !s) return s;
  // A state file is read before anything is allocated; it fixes the spacing (ReadStartState refuses a
  // --spacing that differs) and replaces the settle.
  if (options.checkpointEvery > 0.0 && options.saveState.empty()) {
    return Status::Error("--checkpoint-every: needs --save-state FILE (the checkpoints are that file)");
  }
  if (!options.loadState.empty() && options.settle > 0.0) {
    return Status::Error("--settle and --load-state: the state file is the start; settle in the run that saves it");
  }
  std::shared_ptr<const StateFile> state;
  if (Status s = ReadStartState(options.loadState, ExplicitSpacing(options), scene.name, &scene.setup, &state); !s) return s;
  {
    sim::SolverConfig probe;
    probe.device = options.device;
    probe.threads = options.threads;
    if (Status s = ApplyAutoQuality(options, options.quality == 1, state.get(), probe, &scene.setup); !s) return s;
  }

  double targetTime = options.time;
  int64_t targetSteps = options.steps;
  if (targetTime <= 0.0 && targetSteps <= 0) {
    targetTime = scene.runTime;
    targetSteps = scene.runSteps;
  }
  if (targetTime <= 0.0 && targetSteps <= 0) {
    return Status::Error(options.scenePath + ": the scene has no run.time or run.steps; give --time or --steps");
  }

  if (state && targetSteps <= 0 && state->clock.time >= targetTime - 1e-9) {
    return Status::Error(Format("--load-state %s: the state is at t = %.6g s, at or past the end time %g s (--time is "
                                "the end time on the state's clock)",
                                options.loadState.c_str(), state->clock.time, targetTime));
  }

  // Files are checked before the solver allocates anything, so a bad path costs nothing. The CSV is
  // opened without truncating it here: a run continued from a state file keeps the first half's rows
  // (below), and a run refused at start-up leaves the file as it was.
  std::ofstream stats;
  if (!options.statsPath.empty()) {
    const std::filesystem::path parent = std::filesystem::path(options.statsPath).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::is_directory(parent, ec)) {
      return Status::Error("--stats " + options.statsPath + ": " + parent.string() + " does not exist; make it first");
    }
    stats.open(options.statsPath, std::ios::app);
    if (!stats) return Status::Error("--stats " + options.statsPath + ": cannot open for writing");
  }
  // Files written after the run: check their places before it.
  if (Status s = CheckPlaceToWrite("--screenshot", options.screenshotPath, " (.png)"); !s) return s;
  if (Status s = CheckPlaceToWrite("--save-state", options.saveState, ""); !s) return s;
  if (options.outDir != Options{}.outDir && options.exportEvery <= 0 && options.exportSurfaceEvery <= 0) {
    SPHXR_LOG_WARN("--out %s: nothing is exported without --export-every or --export-surface-every",
                   options.outDir.c_str());
  }
  if (options.exportEvery > 0 || options.exportSurfaceEvery > 0) {
    if (Status s = MakeOutputDirectory("--out", options.outDir); !s) return s;
  }
  // Pictures: the GL context is made before the run, so a machine without EGL fails in a second.
  std::unique_ptr<OfflinePictures> pictures;
  if (!options.screenshotPath.empty() || !options.framesDir.empty()) {
    if (!options.framesDir.empty()) {
      if (Status s = MakeOutputDirectory("--frames", options.framesDir); !s) return s;
    }
    if (Status s = OfflinePictures::Create(options.imageWidth, options.imageHeight, &pictures, options.glDebug); !s) {
      return Status::Error("--screenshot/--frames: " + s.message());
    }
  }
  const render::RenderMode pictureMode = options.particleImages ? render::RenderMode::kParticles : render::RenderMode::kWater;

  // Paddles (scene "paddles" section): sampled at the final spacing, added to the scene as moving bodies.
  std::unique_ptr<interaction::PaddleSystem> paddles;
  if (!scene.paddles.empty()) {
    if (Status s = interaction::PaddleSystem::Create(scene.paddles, scene.setup, &paddles); !s) {
      return Status::Error(options.scenePath + ": " + s.message());
    }
    paddles->AddBodies(&scene.setup);
  }

  sim::SolverConfig config;
  config.device = options.device;
  config.threads = options.threads;
  config.validate = options.validate;
  std::unique_ptr<sim::Solver> solver;
  if (Status s = sim::Solver::Create(scene.setup, config, &solver); !s) return Status::Error(options.scenePath + ": " + s.message());

  int64_t savedStep = 0;  // the state file's step count (-1: unknown, and saved as unknown again)
  if (state) {
    if (Status s = RestoreState(*state, solver.get()); !s) return Status::Error("--load-state " + s.message());
    SPHXR_LOG_INFO("started from %s: t = %.6g s, step %s, %d fluid particles (saved from '%s')",
                   options.loadState.c_str(), state->clock.time,
                   state->step < 0 ? "unknown" : std::to_string(state->step).c_str(), state->fluidCount,
                   state->scene.c_str());
    if (state->step < 0) {
      SPHXR_LOG_INFO("%s has no step count (a version-1 file, or continued from one): steps, exports and CSV rows "
                     "are numbered from 0 again, and a state saved from this run has no count either",
                     options.loadState.c_str());
    }
    savedStep = state->step;
    summary->stepsBefore = std::max<int64_t>(savedStep, 0);
  }
  // Steps count on from the state's (the whole run's numbering): the CSV's step column, the export files'
  // numbers and the state saved at the end.
  const int64_t stepsBefore = summary->stepsBefore;
  double paddleClock = solver->Time();  // paddles: display frames at paddleFrameRate get new targets
  if (paddles) {
    if (Status s = paddles->Attach(solver.get()); !s) return s;
    summary->paddles = paddles->Count();
    for (int k = 0; k < paddles->Count(); ++k) summary->paddleParticles += paddles->ParticleCount(k);
    if (state) RestorePaddles(*state, *solver, paddles.get(), &paddleClock);
  }
  state.reset();  // the solver and the paddles have it now

  summary->startTime = solver->Time();
  const float spacing = scene.setup.params.spacing;
  summary->fluid = solver->FluidCount();
  summary->boundary = solver->BoundaryCount();
  SPHXR_LOG_INFO("%s: %d fluid + %d boundary particles, spacing %g m, device %s, sound speed %.3g m/s",
                 scene.name.empty() ? options.scenePath.c_str() : scene.name.c_str(), summary->fluid,
                 summary->boundary, spacing, sim::DeviceName(solver->ActiveDevice()), solver->SoundSpeed());
  if (summary->fluid == 0) {
    SPHXR_LOG_WARN("the scene has no fluid particles (no fluid block, or every block too thin or filled by "
                   "obstacles at spacing %g m): only the walls and paddles run", spacing);
  }

  const bool probeEveryStep = scene.damBreak.has_value() && stats.is_open();
  const bool dfsph = solver->Method() == sim::SolverMethod::kDfsph;
  if (stats.is_open()) {
    std::string header = "step,time,dt,max_speed,mean_density_error,max_density_error,clamped,active_fraction";
    if (probeEveryStep) header += ",front_Z,height_H";
    if (dfsph) header += ",density_iterations,divergence_iterations,solver_density_error,solver_divergence_error";
    if (paddles) {
      header += ",pushed_out";
      for (int k = 0; k < paddles->Count(); ++k) header += Format(",paddle%d_fx,paddle%d_fy,paddle%d_fz,paddle%d_haptic", k, k, k, k);
    }
    // A continued run appends to the first half's CSV: the whole run's rows in one file. The first half's
    // rows are never rewritten: later rows (of an earlier continuation) are cut off, then rows appended.
    // A pipe or device is written as it was opened (never read back, never reopened).
    int64_t dropped = 0;
    const int64_t keep = StatsBytesToKeep(options.statsPath, header, stepsBefore, &dropped);
    std::error_code ec;
    if (keep >= 0) {
      stats.close();
      if (dropped > 0) std::filesystem::resize_file(options.statsPath, static_cast<uintmax_t>(keep), ec);
      if (!ec) stats.open(options.statsPath, std::ios::app);
      if (ec || !stats) return Status::Error("--stats " + options.statsPath + ": cannot continue the file: " + ec.message());
      SPHXR_LOG_INFO("--stats %s: the rows continue the earlier run's (its steps up to %lld kept%s)",
                     options.statsPath.c_str(), static_cast<long long>(stepsBefore),
                     dropped > 0 ? Format(", %lld rows after it replaced", static_cast<long long>(dropped)).c_str() : "");
    } else {
      if (std::filesystem::is_regular_file(options.statsPath, ec)) {
        stats.close();
        stats.open(options.statsPath, std::ios::trunc);
        if (!stats) return Status::Error("--stats " + options.statsPath + ": cannot open for writing");
      }
      stats << header << "\n";
    }
    stats.flush();
  }
  CsvRows rows(&stats);

  const bool showProgress = options.progress == 1 || (options.progress == -1 && isatty(STDERR_FILENO));
  const bool progressLines = options.progress == -1 && !showProgress;  // a log file: a line a minute
  // Ctrl-C/SIGTERM from here on stop the settling or the run after the step in progress.
  InterruptScope interruptScope;
  const double settle = options.loadState.empty() ? (options.settle >= 0.0 ? options.settle : scene.runSettle) : 0.0;
  if (!options.loadState.empty() && scene.runSettle > 0.0) {
    SPHXR_LOG_INFO("run.settle (%g s) skipped: the state file is the start", scene.runSettle);
  }
  if (settle > 0.0) {
    SPHXR_LOG_INFO("settling: %g simulated s of energy minimisation (FIRE) before t = 0", settle);
    Progress bar(showProgress, "settling ", progressLines);
    const auto t0 = std::chrono::steady_clock::now();
    auto update = [&](double done) {
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const int64_t steps = solver->GetTotals().steps;
      bar.Update(done / settle, done, steps, steps > 0 ? 1e3 * wall / static_cast<double>(steps) : 0.0);
      return !g_interrupt;
    };
    if (Status s = solver->Settle(settle, &summary->settle, update); !s) return Status::Error("--settle: " + s.message());
    bar.Finish();
    if (summary->settle.stopped) {
      SPHXR_LOG_WARN("settle stopped early at %.4g of %g s (%lld steps): the water is not settled", summary->settle.time,
                     settle, static_cast<long long>(summary->settle.steps));
    } else {
      SPHXR_LOG_INFO("settled: %.4g s in %lld steps (%.1f s wall); largest |a| at the end %.3g m/s^2; the run starts here",
                     summary->settle.time, static_cast<long long>(summary->settle.steps), summary->settle.wallSeconds,
                     summary->settle.maxAccel);
    }
  }
  Progress progress(showProgress, "", progressLines);
  sim::HostFluid host;
  auto exportNow = [&](int64_t step) -> Status {
    solver->Download(&host);
    char name[64];
    std::snprintf(name, sizeof(name), "particles_%06lld.%s", static_cast<long long>(step), options.exportFormat.c_str());
    const std::string path = (std::filesystem::path(options.outDir) / name).string();
    Status s = options.exportFormat == "vtk" ? WriteVtk(path, host) : WritePly(path, host);
    if (s) ++summary->exports;
    return s;
  };
  // The start is exported when its step is one of the exports' (a fresh run's step 0): a continued
  // run then writes the files the whole run writes.
  if (options.exportEvery > 0 && stepsBefore % options.exportEvery == 0) {
    if (Status s = exportNow(stepsBefore); !s) return s;
  }
  sim::SurfaceMesh surfaceMesh;
  double surfaceSeconds = 0.0;
  auto exportSurface = [&](int64_t step) -> Status {
    const auto t0 = std::chrono::steady_clock::now();
    sim::SurfaceStats stats;
    if (Status s = solver->ExtractSurface(scene.surface.value_or(sim::SurfaceParams{}), &surfaceMesh, &stats); !s) {
      return Status::Error(options.scenePath + ": " + s.message());
    }
    surfaceSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    char name[64];
    std::snprintf(name, sizeof(name), "surface_%06lld.%s", static_cast<long long>(step), options.surfaceFormat.c_str());
    const std::string path = (std::filesystem::path(options.outDir) / name).string();
    Status s = options.surfaceFormat == "obj" ? WriteSurfaceObj(path, surfaceMesh) : WriteSurfacePly(path, surfaceMesh);
    if (s) {
      ++summary->surfaceExports;
      summary->surfaceTriangles = surfaceMesh.TriangleCount();
    }
    return s;
  };
  if (options.exportSurfaceEvery > 0 && stepsBefore % options.exportSurfaceEvery == 0) {
    if (Status s = exportSurface(stepsBefore); !s) return s;
  }

  // Frame k shows the state after the first step at or past t = k / fps. A run from a state file goes on
  // with the first frame after the state's time (the earlier run drew those up to it), so continued
  // runs number and draw their frames as the whole run does.
  int64_t frameIndex = 0;
  if (summary->startTime > 0.0) {
    frameIndex = static_cast<int64_t>(std::floor(summary->startTime * options.fps));
    while (static_cast<double>(frameIndex) / options.fps - 1e-9 <= summary->startTime) ++frameIndex;
  }
  const int64_t firstFrame = frameIndex;
  // A picture is drawn from a snapshot, as in the window: in water mode from the extracted surface mesh
  // (the scene's "surface" section), with the paddles at their poses.
  SimSnapshot pictureSnap;
  auto picture = [&](const std::string& path) -> Status {
    SurfaceRequest surface;
    surface.enabled = pictureMode == render::RenderMode::kWater;
    surface.params = scene.surface.value_or(sim::SurfaceParams{});
    if (Status s = CaptureSnapshot(*solver, paddles.get(), surface, &pictureSnap); !s) return Status::Error("picture: " + s.message());
    pictureSnap.setup = scene.setup;
    return pictures->Write(MakeFrameScene(pictureSnap, pictureMode), path);
  };
  auto frameNow = [&]() -> Status {
    if (options.framesDir.empty()) return Status::Ok();
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%05lld.png", static_cast<long long>(frameIndex));
    const std::string path = (std::filesystem::path(options.framesDir) / name).string();
    if (Status s = picture(path); !s) return s;
    ++summary->frames;
    ++frameIndex;
    return Status::Ok();
  };
  auto frameDue = [&]() {
    return !options.framesDir.empty() && solver->Time() >= static_cast<double>(frameIndex) / options.fps - 1e-9;
  };
  while (frameDue()) {
    if (Status s = frameNow(); !s) return s;
  }

  double activeSum = 0.0;
  double forceSum = 0.0;
  double nextFrame = paddleClock;  // paddles: the next display frame (a state file's, or now)
  // Checkpoints at whole multiples of the interval on the simulated clock (a continued run keeps the grid).
  double nextCheckpoint = options.checkpointEvery > 0.0
                              ? (std::floor(solver->Time() / options.checkpointEvery + 1e-9) + 1.0) * options.checkpointEvery
                              : 0.0;
  const auto begin = std::chrono::steady_clock::now();
  while (targetSteps > 0 ? solver->GetTotals().steps < targetSteps : solver->Time() < targetTime - 1e-9) {
    if (g_interrupt) break;
    if (paddles && solver->Time() >= nextFrame - 1e-9) {
      nextFrame += 1.0 / scene.paddleFrameRate;
      if (Status s = paddles->BeginFrame(nextFrame); !s) return s;
    }
    if (Status s = solver->Step(); !s) {
      // --validate names the step by the solver's count, this run's; after a state file, say which step
      // of the whole run (the CSV's numbering) that is.
      if (stepsBefore == 0 || s.message().rfind("validate:", 0) != 0) return s;
      return Status::Error(Format("%s (counted in this run; step %lld of the whole run, as the CSV numbers it)",
                                  s.message().c_str(),
                                  static_cast<long long>(stepsBefore + solver->GetTotals().steps + 1)));
    }
    if (paddles) {
      paddles->AfterStep();
      for (int k = 0; k < paddles->Count(); ++k) {
        forceSum += sim::Length(paddles->State(k).force);
        summary->paddlePeakHaptic = std::max(summary->paddlePeakHaptic, paddles->State(k).haptic);
      }
    }
    const sim::StepInfo& info = solver->LastStep();
    const int64_t step = solver->GetTotals().steps;  // this run's
    const int64_t wholeStep = stepsBefore + step;    // the whole run's (files and CSV rows)
    summary->peakMeanDensityError = std::max(summary->peakMeanDensityError, info.meanDensityError);
    summary->maxSpeed = std::max(summary->maxSpeed, info.maxSpeed);
    activeSum += info.activeFraction;
    if (!std::isfinite(info.maxSpeed)) {
      return Status::Error(Format("the simulation became non-finite at step %lld (t = %.4g s); rerun with --validate "
                                  "to find the stage and particle, and lower solver.fixed_dt or raise solver.stiffness",
                                  static_cast<long long>(wholeStep), info.time));
    }
    if (stats.is_open()) {
      std::ostringstream row;
      row << wholeStep << ',' << info.time << ',' << info.dt << ',' << info.maxSpeed << ',' << info.meanDensityError << ','
          << info.maxDensityError << ',' << info.clamped << ',' << info.activeFraction;
      if (probeEveryStep) {
        solver->Download(&host);
        const DamBreakMeasure m = MeasureDamBreak(*scene.damBreak, host, spacing);
        row << ',' << m.front << ',' << m.height;
      }
      if (dfsph) {
        row << ',' << info.densityIterations << ',' << info.divergenceIterations << ',' << info.solverDensityError << ','
            << info.solverDivergenceError;
      }
      if (paddles) {
        row << ',' << info.pushedOut;
        for (int k = 0; k < paddles->Count(); ++k) {
          const interaction::PaddleState& p = paddles->State(k);
          row << ',' << p.force.x << ',' << p.force.y << ',' << p.force.z << ',' << p.haptic;
        }
      }
      row << '\n';
      rows.Add(row.str());
      if (rows.Due() && !rows.Flush()) {
        return Status::Error("--stats " + options.statsPath + ": write failed (disk full?) at step " + std::to_string(wholeStep));
      }
    }
    if (options.checkpointEvery > 0.0 && solver->Time() >= nextCheckpoint - 1e-9) {
      // The CSV first: a run continued from this checkpoint keeps the rows up to its step.
      if (!rows.Flush()) return Status::Error("--stats " + options.statsPath + ": write failed (disk full?)");
      if (Status s = WriteCheckpoint(options.saveState, options.checkpointKeep, *solver, scene.name, paddles.get(),
                                     nextFrame, savedStep);
          !s) {
        return Status::Error("--checkpoint-every: " + s.message());
      }
      ++summary->checkpoints;
      summary->checkpointTime = solver->Time();
      nextCheckpoint = (std::floor(solver->Time() / options.checkpointEvery + 1e-9) + 1.0) * options.checkpointEvery;
    }
    if (options.exportEvery > 0 && wholeStep % options.exportEvery == 0) {
      if (Status s = exportNow(wholeStep); !s) return s;
    }
    if (options.exportSurfaceEvery > 0 && wholeStep % options.exportSurfaceEvery == 0) {
      if (Status s = exportSurface(wholeStep); !s) return s;
    }
    while (frameDue()) {
      if (Status s = frameNow(); !s) return s;
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    const double fraction = targetSteps > 0 ? static_cast<double>(step) / targetSteps
                                            : (solver->Time() - summary->startTime) / (targetTime - summary->startTime);
    progress.Update(std::min(1.0, fraction), solver->Time(), wholeStep, 1e3 * wall / step);
  }
  summary->wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  summary->interrupted = g_interrupt;  // also a signal during the last step
  if (summary->interrupted) {
    const int64_t step = stepsBefore + solver->GetTotals().steps;
    progress.Finish();
    SPHXR_LOG_WARN("%s at step %lld (t = %.4f s): stopping; the summary and the files cover the run so far",
                   summary->interrupted == SIGINT    ? "interrupted (SIGINT)"
                   : summary->interrupted == SIGHUP ? "hung up (SIGHUP: the terminal closed)"
                                                    : "terminated (SIGTERM)",
                   static_cast<long long>(step), solver->Time());
    // The state reached is not lost: one more export at this step unless it was just written.
    if (options.exportEvery > 0 && step % options.exportEvery != 0) {
      if (Status s = exportNow(step); !s) return s;
    }
    if (options.exportSurfaceEvery > 0 && step % options.exportSurfaceEvery != 0) {
      if (Status s = exportSurface(step); !s) return s;
    }
  }
  // The rows of a run stopped by a signal too; a failed save is reported after the summary (which covers
  // the run), not instead of it.
  Status saveStatus;
  if (!rows.Flush()) return Status::Error("--stats " + options.statsPath + ": write failed (disk full?)");
  if (!options.saveState.empty()) {
    saveStatus = WriteStateFile(options.saveState, *solver, scene.name, paddles.get(), nextFrame, savedStep);
  }
  if (!saveStatus) {
    saveStatus = Status::Error("--save-state " + saveStatus.message() +
                               (summary->checkpoints > 0 ? Format(" (the last checkpoint, t = %.6g s, is there)",
                                                                 summary->checkpointTime)
                                                         : ""));
  } else if (!options.saveState.empty()) {
    summary->stateSaved = options.saveState;
    // The file does not record how it was made: a run from it skips the scene's settle as if it were done.
    if (summary->settle.stopped) {
      SPHXR_LOG_WARN("%s holds water whose settle was stopped at %.4g of %g s: a run from it starts from water that is "
                     "not at rest (settle again without --load-state to have a settled start)",
                     options.saveState.c_str(), summary->settle.time, settle);
    }
  }
  if (stats.is_open()) {
    stats.close();  // the last rows leave the buffer here
    if (stats.fail()) return Status::Error("--stats " + options.statsPath + ": write failed (disk full?)");
  }

  const sim::Totals& totals = solver->GetTotals();
  summary->steps = totals.steps;
  summary->simulatedTime = solver->Time();
  summary->msPerStep = totals.steps > 0 ? 1e3 * totals.stepSeconds / totals.steps : 0.0;
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) {
    summary->stageMsPerStep[s] = totals.steps > 0 ? 1e3 * totals.stageSeconds[s] / totals.steps : 0.0;
  }
  summary->meanDensityError = solver->LastStep().meanDensityError;
  summary->maxDensityError = solver->LastStep().maxDensityError;
  summary->clampedEvents = totals.clampedEvents;
  if (totals.particleSteps > 0) {
    summary->clampsPerThousand = 1e3 * static_cast<double>(totals.clampedEvents) / static_cast<double>(totals.particleSteps);
  }
  if (totals.clampedEvents > 0) {
    const auto most = std::max_element(totals.clampedAt.begin(), totals.clampedAt.end());
    summary->clampedMost = sim::ClampSiteName(static_cast<int>(most - totals.clampedAt.begin()));
  }
  summary->pushedOut = totals.pushedOutEvents;
  if (paddles && totals.steps > 0) summary->paddleMeanForce = forceSum / static_cast<double>(totals.steps * paddles->Count());
  summary->meanActiveFraction = totals.steps > 0 ? activeSum / static_cast<double>(totals.steps) : 1.0;
  solver->Download(&host);
  summary->lost = summary->fluid - static_cast<int64_t>(host.size());
  if (scene.damBreak) {
    const DamBreakMeasure m = MeasureDamBreak(*scene.damBreak, host, spacing);
    summary->surgeFront = m.front;
    summary->columnHeight = m.height;
  }

  std::string movie;
  if (summary->frames > 0) {
    const std::string ffmpeg = FindOnPath("ffmpeg");
    if (ffmpeg.empty()) {
      SPHXR_LOG_INFO("ffmpeg is not on the PATH: the frames stay a PNG sequence");
    } else {
      movie = (std::filesystem::path(options.framesDir) / "movie.mp4").string();
      // From the earliest frame of the unbroken sequence ending in this run's: a run continued into its
      // first run's directory makes the whole run's movie.
      int64_t movieStart = firstFrame;
      while (movieStart > 0) {
        char name[64];
        std::snprintf(name, sizeof(name), "frame_%05lld.png", static_cast<long long>(movieStart - 1));
        std::error_code ec;
        if (!std::filesystem::is_regular_file(std::filesystem::path(options.framesDir) / name, ec)) break;
        --movieStart;
      }
      // ... and ending at this run's last frame (not at older, higher-numbered files in the directory).
      const std::string command = Format("'%s' -y -loglevel error -framerate %g -start_number %lld -i '%s/frame_%%05d.png' "
                                         "-frames:v %lld -pix_fmt yuv420p -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' '%s'",
                                         ffmpeg.c_str(), options.fps, static_cast<long long>(movieStart),
                                         options.framesDir.c_str(), static_cast<long long>(frameIndex - movieStart),
                                         movie.c_str());
      if (std::system(command.c_str()) != 0) {
        SPHXR_LOG_WARN("ffmpeg could not make %s; the PNG frames are there", movie.c_str());
        movie.clear();
      }
    }
  }
  if (pictures && !options.screenshotPath.empty()) {
    if (Status s = picture(options.screenshotPath); !s) return s;
  }

  std::printf("sphxr summary: %s\n", scene.name.empty() ? options.scenePath.c_str() : scene.name.c_str());
  std::printf("  particles       %d fluid, %d boundary\n", summary->fluid, summary->boundary);
  std::printf("  device          %s\n", sim::DeviceName(solver->ActiveDevice()));
  std::printf("  steps           %lld (%lld with dt clamped to the stability limit)%s\n",
              static_cast<long long>(summary->steps), static_cast<long long>(totals.dtClampedSteps),
              summary->stepsBefore > 0 && summary->steps > 0 ? Format("; steps %lld to %lld of the whole run",
                                                static_cast<long long>(summary->stepsBefore + 1),
                                                static_cast<long long>(summary->stepsBefore + summary->steps))
                                             .c_str()
                                       : "");
  const double ran = summary->simulatedTime - summary->startTime;
  if (summary->startTime > 0.0) {
    std::printf("  simulated time  %.4f s to %.4f s (from the state file) in %.2f s wall (%.3f simulated s per wall s)\n",
                summary->startTime, summary->simulatedTime, summary->wallSeconds,
                summary->wallSeconds > 0 ? ran / summary->wallSeconds : 0.0);
  } else {
    std::printf("  simulated time  %.4f s in %.2f s wall (%.3f simulated s per wall s)\n", summary->simulatedTime,
                summary->wallSeconds, summary->wallSeconds > 0 ? ran / summary->wallSeconds : 0.0);
  }
  std::printf("  ms per step     %.3f total:", summary->msPerStep);
  for (int s = 0; s < static_cast<int>(sim::Stage::kCount); ++s) {
    std::printf(" %s %.3f", sim::StageName(static_cast<sim::Stage>(s)), summary->stageMsPerStep[s]);
  }
  std::printf("\n");
  std::printf("  density error   mean compression %.3f %% (peak over run %.3f %%); largest |rho/rho0 - 1| %.3f %% at the "
              "end (spray and surface particles are light)\n",
              100.0 * summary->meanDensityError, 100.0 * summary->peakMeanDensityError, 100.0 * summary->maxDensityError);
  std::printf("  max speed       %.3f m/s over the run\n", summary->maxSpeed);
  if (scene.setup.reuse.enabled) {
    std::printf("  reuse           on: %.1f %% of the particles computed per step on average (delta1 %g, delta2 %g, "
                "threshold %g, idle %d)\n",
                100.0 * summary->meanActiveFraction, scene.setup.reuse.delta1, scene.setup.reuse.delta2,
                scene.setup.reuse.threshold, scene.setup.reuse.idle);
  }
  if (summary->settle.steps > 0) {
    std::printf("  settled         %.4g s of energy minimisation before t = 0%s (%lld steps, %.2f s wall; largest |a| "
                "at the end %.3g m/s^2)\n",
                summary->settle.time, summary->settle.stopped ? ", stopped early" : "",
                static_cast<long long>(summary->settle.steps), summary->settle.wallSeconds, summary->settle.maxAccel);
  }
  if (summary->interrupted) {
    std::printf("  interrupted     by %s at t = %.4f s of the %s asked for\n",
                summary->interrupted == SIGINT ? "SIGINT" : summary->interrupted == SIGHUP ? "SIGHUP" : "SIGTERM",
                summary->simulatedTime,
                targetSteps > 0 ? Format("%lld steps", static_cast<long long>(targetSteps)).c_str()
                                : Format("%.4g s", targetTime).c_str());
  }
  std::printf("  particles lost  %lld (clamped back into the tank: %lld times, %.3g per 1,000 particle-steps%s%s)\n",
              static_cast<long long>(summary->lost), static_cast<long long>(summary->clampedEvents),
              summary->clampsPerThousand, summary->clampedMost.empty() ? "" : ", most at the ",
              summary->clampedMost.c_str());
  if (scene.damBreak) {
    std::printf("  dam break       surge front Z = %.3f, column height H = %.3f (Martin & Moyce units)\n",
                summary->surgeFront, summary->columnHeight);
  }
  if (paddles) {
    for (int k = 0; k < paddles->Count(); ++k) {
      const interaction::PaddleDesc& d = paddles->Desc(k);
      const interaction::PaddleState& p = paddles->State(k);
      std::printf("  paddle          %s (%s): %d boundary particles, %s, filtered force [%.3g %.3g %.3g] N at the end, "
                  "%lld teleport(s)\n",
                  d.name.c_str(), interaction::HolderName(d.holder), paddles->ParticleCount(k),
                  interaction::PaddleModeName(p.mode), p.force.x, p.force.y, p.force.z, static_cast<long long>(p.teleports));
    }
    std::printf("  paddles         mean filtered |force| %.3f N, peak haptic amplitude %.2f, fluid pushed out of a paddle "
                "%lld times\n",
                summary->paddleMeanForce, summary->paddlePeakHaptic, static_cast<long long>(summary->pushedOut));
  }
  if (summary->surfaceExports > 0) {
    summary->surfaceMs = 1e3 * surfaceSeconds / static_cast<double>(summary->surfaceExports);
    std::printf("  surface         %lld meshes to %s, %.2f ms per extraction; the last %lld triangles\n",
                static_cast<long long>(summary->surfaceExports), options.outDir.c_str(), summary->surfaceMs,
                static_cast<long long>(summary->surfaceTriangles));
  }
  if (summary->frames > 0) {
    std::printf("  frames          %lld PNG files in %s%s%s\n", static_cast<long long>(summary->frames),
                options.framesDir.c_str(), movie.empty() ? "" : ", movie ", movie.c_str());
  }
  if (pictures && !options.screenshotPath.empty()) {
    std::printf("  picture         %s (%dx%d)\n", options.screenshotPath.c_str(), options.imageWidth, options.imageHeight);
  }
  if (summary->exports > 0) {
    std::printf("  exported        %lld files to %s\n", static_cast<long long>(summary->exports), options.outDir.c_str());
  }
  if (summary->checkpoints > 0) {
    std::printf("  checkpoints     %lld, the last at t = %.6g s in %s%s\n", static_cast<long long>(summary->checkpoints),
                summary->checkpointTime, options.saveState.c_str(),
                summary->stateSaved.empty() ? "" : " (then replaced by the state at the end; older ones: .1, .2, ...)");
  }
  if (!summary->stateSaved.empty()) {
    std::printf("  state           saved to %s at t = %.6g s (sphxr --load-state %s continues from there)\n",
                summary->stateSaved.c_str(), summary->simulatedTime, summary->stateSaved.c_str());
  }
  return saveStatus;
}

}  // namespace sphxr::app
