#pragma once
// Scripted hands: a file of timed poses replayed by time (tests, headless runs, benchmarks).
//
// Format (CSV, one key per line; '#' starts a comment line; blank lines are skipped; a first line that
// does not start with a number is a header and skipped):
//
//   time, px, py, pz [, qw, qx, qy, qz [, tracked [, trigger, grip]]]
//
// time in s, strictly increasing; position in m (world); orientation a quaternion (normalised on load;
// identity when absent); tracked 1 or 0 (default 1); trigger and grip 0..1 (default 0). Between two
// keys the pose is interpolated (position linear, rotation slerp); the hand is untracked between a key
// and the next whenever either of them is untracked. Before the first key the first pose holds, after
// the last key the last (or, looping, the trajectory repeats with the period last time - first time).
#include <string>
#include <vector>

#include "sphxr/common/status.h"
#include "sphxr/interaction/hand.h"

namespace sphxr::interaction {

struct TrajectoryKey {
  double time = 0.0;
  Pose pose;
  bool tracked = true;
  float trigger = 0.0f, grip = 0.0f;
};

class Trajectory {
 public:
  /// Parses CSV text (`origin` names it in messages: "file.csv:12: ...").
  static Status Parse(const std::string& text, const std::string& origin, Trajectory* out);
  static Status Load(const std::string& path, Trajectory* out);
  /// From keys built in code (same checks as the file).
  static Status FromKeys(std::vector<TrajectoryKey> keys, Trajectory* out);

  void SetLoop(bool loop) { m_loop = loop; }
  bool Loop() const { return m_loop; }
  double StartTime() const { return m_keys.front().time; }
  double EndTime() const { return m_keys.back().time; }
  const std::vector<TrajectoryKey>& Keys() const { return m_keys; }

  /// The hand at `time` (hasVelocity false: the paddle derives its velocity from the poses).
  HandInput Sample(double time) const;

 private:
  std::vector<TrajectoryKey> m_keys;
  bool m_loop = false;
};

}  // namespace sphxr::interaction
