#include "pose_script.h"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace sphxr::xr::simrt {
namespace {

DeviceSample DefaultSample(Device device, double t) {
  DeviceSample s;
  switch (device) {
    case Device::kHead:
      // Standing at the table, the tank (centred at 1.0 m high, 0.4 m ahead) at arm's reach.
      s.pose.position = {0.0f, 1.55f, 0.1f};
      s.pose.orientation = AxisAngle({1, 0, 0}, -0.7853982f);  // pitch 45 degrees down
      break;
    case Device::kLeft:
      s.pose.position = {-0.25f, 1.1f, 0.1f};
      break;
    case Device::kRight: {
      double phase = 2.0 * M_PI * 0.5 * t;
      s.pose.position = {0.1f + 0.1f * float(std::cos(phase)), 1.2f, -0.4f + 0.1f * float(std::sin(phase))};
      s.pose.orientation = AxisAngle({1, 0, 0}, -1.5707963f);  // grip axis (-z) pointing down
      s.trigger = 0.8f;  // pressed: a click binding (simple controller) reads 1
      break;
    }
  }
  return s;
}

}  // namespace

PoseScript PoseScript::Default() { return {}; }

bool PoseScript::Load(const std::string& path, PoseScript* out, std::string* error) {
  // A regular file under kMaxBytes only: /dev/zero grew without end, a FIFO waited for a writer.
  struct stat st {};
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size > kMaxBytes) {
    *error = "SPHXR_SIM_XR_POSES='" + Shown(path) + "' is not a pose script (" +
             (stat(path.c_str(), &st) != 0 ? std::string(std::strerror(errno))
              : !S_ISREG(st.st_mode)       ? std::string("not a regular file")
                                           : "larger than " + std::to_string(kMaxBytes) + " bytes") +
             ")";
    return false;
  }
  std::ifstream in(path);
  if (!in) {
    *error = "cannot open pose script '" + Shown(path) + "'";
    return false;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return Parse(ss.str(), out, error);
}

bool PoseScript::Parse(const std::string& text, PoseScript* out, std::string* error) {
  PoseScript script;
  std::istringstream lines(text);
  std::string line;
  int lineNo = 0;
  while (std::getline(lines, line)) {
    ++lineNo;
    if (auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::string first;
    if (!(ls >> first)) continue;
    auto fail = [&](const std::string& why) {
      *error = "pose script line " + std::to_string(lineNo) + ": " + why;
      return false;
    };
    if (first == "loop") {
      if (!(ls >> script.m_loopSeconds) || !std::isfinite(script.m_loopSeconds) || script.m_loopSeconds <= 0)
        return fail("'loop' needs a period > 0 s");
      continue;
    }
    Key key;
    std::string device;
    try {
      key.time = std::stod(first);
    } catch (...) {
      return fail("expected a time in seconds, got '" + Shown(first) + "'");
    }
    if (!std::isfinite(key.time) || key.time < 0.0) return fail("the time must be a finite number of seconds from 0");
    Pose& p = key.sample.pose;
    if (!(ls >> device >> p.position.x >> p.position.y >> p.position.z >> p.orientation.x >> p.orientation.y >>
          p.orientation.z >> p.orientation.w))
      return fail("expected <time> <head|left|right> px py pz qx qy qz qw");
    int index = device == "head" ? 0 : device == "left" ? 1 : device == "right" ? 2 : -1;
    if (index < 0) return fail("unknown device '" + Shown(device) + "' (head, left or right)");
    for (float c : {p.position.x, p.position.y, p.position.z}) {
      if (!std::isfinite(c) || std::fabs(c) > 1e4f) return fail("a position must be finite, within 10 km");
    }
    float qn = std::sqrt(p.orientation.x * p.orientation.x + p.orientation.y * p.orientation.y +
                         p.orientation.z * p.orientation.z + p.orientation.w * p.orientation.w);
    if (!(std::fabs(qn - 1.0f) <= 1e-3f)) return fail("orientation is not a unit quaternion");
    p.orientation = Normalized(p.orientation);
    std::string kv;
    while (ls >> kv) {
      auto eq = kv.find('=');
      if (eq == std::string::npos) return fail("expected key=value, got '" + Shown(kv) + "'");
      std::string k = kv.substr(0, eq);
      float v = 0;
      try {
        v = std::stof(kv.substr(eq + 1));
      } catch (...) {
        return fail("bad value in '" + Shown(kv) + "'");
      }
      if (!std::isfinite(v) || ((k == "trigger" || k == "squeeze") && (v < 0.0f || v > 1.0f)))
        return fail("'" + Shown(kv) + "': a value from 0 to 1 (trigger, squeeze) or a finite number");
      DeviceSample& s = key.sample;
      if (k == "trigger") s.trigger = v;
      else if (k == "squeeze") s.squeeze = v;
      else if (k == "menu") s.menu = v != 0;
      else if (k == "a" || k == "x") s.a = v != 0;
      else if (k == "b" || k == "y") s.b = v != 0;
      else if (k == "trackpad") s.trackpad = v != 0;
      else if (k == "thumbstick") s.thumbstick = v != 0;
      else if (k == "tracked") s.tracked = v != 0;
      else
        return fail("unknown key '" + Shown(k) + "'");
    }
    auto& keys = script.m_keys[index];
    if (!keys.empty() && key.time < keys.back().time) return fail("times of one device must not decrease");
    keys.push_back(key);
  }
  *out = std::move(script);
  return true;
}

DeviceSample PoseScript::Sample(Device device, double seconds) const {
  const auto& keys = m_keys[int(device)];
  if (keys.empty()) return DefaultSample(device, seconds);
  double t = seconds;
  if (m_loopSeconds > 0) t = std::fmod(std::max(0.0, t), m_loopSeconds);
  if (t <= keys.front().time) return keys.front().sample;
  if (t >= keys.back().time) return keys.back().sample;
  size_t i = 1;
  while (keys[i].time < t) ++i;
  const Key& a = keys[i - 1];
  const Key& b = keys[i];
  float f = b.time > a.time ? float((t - a.time) / (b.time - a.time)) : 1.0f;
  DeviceSample s = a.sample;
  s.pose.position = a.sample.pose.position + (b.sample.pose.position - a.sample.pose.position) * f;
  s.pose.orientation = Slerp(a.sample.pose.orientation, b.sample.pose.orientation, f);
  return s;
}

}  // namespace sphxr::xr::simrt
