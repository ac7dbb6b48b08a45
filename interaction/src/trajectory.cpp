#include "sphxr/interaction/trajectory.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "pose_math.h"
#include "sphxr/common/log.h"
#include "sphxr/common/text_file.h"

namespace sphxr::interaction {
namespace {

// Splits a CSV line on commas; fields are trimmed.
std::vector<std::string> Fields(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::stringstream ss(line);
  while (std::getline(ss, field, ',')) {
    const size_t a = field.find_first_not_of(" \t\r");
    const size_t b = field.find_last_not_of(" \t\r");
    out.push_back(a == std::string::npos ? std::string() : field.substr(a, b - a + 1));
  }
  return out;
}

bool ToDouble(const std::string& text, double* v) {
  if (text.empty()) return false;
  char* end = nullptr;
  *v = std::strtod(text.c_str(), &end);
  return *end == '\0' && std::isfinite(*v);
}

constexpr double kMaxTime = 1e9;        // s: the solver's clock limit (32 years)
constexpr double kMaxCoordinate = 1e6;  // m, and the other columns: far past any tank, well inside a float

// A field quoted in a message: at most 80 characters, control characters shown as '?'.
std::string Shown(const std::string& field) {
  std::string out = field.size() > 80 ? field.substr(0, 77) + "..." : field;
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  }
  return out;
}

}  // namespace

Status Trajectory::FromKeys(std::vector<TrajectoryKey> keys, Trajectory* out) {
  if (keys.empty()) return Status::Error("trajectory: no keys");
  for (size_t k = 0; k < keys.size(); ++k) {
    if (k > 0 && !(keys[k].time > keys[k - 1].time)) {
      return Status::Error(Format("trajectory: key %zu: time %g is not after the previous key's %g", k, keys[k].time,
                                  keys[k - 1].time));
    }
    keys[k].pose.orientation = Normalized(keys[k].pose.orientation);
    keys[k].trigger = std::fmin(std::fmax(keys[k].trigger, 0.0f), 1.0f);
    keys[k].grip = std::fmin(std::fmax(keys[k].grip, 0.0f), 1.0f);
  }
  out->m_keys = std::move(keys);
  return Status::Ok();
}

Status Trajectory::Parse(const std::string& text, const std::string& origin, Trajectory* out) {
  std::vector<TrajectoryKey> keys;
  std::stringstream in(text);
  std::string line;
  int lineNumber = 0;
  bool first = true;
  while (std::getline(in, line)) {
    ++lineNumber;
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    const std::vector<std::string> f = Fields(line);
    double v[11];
    const bool header = first && !ToDouble(f[0], &v[0]);
    first = false;
    if (header) continue;
    const size_t n = f.size();
    if (n != 4 && n != 8 && n != 9 && n != 11) {
      return Status::Error(Format("%s:%d: %zu columns; expected 4 (time, position), 8 (+ quaternion w x y z), 9 "
                                  "(+ tracked) or 11 (+ trigger, grip)",
                                  origin.c_str(), lineNumber, n));
    }
    for (size_t c = 0; c < n; ++c) {
      if (!ToDouble(f[c], &v[c])) {
        return Status::Error(Format("%s:%d: column %zu '%s' is not a finite number", origin.c_str(), lineNumber, c + 1,
                                    Shown(f[c]).c_str()));
      }
      // Within what a float holds and a clock runs: 1e300 (and 3e38, which the pose arithmetic
      // overflows) ended in "non-finite target for body 0" with no file or line.
      const double limit = c == 0 ? kMaxTime : kMaxCoordinate;
      if (std::fabs(v[c]) > limit) {
        return Status::Error(Format("%s:%d: column %zu is %.3g; %s must be within +-%g %s", origin.c_str(), lineNumber,
                                    c + 1, v[c], c == 0 ? "a time" : c < 4 ? "a position" : "this column", limit,
                                    c == 0 ? "s" : c < 4 ? "m" : ""));
      }
    }
    TrajectoryKey key;
    key.time = v[0];
    key.pose.position = sim::Vec3{static_cast<float>(v[1]), static_cast<float>(v[2]), static_cast<float>(v[3])};
    if (n >= 8) {
      const double norm = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
      if (norm < 1e-6) return Status::Error(Format("%s:%d: the quaternion is zero", origin.c_str(), lineNumber));
      key.pose.orientation = Quat{static_cast<float>(v[4]), static_cast<float>(v[5]), static_cast<float>(v[6]),
                                  static_cast<float>(v[7])};
    }
    if (n >= 9) {
      if (v[8] != 0.0 && v[8] != 1.0) return Status::Error(Format("%s:%d: tracked must be 0 or 1", origin.c_str(), lineNumber));
      key.tracked = v[8] == 1.0;
    }
    if (n == 11) {
      key.trigger = static_cast<float>(v[9]);
      key.grip = static_cast<float>(v[10]);
    }
    if (!keys.empty() && !(key.time > keys.back().time)) {
      return Status::Error(Format("%s:%d: time %g is not after the previous key's %g (times must increase)",
                                  origin.c_str(), lineNumber, key.time, keys.back().time));
    }
    keys.push_back(key);
  }
  if (keys.empty()) return Status::Error(origin + ": no keys (a trajectory needs at least one timed pose)");
  return FromKeys(std::move(keys), out);
}

Status Trajectory::Load(const std::string& path, Trajectory* out) {
  // 256 MiB: hours of a recorded hand at 90 Hz.
  std::string text;
  if (Status s = ReadTextFile(path, "trajectory file", size_t{256} << 20, &text); !s) return s;
  return Parse(text, path, out);
}

HandInput Trajectory::Sample(double time) const {
  HandInput hand;
  hand.time = time;
  double t = time;
  const double first = m_keys.front().time, last = m_keys.back().time;
  if (m_loop && last > first) t = first + std::fmod(std::fmod(t - first, last - first) + (last - first), last - first);
  size_t k = 0;
  while (k + 1 < m_keys.size() && m_keys[k + 1].time <= t) ++k;
  const TrajectoryKey& a = m_keys[k];
  if (t <= first || k + 1 == m_keys.size()) {
    hand.tracked = a.tracked;
    hand.pose = a.pose;
    hand.trigger = a.trigger;
    hand.grip = a.grip;
    return hand;
  }
  const TrajectoryKey& b = m_keys[k + 1];
  const float u = static_cast<float>((t - a.time) / (b.time - a.time));
  hand.tracked = a.tracked && b.tracked;
  hand.pose = Interpolate(a.pose, b.pose, u);
  hand.trigger = a.trigger + (b.trigger - a.trigger) * u;
  hand.grip = a.grip + (b.grip - a.grip) * u;
  return hand;
}

}  // namespace sphxr::interaction
