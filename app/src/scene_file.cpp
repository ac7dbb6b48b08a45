#include "sphxr/app/scene_file.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <limits>
#include <set>
#include <unordered_map>
#include <sstream>

#include "sphxr/app/param_registry.h"
#include "sphxr/common/log.h"
#include "sphxr/common/text_file.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {
namespace {

using nlohmann::json;

constexpr int kMaxDepth = 64;        // no scene nests deeper than 6; the cap keeps every walk shallow
constexpr size_t kMaxEcho = 80;      // characters of a bad value quoted in a message

// A bad value as a message quotes it: at most kMaxEcho characters, ASCII only (control characters and
// terminal escapes are escaped by dump's ensure_ascii), so a message stays one short line whatever the
// file holds. (Depth is capped at parse time, so dump's recursion is bounded.)
std::string Brief(const json& j) {
  std::string text = j.dump(-1, ' ', true, json::error_handler_t::replace);
  if (text.size() > kMaxEcho) text = text.substr(0, kMaxEcho - 3) + "...";
  return text;
}

// A key from the file in a message or warning: at most kMaxEcho characters, control characters as '?'.
std::string Shown(const std::string& key) {
  std::string out = key.size() > kMaxEcho ? key.substr(0, kMaxEcho - 3) + "..." : key;
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  }
  return out;
}

// Text from the file shown on a terminal (names): printable ASCII and UTF-8, no control characters.
bool Printable(const std::string& text) {
  for (const char c : text) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return false;
  }
  return true;
}

// What nlohmann's parser does not say: nesting deeper than kMaxDepth, and a key given twice in one
// object (the parser keeps the last, so a second "solver" silently replaced the first). A scan of the
// raw text, so that the message can give the line of each; run on text the parser accepted.
class StructureScan {
 public:
  explicit StructureScan(const std::string& text) : m_text(text) {}

  Status Run(const std::string& origin) {
    struct Frame {
      bool object;
      std::string path;
      std::unordered_map<std::string, int> keys;  // key -> its line (a map: an object may have 100,000 keys)
      std::string pendingKey;
      size_t index = 0;
    };
    std::vector<Frame> stack;
    int line = 1;
    auto childPath = [&]() -> std::string {
      if (stack.empty()) return "";
      const Frame& f = stack.back();
      if (f.object) return f.path.empty() ? f.pendingKey : f.path + "." + f.pendingKey;
      return f.path + "[" + std::to_string(f.index) + "]";
    };
    for (size_t i = 0; i < m_text.size(); ++i) {
      const char c = m_text[i];
      if (c == '\n') {
        ++line;
      } else if (c == '"') {
        const size_t start = i;
        for (++i; i < m_text.size() && m_text[i] != '"'; ++i) {
          if (m_text[i] == '\\') ++i;
        }
        if (stack.empty() || !stack.back().object) continue;
        // A key is a string followed by ':'.
        size_t k = i + 1;
        while (k < m_text.size() && (m_text[k] == ' ' || m_text[k] == '\t' || m_text[k] == '\r' || m_text[k] == '\n')) ++k;
        if (k >= m_text.size() || m_text[k] != ':') continue;
        std::string key = m_text.substr(start + 1, i - start - 1);
        if (key.find('\\') != std::string::npos) {  // escapes: compare keys as the parser reads them
          try {
            key = json::parse(m_text.substr(start, i - start + 1)).get<std::string>();
          } catch (const json::exception&) {
          }
        }
        Frame& f = stack.back();
        if (const auto seen = f.keys.find(key); seen != f.keys.end()) {
          const std::string where = f.path.empty() ? "at the top level" : "in " + Shown(f.path);
          return Status::Error(Format("%s: key %s appears twice %s (lines %d and %d): the second would replace the "
                                      "first; keep one",
                                      origin.c_str(), Brief(json(key)).c_str(), where.c_str(), seen->second, line));
        }
        f.keys.emplace(key, line);
        f.pendingKey = key;
      } else if (c == '{' || c == '[') {
        if (static_cast<int>(stack.size()) >= kMaxDepth) {
          return Status::Error(Format("%s: line %d: nested more than %d levels deep: not a scene", origin.c_str(), line,
                                      kMaxDepth));
        }
        Frame f;
        f.object = c == '{';
        f.path = childPath();
        stack.push_back(std::move(f));
      } else if (c == '}' || c == ']') {
        if (!stack.empty()) stack.pop_back();
      } else if (c == ',' && !stack.empty() && !stack.back().object) {
        ++stack.back().index;
      }
    }
    return Status::Ok();
  }

