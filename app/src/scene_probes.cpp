#include "scene_probes.h"

#include <cmath>
#include <limits>
#include <set>

#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace sphxr::app {
namespace {

using nlohmann::json;

std::string Str(sim::Vec3 v) { return Format("[%g, %g, %g]", v.x, v.y, v.z); }

class ProbeReader {
 public:
  ProbeReader(const std::string& path, const sim::SceneSetup& setup, const std::function<void(const std::string&)>& unknown)
      : m_path(path), m_setup(setup), m_unknown(unknown) {}

  Status Error(const std::string& key, const std::string& why) const { return Status::Error(m_path + ": " + key + ": " + why); }

  void CheckKeys(const json& obj, const std::string& prefix, std::initializer_list<const char*> known) const {
    const std::set<std::string> names(known.begin(), known.end());
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      if (!names.count(it.key())) m_unknown(prefix + "." + ShowText(it.key()));
    }
  }

  Status Number(const json& j, const std::string& key, float* v) const {
    if (!j.is_number()) return Error(key, "must be a number, got " + std::string(j.type_name()));
    const double d = j.get<double>();
    if (!std::isfinite(d) || std::fabs(d) > std::numeric_limits<float>::max()) return Error(key, "must be a finite number");
    *v = static_cast<float>(d);
    return Status::Ok();
  }

  Status Vec(const json& j, const std::string& key, sim::Vec3* v) const {
    if (!j.is_array() || j.size() != 3) return Error(key, "must be an array of three numbers");
    float c[3];
    for (int i = 0; i < 3; ++i) {
      if (Status s = Number(j[i], key + "[" + std::to_string(i) + "]", &c[i]); !s) return s;
    }
    *v = sim::Vec3{c[0], c[1], c[2]};
    return Status::Ok();
  }

  /// Every probe has a name, unique among the probes, that can head a CSV column as it is.
  Status Name(const json& p, const std::string& key, std::string* name) {
    if (!p.contains("name") || !p["name"].is_string()) return Error(key + ".name", "every probe needs a name (a string)");
    *name = p["name"].get<std::string>();
    if (name->empty() || name->size() > 64) return Error(key + ".name", "must have 1 to 64 characters");
    if (!IsPlainText(*name) || name->find_first_of(",\"") != std::string::npos) {
      return Error(key + ".name", "'" + ShowText(*name) + "' has a comma, a quote or a control, format or line-separator "
                                  "character: it heads a CSV column");
    }
    if (!m_names.insert(*name).second) return Error(key + ".name", "'" + ShowText(*name) + "' names another probe too");
    return Status::Ok();
  }

  bool InTank(sim::Vec3 p) const {
    const sim::Aabb& t = m_setup.tank;
    return p.x >= t.min.x && p.x <= t.max.x && p.y >= t.min.y && p.y <= t.max.y && p.z >= t.min.z && p.z <= t.max.z;
  }
  std::string Tank() const { return "the tank " + Str(m_setup.tank.min) + " .. " + Str(m_setup.tank.max); }

  Status Pressure(const json& p, const std::string& key, sim::PressureProbe* out) {
    if (!p.is_object()) return Error(key, "must be an object with name, at and (for a wall) normal");
    CheckKeys(p, key, {"name", "at", "normal", "offset"});
    if (Status s = Name(p, key, &out->name); !s) return s;
    if (!p.contains("at")) return Error(key + ".at", "is missing (the sensor's point, m)");
    if (Status s = Vec(p["at"], key + ".at", &out->at); !s) return s;
    if (!InTank(out->at)) return Error(key + ".at", Str(out->at) + " is outside " + Tank());
    if (p.contains("normal")) {
      if (Status s = Vec(p["normal"], key + ".normal", &out->normal); !s) return s;
      const float length = Length(out->normal);
      if (!(length > 0.0f)) return Error(key + ".normal", "must not be zero (leave it out for a point in the water)");
      out->normal = out->normal * (1.0f / length);
    }
    if (p.contains("offset")) {
      float offset;
      if (Status s = Number(p["offset"], key + ".offset", &offset); !s) return s;
      if (offset < 0.0f) return Error(key + ".offset", Format("%g: must be 0 or more (m into the water)", offset));
      out->offset = offset;
    }
    const float offset = out->offset.value_or(Length(out->normal) > 0.0f ? 0.5f * m_setup.params.spacing : 0.0f);
    const sim::Vec3 x = out->at - out->normal * offset;
    if (!InTank(x)) return Error(key + ".offset", Format("%g m along -normal puts the point at ", offset) + Str(x) + ", outside " + Tank());
    return Status::Ok();
  }

