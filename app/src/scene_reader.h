#pragma once
// The scene file's reader (scene_file.h), private to app/: the JSON checks every section shares
// (scene_json.cpp), and one method per section: the top level, solver, reuse, surface, run and probe
// (scene_file.cpp), the tank and the fluid and obstacle blocks (scene_tank.cpp), the paddles
// (scene_paddles.cpp).
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>

#include "sphxr/app/scene_file.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/common/status.h"

namespace sphxr::app::scene {

using nlohmann::json;

constexpr int kMaxDepth = kMaxSceneDepth;
constexpr size_t kMaxEcho = 80;      // characters of a bad value quoted in a message

// A bad value as a message quotes it: at most kMaxEcho characters, ASCII only (control characters and
// terminal escapes are escaped by dump's ensure_ascii), so a message stays one short line whatever the
// file holds. (Depth is capped at parse time, so dump's recursion is bounded.)
std::string Brief(const json& j);
// A key from the file in a message or warning: ShowText (escaped, at most kMaxEcho bytes).
std::string Shown(const std::string& key);
// Text from the file shown on a terminal (names): UTF-8 without Unicode's Cc, Cf, Zl and Zp (IsPlainText).
bool Printable(const std::string& text);

// What nlohmann's parser does not say: nesting deeper than kMaxDepth, and a key given twice in one
// object (the parser keeps the last, so a second "solver" would silently replace the first). A scan of the
// raw text, so that the message can give the line of each; run on text the parser accepted.
class StructureScan {
 public:
  explicit StructureScan(const std::string& text) : m_text(text) {}
  Status Run(const std::string& origin);

 private:
  const std::string& m_text;
};

class Reader {
 public:
  explicit Reader(SceneFile* out) : m_out(out) {}
  Status Parse(const json& root);
  void CountUnknown() const;

 private:
  Status Error(const std::string& key, const std::string& why) const;
  void CheckKeys(const json& obj, const std::string& prefix, std::initializer_list<const char*> known);
  // An unknown key is warned about by name, the first kMaxWarnings of them (a file of 100,000 would
  // be 100,000 lines); Parse counts the rest in one line.
  static constexpr int kMaxWarnings = 20;
  void Unknown(const std::string& key);
  Status Number(const json& j, const std::string& key, double* v) const;
  Status Vec(const json& j, const std::string& key, sim::Vec3* v) const;
  Status Box(const json& j, const std::string& key, sim::Aabb* box) const;

  // The sections; each takes the root object and reads its own key.
  Status Solver(const json& root);
  Status Tank(const json& root);
  Status Friction(const json& friction, sim::TankFriction* out);  // tank.friction
  Status Fluid(const json& root);
  Status Obstacles(const json& root);
  Status Reuse(const json& root);
  Status Surface(const json& root);
  Status Run(const json& root);
  Status Probe(const json& root);
  // "paddles": {"frame_rate": 90, "list": [{name, hand, shapes, trajectory, loop, viscosity, limits, haptics}]}
  Status Paddles(const json& j);
  Status Paddle(const json& p, const std::string& key, size_t index, interaction::PaddleDesc* d);  // one of the list
  Status PaddleShapes(const json& p, const std::string& key, interaction::PaddleDesc* d) const;
  Status PaddleLimits(const json& l, const std::string& key, interaction::PaddleLimits* limits);  // "limits"
  Status PaddleTrajectory(const json& p, const std::string& key, interaction::PaddleDesc* d);
  Status Positive(const json& obj, const std::string& prefix, const char* name, float* out) const;
  Status Shape(const json& j, const std::string& key, sim::ShapePrimitive* out) const;

  SceneFile* m_out;
  int m_unknown = 0;
};

}  // namespace sphxr::app::scene