 private:
  const std::string& m_text;
};

class Reader {
 public:
  explicit Reader(SceneFile* out) : m_out(out) {}

  Status Error(const std::string& key, const std::string& why) const {
    return Status::Error(m_out->path + ": " + key + ": " + why);
  }

  void CheckKeys(const json& obj, const std::string& prefix, std::initializer_list<const char*> known) {
    std::set<std::string> names(known.begin(), known.end());
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      if (!names.count(it.key())) {
        const std::string key = prefix.empty() ? Shown(it.key()) : prefix + "." + Shown(it.key());
        Unknown(key);
      }
    }
  }

  // An unknown key is warned about by name, the first kMaxWarnings of them (a file of 100,000 would
  // be 100,000 lines); Parse counts the rest in one line.
  static constexpr int kMaxWarnings = 20;
  void Unknown(const std::string& key) {
    if (++m_unknown > kMaxWarnings) return;
    m_out->warnings.push_back("unknown key '" + key + "' ignored");
    SPHXR_LOG_WARN("%s: unknown key '%s' ignored", m_out->path.c_str(), key.c_str());
  }
  void CountUnknown() const {
    if (m_unknown <= kMaxWarnings) return;
    m_out->warnings.push_back(Format("%d more unknown keys ignored", m_unknown - kMaxWarnings));
    SPHXR_LOG_WARN("%s: %d more unknown keys ignored", m_out->path.c_str(), m_unknown - kMaxWarnings);
  }

  Status Number(const json& j, const std::string& key, double* v) const {
    if (!j.is_number()) return Error(key, "must be a number, got " + std::string(j.type_name()) + " " + Brief(j));
    *v = j.get<double>();
    if (!std::isfinite(*v)) return Error(key, "must be finite");
    // Every scene number is stored as a float: beyond its range the conversion is undefined.
    if (std::fabs(*v) > static_cast<double>(std::numeric_limits<float>::max())) {
      return Error(key, "is " + Brief(j) + ", beyond the range of a float (3.4e38)");
    }
    return Status::Ok();
  }

  Status Vec(const json& j, const std::string& key, sim::Vec3* v) const {
    if (!j.is_array() || j.size() != 3) return Error(key, "must be an array of three numbers, got " + Brief(j));
    double c[3];
    for (int i = 0; i < 3; ++i) {
      if (Status s = Number(j[i], key + "[" + std::to_string(i) + "]", &c[i]); !s) return s;
    }
    *v = sim::Vec3{static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])};
    return Status::Ok();
  }

  Status Box(const json& j, const std::string& key, sim::Aabb* box) const {
    if (!j.contains("min") || !j.contains("max")) return Error(key, "needs \"min\" and \"max\"");
    if (Status s = Vec(j["min"], key + ".min", &box->min); !s) return s;
    if (Status s = Vec(j["max"], key + ".max", &box->max); !s) return s;
    return Status::Ok();
  }

  Status Parse(const json& root) {
    if (!root.is_object()) return Error("(root)", "a scene must be a JSON object");
    CheckKeys(root, "", {"name", "description", "solver", "gravity", "tank", "fluid", "obstacles", "run", "probe", "reuse",
                         "paddles", "surface"});
    sim::SceneSetup& s = m_out->setup;
    if (root.contains("name")) {
      if (!root["name"].is_string()) return Error("name", "must be a string");
      m_out->name = root["name"].get<std::string>();
      if (!Printable(m_out->name)) return Error("name", "has control characters (terminal escapes?): use plain text");
    }
    if (root.contains("description") && root["description"].is_string()) {
      m_out->description = root["description"].get<std::string>();
    }
    if (root.contains("solver")) {
      const json& solver = root["solver"];
      if (!solver.is_object()) return Error("solver", "must be an object");
      for (auto it = solver.begin(); it != solver.end(); ++it) {
        if (it.key() == "method") {  // the pressure solver, by name (docs/user/scenes.md)
          const std::string v = it.value().is_string() ? it.value().get<std::string>() : "";
          if (!sim::ParseSolverMethod(v, &s.method)) return Error("solver.method", "must be \"wcsph\" or \"dfsph\"");
          continue;
        }
        if (it.key() == "density") {  // how WCSPH finds the density, by name (docs/dev/physics.md)
          const std::string v = it.value().is_string() ? it.value().get<std::string>() : "";
          if (!sim::ParseDensityModel(v, &s.density)) {
            return Error("solver.density", "must be \"summation\" or \"delta_sph\"");
          }
          continue;
        }
        const sim::ParamInfo* info = sim::FindSolverParam(it.key());
        if (!info) {
          Unknown("solver." + Shown(it.key()));
          continue;
        }
        double v;
        if (Status st = Number(it.value(), "solver." + it.key(), &v); !st) return st;
        if (v < info->min || v > info->max) {
          return Error("solver." + it.key(), Format("%g is out of range: must be from %g to %g%s%s (%s)", v, info->min,
                                                    info->max, info->unit[0] ? " " : "", info->unit, info->help));
        }
        if (info->integer && v != std::floor(v)) return Error("solver." + it.key(), "must be a whole number");
        s.params.*(info->member) = static_cast<float>(v);
      }
    }
    if (root.contains("gravity")) {
      if (Status st = Vec(root["gravity"], "gravity", &s.gravity); !st) return st;
    }
    if (!root.contains("tank")) return Error("tank", "missing: every scene needs a tank (its interior is the domain)");
    {
      const json& tank = root["tank"];
      if (!tank.is_object()) return Error("tank", "must be an object");
      CheckKeys(tank, "tank", {"min", "max", "open_top", "boundary_layers", "floor_viscosity", "wall_pressure"});
      if (Status st = Box(tank, "tank", &s.tank); !st) return st;
      if (tank.contains("open_top")) {
        if (!tank["open_top"].is_boolean()) return Error("tank.open_top", "must be true or false");
        s.openTop = tank["open_top"].get<bool>();
      }
      if (tank.contains("floor_viscosity")) {
        double v;
        if (Status st = Number(tank["floor_viscosity"], "tank.floor_viscosity", &v); !st) return st;
        if (v < 0 || v > 10) return Error("tank.floor_viscosity", "must be from 0 to 10 (artificial viscosity alpha)");
        s.floorViscosity = static_cast<float>(v);
      }
      if (tank.contains("wall_pressure")) {
        const json& w = tank["wall_pressure"];
        const std::string v = w.is_string() ? w.get<std::string>() : "";
        if (v == "mirrored") s.wallPressure = sim::SceneSetup::WallPressure::kMirrored;
        else if (v == "wall_density") s.wallPressure = sim::SceneSetup::WallPressure::kWallDensity;
        else return Error("tank.wall_pressure", "must be \"mirrored\" or \"wall_density\"");
      }
      if (tank.contains("boundary_layers")) {
        if (!tank["boundary_layers"].is_number_integer()) return Error("tank.boundary_layers", "must be an integer");
        const int64_t layers = tank["boundary_layers"].get<int64_t>();
        if (layers < 1 || layers > 4) return Error("tank.boundary_layers", "must be 1 to 4");
        s.boundaryLayers = static_cast<int>(layers);
      }
    }
    if (root.contains("fluid")) {
      const json& fluid = root["fluid"];
      if (!fluid.is_array()) return Error("fluid", "must be an array of blocks");
      for (size_t i = 0; i < fluid.size(); ++i) {
        const std::string key = "fluid[" + std::to_string(i) + "]";
        if (!fluid[i].is_object()) return Error(key, "must be an object with min and max");
        CheckKeys(fluid[i], key, {"min", "max", "velocity", "hydrostatic"});
        sim::FluidBlock block;
        if (Status st = Box(fluid[i], key, &block.box); !st) return st;
        if (fluid[i].contains("velocity")) {
          if (Status st = Vec(fluid[i]["velocity"], key + ".velocity", &block.velocity); !st) return st;
        }
        if (fluid[i].contains("hydrostatic")) {
          if (!fluid[i]["hydrostatic"].is_boolean()) return Error(key + ".hydrostatic", "must be true or false");
          block.hydrostatic = fluid[i]["hydrostatic"].get<bool>();
        }
        s.fluid.push_back(block);
      }
    }
    if (root.contains("obstacles")) {
      const json& obstacles = root["obstacles"];
      if (!obstacles.is_array()) return Error("obstacles", "must be an array of boxes");
      for (size_t i = 0; i < obstacles.size(); ++i) {
        const std::string key = "obstacles[" + std::to_string(i) + "]";
        if (!obstacles[i].is_object()) return Error(key, "must be an object with min and max");
        CheckKeys(obstacles[i], key, {"min", "max"});
        sim::Aabb box;
        if (Status st = Box(obstacles[i], key, &box); !st) return st;
        s.obstacles.push_back(box);
      }
    }
    if (root.contains("reuse")) {
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
    }
    if (root.contains("paddles")) {
      if (Status st = Paddles(root["paddles"]); !st) return st;
    }
    if (root.contains("surface")) {
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
    }
    if (root.contains("run")) {
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
    }
    if (root.contains("probe")) {
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
    }
    return Status::Ok();
  }

  Status Positive(const json& obj, const std::string& prefix, const char* name, float* out) const {
    if (!obj.contains(name)) return Status::Ok();
    double v;
    if (Status st = Number(obj[name], prefix + "." + name, &v); !st) return st;
    if (v <= 0.0 || v > 1e6) return Error(prefix + "." + name, Format("%g: must be positive (and at most 1e6)", v));
    *out = static_cast<float>(v);
    return Status::Ok();
  }

  Status Shape(const json& j, const std::string& key, sim::ShapePrimitive* out) const {
    if (!j.is_object() || j.size() != 1 || !(j.contains("box") || j.contains("capsule"))) {
      return Error(key, "must be {\"box\": {center, half_extents}} or {\"capsule\": {a, b, radius}}");
    }
    if (j.contains("box")) {
      const json& b = j["box"];
      if (!b.is_object() || !b.contains("center") || !b.contains("half_extents")) {
        return Error(key + ".box", "needs \"center\" and \"half_extents\"");
      }
      out->kind = sim::ShapePrimitive::Kind::kBox;
      if (Status st = Vec(b["center"], key + ".box.center", &out->a); !st) return st;
      if (Status st = Vec(b["half_extents"], key + ".box.half_extents", &out->b); !st) return st;
      if (!(out->b.x > 0 && out->b.y > 0 && out->b.z > 0)) return Error(key + ".box.half_extents", "must be positive");
      return Status::Ok();
    }
    const json& c = j["capsule"];
    if (!c.is_object() || !c.contains("a") || !c.contains("b") || !c.contains("radius")) {
      return Error(key + ".capsule", "needs \"a\", \"b\" and \"radius\"");
    }
    out->kind = sim::ShapePrimitive::Kind::kCapsule;
    if (Status st = Vec(c["a"], key + ".capsule.a", &out->a); !st) return st;
    if (Status st = Vec(c["b"], key + ".capsule.b", &out->b); !st) return st;
    double r;
    if (Status st = Number(c["radius"], key + ".capsule.radius", &r); !st) return st;
    if (r <= 0) return Error(key + ".capsule.radius", "must be positive");
    out->radius = static_cast<float>(r);
    return Status::Ok();
  }

  // "paddles": {"frame_rate": 90, "list": [{name, hand, shapes, trajectory, loop, viscosity, limits, haptics}]}
  Status Paddles(const json& j) {
    if (!j.is_object()) return Error("paddles", "must be an object with \"list\" (and optionally \"frame_rate\")");
    CheckKeys(j, "paddles", {"frame_rate", "list"});
    if (j.contains("frame_rate")) {
      double f;
      if (Status st = Number(j["frame_rate"], "paddles.frame_rate", &f); !st) return st;
      if (f < 1 || f > 10000) return Error("paddles.frame_rate", "must be from 1 to 10000 Hz");
      m_out->paddleFrameRate = f;
    }
    if (!j.contains("list") || !j["list"].is_array()) return Error("paddles.list", "must be an array of paddles");
    const json& list = j["list"];
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string key = "paddles.list[" + std::to_string(i) + "]";
      const json& p = list[i];
      if (!p.is_object()) return Error(key, "must be an object");
      CheckKeys(p, key, {"name", "hand", "shapes", "trajectory", "loop", "viscosity", "limits", "haptics"});
      interaction::PaddleDesc d;
      d.name = "paddle" + std::to_string(i);
      if (p.contains("name")) {
        if (!p["name"].is_string()) return Error(key + ".name", "must be a string");
        d.name = p["name"].get<std::string>();
        if (!Printable(d.name)) return Error(key + ".name", "has control characters (terminal escapes?): use plain text");
      }
      const std::string hand = p.contains("hand") && p["hand"].is_string() ? p["hand"].get<std::string>() : "";
      if (hand == "left") d.holder = interaction::Holder::kLeftHand;
      else if (hand == "right") d.holder = interaction::Holder::kRightHand;
      else if (hand == "script") d.holder = interaction::Holder::kScript;
      else return Error(key + ".hand", "must be \"left\", \"right\" or \"script\"");
      if (!p.contains("shapes")) return Error(key + ".shapes", "missing: \"blade_on_handle\" or a list of box/capsule");
      const json& shapes = p["shapes"];
      if (shapes.is_string() && shapes.get<std::string>() == "blade_on_handle") {
        d.shapes = interaction::BladeOnHandle();
      } else if (shapes.is_array() && !shapes.empty()) {
        for (size_t k = 0; k < shapes.size(); ++k) {
          sim::ShapePrimitive prim;
          if (Status st = Shape(shapes[k], key + ".shapes[" + std::to_string(k) + "]", &prim); !st) return st;
          d.shapes.push_back(prim);
        }
      } else {
        return Error(key + ".shapes", "must be \"blade_on_handle\" or a non-empty list of box/capsule");
      }
      if (p.contains("viscosity")) {
        double v;
        if (Status st = Number(p["viscosity"], key + ".viscosity", &v); !st) return st;
        if (v < 0 || v > 10) return Error(key + ".viscosity", "must be from 0 to 10 (artificial viscosity alpha)");
        d.viscosity = static_cast<float>(v);
      }
      if (p.contains("limits")) {
        const json& l = p["limits"];
        const std::string lk = key + ".limits";
        if (!l.is_object()) return Error(lk, "must be an object");
        CheckKeys(l, lk, {"max_speed", "max_angular_speed", "teleport_distance", "reentry_speed", "hold_time",
                          "withdraw_speed", "withdraw_clearance"});
        interaction::PaddleLimits& m = d.limits;
        const std::pair<const char*, float*> positive[] = {{"max_speed", &m.maxSpeed},
                                                           {"max_angular_speed", &m.maxAngularSpeed},
                                                           {"teleport_distance", &m.teleportDistance},
                                                           {"reentry_speed", &m.reentrySpeed},
                                                           {"withdraw_speed", &m.withdrawSpeed}};
        for (const auto& [name, member] : positive) {
          if (Status st = Positive(l, lk, name, member); !st) return st;
        }
        for (const auto& [name, member] : {std::pair<const char*, float*>{"hold_time", &m.holdTime},
                                           std::pair<const char*, float*>{"withdraw_clearance", &m.withdrawClearance}}) {
          if (!l.contains(name)) continue;
          double v;
          if (Status st = Number(l[name], lk + "." + name, &v); !st) return st;
          if (v < 0 || v > 1e6) return Error(lk + "." + name, "must be 0 or more");
          *member = static_cast<float>(v);
        }
      }
      if (p.contains("haptics")) {
        const json& h = p["haptics"];
        const std::string hk = key + ".haptics";
        if (!h.is_object()) return Error(hk, "must be an object");
        CheckKeys(h, hk, {"full_scale_force", "time_constant"});
        if (Status st = Positive(h, hk, "full_scale_force", &d.haptics.fullScaleForce); !st) return st;
        if (Status st = Positive(h, hk, "time_constant", &d.haptics.timeConstant); !st) return st;
      }
      if (d.holder == interaction::Holder::kScript) {
        if (!p.contains("trajectory") || !p["trajectory"].is_string()) {
          return Error(key + ".trajectory", "a scripted paddle needs a trajectory file (CSV of timed poses)");
        }
        const std::string name = p["trajectory"].get<std::string>();
        if (name.empty() || name.size() > 4096 || !Printable(name)) {
          return Error(key + ".trajectory", "must be a file name (printable, at most 4096 characters)");
        }
        // Relative to the scene file's folder.
        std::filesystem::path file = name;
        if (file.is_relative()) file = std::filesystem::path(m_out->path).parent_path() / file;
        m_out->inputs.push_back(file.string());
        if (Status st = interaction::Trajectory::Load(file.string(), &d.trajectory); !st) {
          return Error(key + ".trajectory", st.message());
        }
        if (p.contains("loop")) {
          if (!p["loop"].is_boolean()) return Error(key + ".loop", "must be true or false");
          d.trajectory.SetLoop(p["loop"].get<bool>());
        }
      }
      m_out->paddles.push_back(std::move(d));
    }
    return Status::Ok();
  }

 private:
  SceneFile* m_out;
  int m_unknown = 0;
};

}  // namespace

