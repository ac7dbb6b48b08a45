#include "scene_reader.h"
#include "sphxr/common/log.h"

namespace sphxr::app::scene {

Status Reader::Tank(const json& root) {
  sim::SceneSetup& s = m_out->setup;
  if (!root.contains("tank")) return Error("tank", "missing: every scene needs a tank (its interior is the domain)");
  const json& tank = root["tank"];
  if (!tank.is_object()) return Error("tank", "must be an object");
  CheckKeys(tank, "tank", {"min", "max", "open_top", "boundary_layers", "floor_viscosity", "friction", "wall_pressure", "wall_contact"});
  if (Status st = Box(tank, "tank", &s.tank); !st) return st;
  if (tank.contains("open_top")) {
    if (!tank["open_top"].is_boolean()) return Error("tank.open_top", "must be true or false");
    s.openTop = tank["open_top"].get<bool>();
  }
  if (tank.contains("floor_viscosity")) {
    return Error("tank.floor_viscosity",
                 "was removed: a wall's friction is now tank.friction (\"no_slip\", \"free_slip\" or \"artificial\", "
                 "per face; docs/user/scenes.md)");
  }
  if (tank.contains("friction")) {
    if (Status st = Friction(tank["friction"], &s.friction); !st) return st;
  }
  if (tank.contains("wall_pressure")) {
    const json& w = tank["wall_pressure"];
    const std::string v = w.is_string() ? w.get<std::string>() : "";
    if (v == "mirrored") s.wallPressure = sim::SceneSetup::WallPressure::kMirrored;
    else if (v == "wall_density") s.wallPressure = sim::SceneSetup::WallPressure::kWallDensity;
    else return Error("tank.wall_pressure", "must be \"mirrored\" or \"wall_density\"");
  }
  if (tank.contains("wall_contact")) {
    if (!tank["wall_contact"].is_boolean()) return Error("tank.wall_contact", "must be true or false");
    s.wallContact = tank["wall_contact"].get<bool>();
  }
  if (tank.contains("boundary_layers")) {
    if (!tank["boundary_layers"].is_number_integer()) return Error("tank.boundary_layers", "must be an integer");
    const int64_t layers = tank["boundary_layers"].get<int64_t>();
    if (layers < 1 || layers > 4) return Error("tank.boundary_layers", "must be 1 to 4");
    s.boundaryLayers = static_cast<int>(layers);
  }
  return Status::Ok();
}

Status Reader::Friction(const json& f, sim::TankFriction* out) {
  auto parse = [&](const json& v, const std::string& key, sim::WallFriction* w) -> Status {
    const std::string name = v.is_string() ? v.get<std::string>() : "";
    if (name == "no_slip") *w = sim::WallFriction::kNoSlip;
    else if (name == "free_slip") *w = sim::WallFriction::kFreeSlip;
    else if (name == "artificial") *w = sim::WallFriction::kArtificial;
    else return Error(key, "must be \"no_slip\", \"free_slip\" or \"artificial\"");
    return Status::Ok();
  };
  if (f.is_string()) {  // one friction for every face and the obstacles
    sim::WallFriction w;
    if (Status st = parse(f, "tank.friction", &w); !st) return st;
    *out = sim::TankFriction{w, w, w, w, w, w, w};
    return Status::Ok();
  }
  if (!f.is_object()) {
    return Error("tank.friction", "must be a friction name or an object of faces (floor, top, walls, x_min, x_max, "
                                  "z_min, z_max, obstacles)");
  }
  CheckKeys(f, "tank.friction", {"floor", "top", "walls", "x_min", "x_max", "z_min", "z_max", "obstacles"});
  // "walls" sets the four side faces; a side named on its own overrides it.
  if (f.contains("walls")) {
    sim::WallFriction w;
    if (Status st = parse(f["walls"], "tank.friction.walls", &w); !st) return st;
    out->xMin = out->xMax = out->zMin = out->zMax = w;
  }
  const std::pair<const char*, sim::WallFriction*> faces[] = {
      {"floor", &out->floor}, {"top", &out->top},     {"x_min", &out->xMin},         {"x_max", &out->xMax},
      {"z_min", &out->zMin},  {"z_max", &out->zMax},  {"obstacles", &out->obstacles}};
  for (const auto& [name, w] : faces) {
    if (f.contains(name)) {
      if (Status st = parse(f[name], std::string("tank.friction.") + name, w); !st) return st;
    }
  }
  return Status::Ok();
}

Status Reader::Fluid(const json& root) {
  sim::SceneSetup& s = m_out->setup;
  const json& fluid = root["fluid"];
  if (!fluid.is_array()) return Error("fluid", "must be an array of blocks");
  if (fluid.size() > static_cast<size_t>(sim::kMaxFluidBlocks)) {
    return Error("fluid", Format("%zu blocks, at most %d (docs/user/scenes.md#limits): merge blocks that touch",
                                 fluid.size(), sim::kMaxFluidBlocks));
  }
  s.fluid.reserve(fluid.size());
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
  return Status::Ok();
}

Status Reader::Obstacles(const json& root) {
  sim::SceneSetup& s = m_out->setup;
  const json& obstacles = root["obstacles"];
  if (!obstacles.is_array()) return Error("obstacles", "must be an array of boxes");
  if (obstacles.size() > static_cast<size_t>(sim::kMaxObstacles)) {
    return Error("obstacles", Format("%zu boxes, at most %d (each is checked for fluid inside it every step; "
                                     "docs/user/scenes.md#limits): merge touching boxes",
                                     obstacles.size(), sim::kMaxObstacles));
  }
  for (size_t i = 0; i < obstacles.size(); ++i) {
    const std::string key = "obstacles[" + std::to_string(i) + "]";
    if (!obstacles[i].is_object()) return Error(key, "must be an object with min and max");
    CheckKeys(obstacles[i], key, {"min", "max"});
    sim::Aabb box;
    if (Status st = Box(obstacles[i], key, &box); !st) return st;
    s.obstacles.push_back(box);
  }
  return Status::Ok();
}

}  // namespace sphxr::app::scene
