#include "sphxr/app/scene_file.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"

namespace sphxr::app {
namespace {

using nlohmann::json;

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
        const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
        m_out->warnings.push_back("unknown key '" + key + "' ignored");
        SPHXR_LOG_WARN("%s: unknown key '%s' ignored", m_out->path.c_str(), key.c_str());
      }
    }
  }

  Status Number(const json& j, const std::string& key, double* v) const {
    if (!j.is_number()) return Error(key, "must be a number, got " + std::string(j.type_name()) + " " + j.dump());
    *v = j.get<double>();
    if (!std::isfinite(*v)) return Error(key, "must be finite");
    return Status::Ok();
  }

  Status Vec(const json& j, const std::string& key, sim::Vec3* v) const {
    if (!j.is_array() || j.size() != 3) return Error(key, "must be an array of three numbers, got " + j.dump());
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
    CheckKeys(root, "", {"name", "description", "solver", "gravity", "tank", "fluid", "obstacles", "run", "probe", "reuse"});
    sim::SceneSetup& s = m_out->setup;
    if (root.contains("name")) {
      if (!root["name"].is_string()) return Error("name", "must be a string");
      m_out->name = root["name"].get<std::string>();
    }
    if (root.contains("description") && root["description"].is_string()) {
      m_out->description = root["description"].get<std::string>();
    }
    if (root.contains("solver")) {
      const json& solver = root["solver"];
      if (!solver.is_object()) return Error("solver", "must be an object");
      for (auto it = solver.begin(); it != solver.end(); ++it) {
        const sim::ParamInfo* info = sim::FindSolverParam(it.key());
        if (!info) {
          m_out->warnings.push_back("unknown key 'solver." + it.key() + "' ignored");
          SPHXR_LOG_WARN("%s: unknown key 'solver.%s' ignored", m_out->path.c_str(), it.key().c_str());
          continue;
        }
        double v;
        if (Status st = Number(it.value(), "solver." + it.key(), &v); !st) return st;
        if (v < info->min || v > info->max) {
          return Error("solver." + it.key(), Format("%g is out of range: must be from %g to %g%s%s (%s)", v, info->min,
                                                    info->max, info->unit[0] ? " " : "", info->unit, info->help));
        }
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
      CheckKeys(tank, "tank", {"min", "max", "open_top", "boundary_layers", "floor_viscosity"});
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
        CheckKeys(fluid[i], key, {"min", "max", "velocity"});
        sim::FluidBlock block;
        if (Status st = Box(fluid[i], key, &block.box); !st) return st;
        if (fluid[i].contains("velocity")) {
          if (Status st = Vec(fluid[i]["velocity"], key + ".velocity", &block.velocity); !st) return st;
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
      CheckKeys(reuse, "reuse", {"enabled", "delta1", "delta2", "threshold", "idle", "pressure_scale", "cell_count"});
      sim::ReuseParams& r = s.reuse;
      r.enabled = true;
      if (reuse.contains("enabled")) {
        if (!reuse["enabled"].is_boolean()) return Error("reuse.enabled", "must be true or false");
        r.enabled = reuse["enabled"].get<bool>();
      }
      const std::pair<const char*, float*> numbers[] = {{"delta1", &r.delta1},       {"delta2", &r.delta2},
                                                        {"threshold", &r.threshold}, {"pressure_scale", &r.pressureScale},
                                                        {"cell_count", &r.cellCount}};
      for (const auto& [key, member] : numbers) {
        if (!reuse.contains(key)) continue;
        double v;
        if (Status st = Number(reuse[key], std::string("reuse.") + key, &v); !st) return st;
        if (v < 0 || v > 1e9) return Error(std::string("reuse.") + key, "must be from 0 to 1e9");
        *member = static_cast<float>(v);
      }
      if (reuse.contains("idle")) {
        if (!reuse["idle"].is_number_integer()) return Error("reuse.idle", "must be an integer (steps)");
        const int64_t idle = reuse["idle"].get<int64_t>();
        if (idle < 0 || idle > 1000) return Error("reuse.idle", "must be 0 to 1000 steps");
        r.idle = static_cast<int>(idle);
      }
    }
    if (root.contains("run")) {
      const json& run = root["run"];
      if (!run.is_object()) return Error("run", "must be an object");
      CheckKeys(run, "run", {"time", "steps"});
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

 private:
  SceneFile* m_out;
};

}  // namespace

Status ParseScene(const std::string& text, const std::string& origin, SceneFile* out) {
  *out = SceneFile{};
  out->path = origin;
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {  // parse errors, and numbers too large for a double
    return Status::Error(origin + ": not valid JSON: " + e.what());
  }
  Reader reader(out);
  return reader.Parse(root);
}

Status LoadScene(const std::string& path, SceneFile* out) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open the scene file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return ParseScene(buffer.str(), path, out);
}

Status SetSolverParam(sim::SceneSetup* setup, const std::string& assignment) {
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos) return Status::Error("--set " + assignment + ": expected key=value");
  const std::string key = assignment.substr(0, eq);
  const std::string value = assignment.substr(eq + 1);
  const sim::ParamInfo* info = sim::FindSolverParam(key);
  if (!info) {
    std::string names;
    for (const sim::ParamInfo& p : sim::SolverParamInfos()) names += std::string(names.empty() ? "" : ", ") + p.key;
    return Status::Error("--set " + key + ": unknown parameter (known: " + names + ")");
  }
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || !std::isfinite(v)) {
    return Status::Error("--set " + key + "=" + value + ": not a finite number");
  }
  if (v < info->min || v > info->max) {
    return Status::Error(Format("--set %s=%s: out of range, must be from %g to %g %s", key.c_str(), value.c_str(),
                                info->min, info->max, info->unit));
  }
  setup->params.*(info->member) = static_cast<float>(v);
  return Status::Ok();
}

}  // namespace sphxr::app
