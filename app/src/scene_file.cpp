#include "sphxr/app/scene_file.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "scene_reader.h"
#include "sphxr/app/param_registry.h"
#include "sphxr/common/log.h"
#include "sphxr/common/text_file.h"
#include "sphxr/sim/solver.h"
#include "sphxr/sim/solver_table.h"
#include "scene_probes.h"

namespace sphxr::app {
namespace scene {

Status Reader::Parse(const json& root) {
  if (!root.is_object()) return Error("(root)", "a scene must be a JSON object");
  CheckKeys(root, "", {"name", "description", "solver", "gravity", "tank", "fluid", "obstacles", "run", "probe", "reuse",
                       "paddles", "surface", "probes"});
  if (root.contains("name")) {
    if (!root["name"].is_string()) return Error("name", "must be a string");
    m_out->name = root["name"].get<std::string>();
    if (!Printable(m_out->name)) {
      return Error("name", ShowText(m_out->name) + ": has control, format or line-separator characters (terminal "
                           "escapes?): use plain text");
    }
  }
  if (root.contains("description") && root["description"].is_string()) {
    m_out->description = root["description"].get<std::string>();
  }
  if (root.contains("solver")) {
    if (Status st = Solver(root); !st) return st;
  }
  if (root.contains("gravity")) {
    if (Status st = Vec(root["gravity"], "gravity", &m_out->setup.gravity); !st) return st;
  }
  if (Status st = Tank(root); !st) return st;
  if (root.contains("fluid")) {
    if (Status st = Fluid(root); !st) return st;
  }
  if (root.contains("obstacles")) {
    if (Status st = Obstacles(root); !st) return st;
  }
  if (root.contains("reuse")) {
    if (Status st = Reuse(root); !st) return st;
  }
  if (root.contains("paddles")) {
    if (Status st = Paddles(root["paddles"]); !st) return st;
  }
  if (root.contains("probes")) {  // after the tank and the paddles, which its probes name
    ProbeConfig probes;
    const auto unknown = [this](const std::string& key) { Unknown(key); };
    if (Status st = ParseProbes(root["probes"], m_out->path, m_out->setup, m_out->paddles, unknown, &probes); !st) return st;
    m_out->probes = std::move(probes);
  }
  if (root.contains("surface")) {
    if (Status st = Surface(root); !st) return st;
  }
  if (root.contains("run")) {
    if (Status st = Run(root); !st) return st;
  }
  if (root.contains("probe")) {
    if (Status st = Probe(root); !st) return st;
  }
  return Status::Ok();
}

Status Reader::Solver(const json& root) {
  sim::SceneSetup& s = m_out->setup;
  const json& solver = root["solver"];
  if (!solver.is_object()) return Error("solver", "must be an object");
  for (auto it = solver.begin(); it != solver.end(); ++it) {
    if (it.key() == "method") {  // the pressure solver, by name (docs/user/scenes.md)
      const std::string v = it.value().is_string() ? it.value().get<std::string>() : "";
      if (!sim::ParseSolverMethod(v, &s.method)) return Error("solver.method", "must be one of " + sim::SolverNames());
      continue;
    }
    if (it.key() == "density") {  // how WCSPH finds the density, by name (docs/dev/physics.md)
      const std::string v = it.value().is_string() ? it.value().get<std::string>() : "";
      if (!sim::ParseDensityModel(v, &s.density)) return Error("solver.density", "must be \"summation\" or \"delta_sph\"");
      continue;
    }
    const ParamDesc* desc = FindParam("solver." + it.key());
    if (!desc) {
      Unknown("solver." + Shown(it.key()));
      continue;
    }
    double v;
    if (Status st = Number(it.value(), "solver." + it.key(), &v); !st) return st;
    if (Status st = SetParam(*desc, v, m_out->path + ": " + desc->key, &s); !st) return st;
  }
  return Status::Ok();
}

Status Reader::Reuse(const json& root) {
  sim::SceneSetup& s = m_out->setup;
  // A reuse section turns reuse on unless it says "enabled": false.
  const json& reuse = root["reuse"];
  if (!reuse.is_object()) return Error("reuse", "must be an object");
  CheckKeys(reuse, "reuse",
            {"enabled", "preset", "delta1", "delta2", "threshold", "idle", "pressure_scale", "cell_count",
             "accel_tolerance", "impulse"});  // the last two retired: warned about below
  for (const char* retired : {"impulse", "accel_tolerance"}) {
    if (!reuse.contains(retired)) continue;
    const std::string why = std::string("retired key 'reuse.") + retired +
                            "' ignored: the impulse hold is the only hold (docs/design/impulse_hold.md)";
    m_out->warnings.push_back(why);
    SPHXR_LOG_WARN("%s: %s", m_out->path.c_str(), why.c_str());
  }
  sim::ReuseParams& r = s.reuse;
  r.enabled = true;
  // A preset first, then any parameter the section names overrides it.
  if (reuse.contains("preset")) {
    const json& preset = reuse["preset"];
    if (!preset.is_string() || !sim::ApplyReusePreset(preset.get<std::string>(), &r)) {
      return Error("reuse.preset", std::string("must be one of ") + sim::ReusePresetNames());
    }
  }
  if (reuse.contains("enabled")) {
    if (!reuse["enabled"].is_boolean()) return Error("reuse.enabled", "must be true or false");
    r.enabled = reuse["enabled"].get<bool>();
  }
  for (const ParamDesc& p : ParamRegistry()) {  // the one description of each parameter
    if (p.group != "reuse" || !reuse.contains(p.name)) continue;
    double v;
    if (Status st = Number(reuse[p.name], p.key, &v); !st) return st;
    if (Status st = SetParam(p, v, m_out->path + ": " + p.key, &s); !st) return st;
  }
  return Status::Ok();
}

Status Reader::Surface(const json& root) {
  // The water surface (docs/dev/surface.md): sim::SurfaceParams; absent keys keep their defaults.
  const json& surface = root["surface"];
  if (!surface.is_object()) return Error("surface", "must be an object");
  CheckKeys(surface, "surface", {"cell_size", "iso_level", "margin"});
  sim::SurfaceParams p;
  const struct {
    const char* key;
    float* member;
    double lo, hi;
    bool loOpen;
    const char* why;
  } numbers[] = {{"cell_size", &p.cellSize, 0, 100, false, "must be from 0 (the particle spacing) to 100 m"},
                 {"iso_level", &p.isoLevel, 0, 10, true, "must be above 0 and below 10 (volume fraction; 0.5 is the surface)"},
                 {"margin", &p.margin, 0, 100, false, "must be from 0 to 100 m"}};
  for (const auto& n : numbers) {
    if (!surface.contains(n.key)) continue;
    double v;
    if (Status st = Number(surface[n.key], std::string("surface.") + n.key, &v); !st) return st;
    if (v > n.hi || v < n.lo || (n.loOpen && v <= n.lo) || (std::string(n.key) == "iso_level" && v >= n.hi)) {
      return Error(std::string("surface.") + n.key, Format("%g: %s", v, n.why));
    }
    *n.member = static_cast<float>(v);
  }
  m_out->surface = p;
  return Status::Ok();
}

Status Reader::Run(const json& root) {
  const json& run = root["run"];
  if (!run.is_object()) return Error("run", "must be an object");
  CheckKeys(run, "run", {"time", "steps", "settle"});
  if (run.contains("time")) {
    if (Status st = Number(run["time"], "run.time", &m_out->runTime); !st) return st;
    if (m_out->runTime <= 0) return Error("run.time", "must be positive");
  }
  if (run.contains("steps")) {
    if (!run["steps"].is_number_integer() || run["steps"].get<int64_t>() <= 0) {
      return Error("run.steps", "must be a positive integer");
    }
    m_out->runSteps = run["steps"].get<int64_t>();
  }
  if (run.contains("settle")) {
    if (Status st = Number(run["settle"], "run.settle", &m_out->runSettle); !st) return st;
    if (m_out->runSettle < 0 || m_out->runSettle > 3600) return Error("run.settle", "must be 0 to 3600 seconds");
  }
  return Status::Ok();
}

Status Reader::Probe(const json& root) {
  sim::SceneSetup& s = m_out->setup;
  const json& probe = root["probe"];
  if (!probe.is_object()) return Error("probe", "must be an object");
  CheckKeys(probe, "probe", {"dam_break_column_width"});
  if (probe.contains("dam_break_column_width")) {
    double a;
    if (Status st = Number(probe["dam_break_column_width"], "probe.dam_break_column_width", &a); !st) return st;
    if (a <= 0) return Error("probe.dam_break_column_width", "must be positive");
    DamBreakProbe p;
    p.columnWidth = static_cast<float>(a);
    p.wallX = s.tank.min.x;
    p.floorY = s.tank.min.y;
    p.depth = s.tank.max.z - s.tank.min.z;
    m_out->damBreak = p;
  }
  return Status::Ok();
}

}  // namespace scene

using scene::json;
using scene::kMaxDepth;
using scene::kMaxEcho;

namespace {

/// The deepest nesting of [ and { outside strings (a bound on the parser's depth: one pass, no allocation).
int BracketDepth(const std::string& text) {
  int depth = 0, deepest = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '"') {
      for (++i; i < text.size() && text[i] != '"'; ++i) {
        if (text[i] == '\\') ++i;
      }
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

}  // namespace

Status ParseScene(const std::string& text, const std::string& origin, SceneFile* out) {
  *out = SceneFile{};
  out->path = origin;
  scene::StructureScan scan(text);
  json root;
  try {
    // The parser is not recursive, but dump (the messages) and a json's copies are: deeper values are
    // dropped as they are read, and the scene refused.
    // The callback parser is several times slower than the plain one (a 13 MB scene of 97,336 blocks:
    // 10 s), so it runs only where the brackets come near the cap.
    int deepest = 0;
    if (BracketDepth(text) < kMaxDepth - 2) {
      root = json::parse(text);
    } else {
      json::parser_callback_t depthCap = [&](int depth, json::parse_event_t, json&) {
        if (depth > kMaxDepth) deepest = depth;
        return depth <= kMaxDepth;
      };
      root = json::parse(text, depthCap);
    }
    if (deepest > 0) {
      if (Status s = scan.Run(origin); !s) return s;  // names the line
      return Status::Error(Format("%s: nested more than %d levels deep: not a scene", origin.c_str(), kMaxDepth));
    }
  } catch (const json::exception& e) {  // parse errors, and numbers too large for a double
    // The parser quotes the bytes it read last, whole: a binary file given by mistake, invalid UTF-8
    // or a 5 MB unterminated string must reach the terminal escaped and cut, like any user text.
    const std::string what = ShowText(e.what(), 2 * kMaxEcho);
    return Status::Error(origin + ": not valid JSON: " + what);
  }
  if (Status s = scan.Run(origin); !s) return s;
  scene::Reader reader(out);
  const Status s = reader.Parse(root);
  reader.CountUnknown();
  return s;
}

Status LoadScene(const std::string& path, SceneFile* out) {
  std::string text;
  if (Status s = ReadTextFile(path, "scene file", size_t{16} << 20, &text); !s) return s;  // 16 MiB
  return ParseScene(text, path, out);
}

Status SetSolverParam(sim::SceneSetup* setup, const std::string& assignment) {
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos) return Status::Error("--set " + ShowText(assignment) + ": expected key=value");
  const std::string key = assignment.substr(0, eq);
  const std::string value = assignment.substr(eq + 1);
  // What a message quotes: the key and the value escaped and cut to 40 characters each.
  const std::string shown = "--set " + ShowText(key, 40) + "=" + ShowText(value, 40);
  if (key == "method" || key == "solver.method") {
    if (!sim::ParseSolverMethod(value, &setup->method)) return Status::Error(shown + ": must be one of " + sim::SolverNames());
    return Status::Ok();
  }
  if (key == "density" || key == "solver.density") {
    if (!sim::ParseDensityModel(value, &setup->density)) return Status::Error(shown + ": must be summation or delta_sph");
    return Status::Ok();
  }
  const ParamDesc* desc = FindParam(key);
  if (!desc) {
    std::vector<std::string> solver, reuse;
    for (const ParamDesc& p : ParamRegistry()) (p.group == "solver" ? solver : reuse).push_back(p.group == "solver" ? p.name : p.key);
    return Status::Error("--set " + ShowText(key, 40) + ": unknown parameter (known: " + ShowList(solver, 6) + "; " +
                         ShowList(reuse, 8) + "; docs/user/scenes.md lists them all)");
  }
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || !std::isfinite(v)) return Status::Error(shown + ": not a finite number");
  // A known key is shown as it is; the registry's check names it, the value and the range.
  return SetParam(*desc, v, "--set " + key, setup);
}

}  // namespace sphxr::app