Status ParseScene(const std::string& text, const std::string& origin, SceneFile* out) {
  *out = SceneFile{};
  out->path = origin;
  StructureScan scan(text);
  json root;
  try {
    // The parser is not recursive, but dump (the messages) and a json's copies are: deeper values are
    // dropped as they are read, and the scene refused.
    int deepest = 0;
    json::parser_callback_t depthCap = [&](int depth, json::parse_event_t, json&) {
      if (depth > kMaxDepth) deepest = depth;
      return depth <= kMaxDepth;
    };
    root = json::parse(text, depthCap);
    if (deepest > 0) {
      if (Status s = scan.Run(origin); !s) return s;  // names the line
      return Status::Error(Format("%s: nested more than %d levels deep: not a scene", origin.c_str(), kMaxDepth));
    }
  } catch (const json::exception& e) {  // parse errors, and numbers too large for a double
    // (The parser quotes the bytes it read last: a binary file given by mistake must not put raw control
    // bytes on the terminal.)
    std::string what = e.what();
    for (char& c : what) {
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
    }
    // ("last read" quotes the whole token: a 5 MB unterminated string would be a 5 MB message.)
    if (what.size() > 2 * kMaxEcho) what = what.substr(0, 2 * kMaxEcho - 3) + "...";
    return Status::Error(origin + ": not valid JSON: " + what);
  }
  if (Status s = scan.Run(origin); !s) return s;
  Reader reader(out);
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
  if (eq == std::string::npos) return Status::Error("--set " + assignment + ": expected key=value");
  const std::string key = assignment.substr(0, eq);
  const std::string value = assignment.substr(eq + 1);
  if (key == "method" || key == "solver.method") {
    if (!sim::ParseSolverMethod(value, &setup->method)) {
      return Status::Error("--set " + key + "=" + value + ": must be wcsph or dfsph");
    }
    return Status::Ok();
  }
  if (key == "density" || key == "solver.density") {
    if (!sim::ParseDensityModel(value, &setup->density)) {
      return Status::Error("--set " + key + "=" + value + ": must be summation or delta_sph");
    }
    return Status::Ok();
  }
  const ParamDesc* desc = FindParam(key);
  if (desc && desc->group == "reuse") {  // reuse.* keys of the registry
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0') return Status::Error("--set " + key + "=" + value + ": not a finite number");
    return SetParam(*desc, v, "--set " + key, setup);
  }
  const sim::ParamInfo* info = sim::FindSolverParam(key);
  if (!info) {
    std::string names;
    for (const ParamDesc& p : ParamRegistry()) names += (names.empty() ? "" : ", ") + (p.group == "solver" ? p.name : p.key);
    return Status::Error("--set " + key + ": unknown parameter (known: " + names + ")");
  }
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || !std::isfinite(v)) {
    return Status::Error("--set " + key + "=" + value + ": not a finite number");
  }
  if (v < info->min || v > info->max) {
    return Status::Error(Format("--set %s=%s: out of range, must be from %g to %g%s%s", key.c_str(), value.c_str(),
                                info->min, info->max, *info->unit ? " " : "", info->unit));
  }
  if (info->integer && v != std::floor(v)) return Status::Error("--set " + key + "=" + value + ": must be a whole number");
  setup->params.*(info->member) = static_cast<float>(v);
  return Status::Ok();
}

}  // namespace sphxr::app
