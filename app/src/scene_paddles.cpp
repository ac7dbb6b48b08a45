#include <cmath>
#include <filesystem>

#include "scene_reader.h"
#include "sphxr/common/log.h"

namespace sphxr::app::scene {

Status Reader::Positive(const json& obj, const std::string& prefix, const char* name, float* out) const {
  if (!obj.contains(name)) return Status::Ok();
  double v;
  if (Status st = Number(obj[name], prefix + "." + name, &v); !st) return st;
  if (v <= 0.0 || v > 1e6) return Error(prefix + "." + name, Format("%g: must be positive (and at most 1e6)", v));
  *out = static_cast<float>(v);
  return Status::Ok();
}

Status Reader::Shape(const json& j, const std::string& key, sim::ShapePrimitive* out) const {
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

Status Reader::PaddleShapes(const json& p, const std::string& key, interaction::PaddleDesc* d) const {
  if (!p.contains("shapes")) return Error(key + ".shapes", "missing: \"blade_on_handle\" or a list of box/capsule");
  const json& shapes = p["shapes"];
  if (shapes.is_string() && shapes.get<std::string>() == "blade_on_handle") {
    d->shapes = interaction::BladeOnHandle();
  } else if (shapes.is_array() && !shapes.empty()) {
    if (shapes.size() > static_cast<size_t>(sim::kMaxBodyShapes)) {
      return Error(key + ".shapes", Format("%zu shapes, at most %d (every step's contact test loops over them; "
                                           "docs/user/scenes.md#limits)",
                                           shapes.size(), sim::kMaxBodyShapes));
    }
    for (size_t k = 0; k < shapes.size(); ++k) {
      sim::ShapePrimitive prim;
      if (Status st = Shape(shapes[k], key + ".shapes[" + std::to_string(k) + "]", &prim); !st) return st;
      d->shapes.push_back(prim);
    }
  } else {
    return Error(key + ".shapes", "must be \"blade_on_handle\" or a non-empty list of box/capsule");
  }
  return Status::Ok();
}

Status Reader::PaddleLimits(const json& l, const std::string& key, interaction::PaddleLimits* limits) {
  const std::string lk = key + ".limits";
  if (!l.is_object()) return Error(lk, "must be an object");
  CheckKeys(l, lk, {"max_speed", "max_angular_speed", "teleport_distance", "reentry_speed", "hold_time",
                    "withdraw_speed", "withdraw_clearance"});
  interaction::PaddleLimits& m = *limits;
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
  return Status::Ok();
}

// A scripted paddle's trajectory file, relative to the scene file's folder.
Status Reader::PaddleTrajectory(const json& p, const std::string& key, interaction::PaddleDesc* d) {
  if (!p.contains("trajectory") || !p["trajectory"].is_string()) {
    return Error(key + ".trajectory", "a scripted paddle needs a trajectory file (CSV of timed poses)");
  }
  const std::string name = p["trajectory"].get<std::string>();
  if (name.empty() || name.size() > 4096 || !Printable(name)) {
    return Error(key + ".trajectory", "must be a file name (printable, at most 4096 characters)");
  }
  std::filesystem::path file = name;
  if (file.is_relative()) file = std::filesystem::path(m_out->path).parent_path() / file;
  m_out->inputs.push_back(file.string());
  if (Status st = interaction::Trajectory::Load(file.string(), &d->trajectory); !st) {
    return Error(key + ".trajectory", st.message());
  }
  if (p.contains("loop")) {
    if (!p["loop"].is_boolean()) return Error(key + ".loop", "must be true or false");
    d->trajectory.SetLoop(p["loop"].get<bool>());
  }
  return Status::Ok();
}

Status Reader::Paddle(const json& p, const std::string& key, size_t index, interaction::PaddleDesc* d) {
  if (!p.is_object()) return Error(key, "must be an object");
  CheckKeys(p, key, {"name", "hand", "shapes", "trajectory", "loop", "viscosity", "limits", "haptics"});
  d->name = "paddle" + std::to_string(index);
  if (p.contains("name")) {
    if (!p["name"].is_string()) return Error(key + ".name", "must be a string");
    d->name = p["name"].get<std::string>();
    if (!Printable(d->name)) {
      return Error(key + ".name", ShowText(d->name) + ": has control, format or line-separator characters (terminal "
                                  "escapes?): use plain text");
    }
  }
  const std::string hand = p.contains("hand") && p["hand"].is_string() ? p["hand"].get<std::string>() : "";
  if (hand == "left") d->holder = interaction::Holder::kLeftHand;
  else if (hand == "right") d->holder = interaction::Holder::kRightHand;
  else if (hand == "script") d->holder = interaction::Holder::kScript;
  else return Error(key + ".hand", "must be \"left\", \"right\" or \"script\"");
  if (Status st = PaddleShapes(p, key, d); !st) return st;
  if (p.contains("viscosity")) {
    double v;
    if (Status st = Number(p["viscosity"], key + ".viscosity", &v); !st) return st;
    if (v < 0 || v > 10) return Error(key + ".viscosity", "must be from 0 to 10 (artificial viscosity alpha)");
    d->viscosity = static_cast<float>(v);
  }
  if (p.contains("limits")) {
    if (Status st = PaddleLimits(p["limits"], key, &d->limits); !st) return st;
  }
  if (p.contains("haptics")) {
    const json& h = p["haptics"];
    const std::string hk = key + ".haptics";
    if (!h.is_object()) return Error(hk, "must be an object");
    CheckKeys(h, hk, {"full_scale_force", "time_constant"});
    if (Status st = Positive(h, hk, "full_scale_force", &d->haptics.fullScaleForce); !st) return st;
    if (Status st = Positive(h, hk, "time_constant", &d->haptics.timeConstant); !st) return st;
  }
  if (d->holder == interaction::Holder::kScript) return PaddleTrajectory(p, key, d);
  return Status::Ok();
}

Status Reader::Paddles(const json& j) {
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
  if (list.size() > static_cast<size_t>(sim::kMaxBodies)) {
    return Error("paddles.list", Format("%zu paddles, at most %d (docs/user/scenes.md#limits)", list.size(), sim::kMaxBodies));
  }
  for (size_t i = 0; i < list.size(); ++i) {
    interaction::PaddleDesc d;
    if (Status st = Paddle(list[i], "paddles.list[" + std::to_string(i) + "]", i, &d); !st) return st;
    m_out->paddles.push_back(std::move(d));
  }
  return Status::Ok();
}

}  // namespace sphxr::app::scene