  Status Level(const json& g, const std::string& key, sim::LevelGauge* out) {
    if (!g.is_object()) return Error(key, "must be an object with name, x and z");
    CheckKeys(g, key, {"name", "x", "z", "bottom", "top"});
    if (Status s = Name(g, key, &out->name); !s) return s;
    for (const char* k : {"x", "z"}) {
      if (!g.contains(k)) return Error(key + "." + k, "is missing (the gauge's vertical line, m)");
    }
    if (Status s = Number(g["x"], key + ".x", &out->x); !s) return s;
    if (Status s = Number(g["z"], key + ".z", &out->z); !s) return s;
    const sim::Aabb& t = m_setup.tank;
    if (out->x < t.min.x || out->x > t.max.x) return Error(key + ".x", Format("%g is outside ", out->x) + Tank());
    if (out->z < t.min.z || out->z > t.max.z) return Error(key + ".z", Format("%g is outside ", out->z) + Tank());
    for (const char* k : {"bottom", "top"}) {
      if (!g.contains(k)) continue;
      float v;
      if (Status s = Number(g[k], key + "." + k, &v); !s) return s;
      if (v < t.min.y || v > t.max.y) return Error(key + "." + k, Format("%g is outside the tank's height %g .. %g", v, t.min.y, t.max.y));
      (std::string(k) == "bottom" ? out->bottom : out->top) = v;
    }
    if (out->bottom.value_or(t.min.y) >= out->top.value_or(t.max.y)) return Error(key + ".top", "must be above bottom");
    return Status::Ok();
  }

 private:
  std::string m_path;
  const sim::SceneSetup& m_setup;
  const std::function<void(const std::string&)>& m_unknown;
  std::set<std::string> m_names;
};

}  // namespace

Status ParseProbes(const json& j, const std::string& path, const sim::SceneSetup& setup,
                   const std::vector<interaction::PaddleDesc>& paddles,
                   const std::function<void(const std::string&)>& unknown, ProbeConfig* out) {
  ProbeReader r(path, setup, unknown);
  *out = ProbeConfig{};
  if (!j.is_object()) return r.Error("probes", "must be an object (every, pressure, level, force)");
  r.CheckKeys(j, "probes", {"every", "pressure", "level", "force"});
  if (j.contains("every")) {  // a double, as written: the rows' times are its multiples
    float check;
    if (Status s = r.Number(j["every"], "probes.every", &check); !s) return s;
    const double every = j["every"].get<double>();
    if (!(every >= kMinProbeInterval)) {
      return r.Error("probes.every", Format("%g: must be at least %g s of simulated time between rows (every row is "
                                            "written; 1e-9 s wrote 1.28 million rows in 3 steps)",
                                            every, kMinProbeInterval));
    }
    out->every = every;
  }
  // The probes together, counted before one is read (10,000 gauges were read and sampled every step).
  size_t probes = 0;
  for (const char* name : {"pressure", "level", "force"}) {
    if (j.contains(name) && j[name].is_array()) probes += j[name].size();
  }
  if (probes > static_cast<size_t>(sim::kMaxProbes)) {
    return r.Error("probes", Format("%zu probes, at most %d together (a CSV column each; docs/user/scenes.md#limits)",
                                    probes, sim::kMaxProbes));
  }
  auto list = [&](const char* name, auto&& each) -> Status {
    if (!j.contains(name)) return Status::Ok();
    const std::string key = std::string("probes.") + name;
    if (!j[name].is_array()) return r.Error(key, "must be an array");
    for (size_t i = 0; i < j[name].size(); ++i) {
      if (Status s = each(j[name][i], key + "[" + std::to_string(i) + "]"); !s) return s;
    }
    return Status::Ok();
  };
  if (Status s = list("pressure", [&](const json& p, const std::string& key) {
        sim::PressureProbe probe;
        if (Status st = r.Pressure(p, key, &probe); !st) return st;
        out->set.pressure.push_back(probe);
        return Status::Ok();
      });
      !s) {
    return s;
  }
  if (Status s = list("level", [&](const json& g, const std::string& key) {
        sim::LevelGauge gauge;
        if (Status st = r.Level(g, key, &gauge); !st) return st;
        out->set.level.push_back(gauge);
        return Status::Ok();
      });
      !s) {
    return s;
  }
  if (Status s = list("force", [&](const json& f, const std::string& key) {
        if (!f.is_object()) return r.Error(key, "must be an object with name and body (a paddle's name)");
        r.CheckKeys(f, key, {"name", "body"});
        sim::ForceProbe probe;
        if (Status st = r.Name(f, key, &probe.name); !st) return st;
        if (!f.contains("body") || !f["body"].is_string()) return r.Error(key + ".body", "must name a paddle (a string)");
        const std::string body = f["body"].get<std::string>();
        std::vector<std::string> all;
        for (size_t k = 0; k < paddles.size(); ++k) {
          if (paddles[k].name == body) probe.body = static_cast<int>(k);
          all.push_back(paddles[k].name);
        }
        const std::string names = ShowList(all);
        if (probe.body < 0) {
          return r.Error(key + ".body", "'" + ShowText(body) + "' is no paddle of the scene (" +
                                            (names.empty() ? std::string("it has none") : "its paddles: " + names) +
                                            "; static obstacles have no force probe)");
        }
        out->set.force.push_back(probe);
        return Status::Ok();
      });
      !s) {
    return s;
  }
  return Status::Ok();
}

}  // namespace sphxr::app
