#pragma once
// Scripted devices of the simulated headset: the head and two controllers, as timed key frames read
// from a text file, or the default motion (head looking at the tank, right controller stirring).
//
// File format, one key frame per line ('#' starts a comment):
//   <time_s> <head|left|right> <px> <py> <pz> <qx> <qy> <qz> <qw> [trigger=F] [squeeze=F] [menu=0|1]
//                                                                  [a=0|1] [b=0|1] [trackpad=0|1]
//                                                                  [thumbstick=0|1] [tracked=0|1]
// (trackpad and thumbstick: their clicks, the Vive's and the WMR controller's.)
// Poses are in the STAGE space (metres, +y up, -z forward). Between key frames of one device the
// position is interpolated linearly, the orientation by slerp; buttons and values hold the earlier
// key frame's value. Before the first / after the last key frame the device holds that frame. A
// device with no key frame keeps its default motion. `loop <seconds>` on its own line repeats the
// script with that period.
#include <cstdio>
#include <string>
#include <vector>

#include "sphxr/xr/math.h"

namespace sphxr::xr::simrt {

enum class Device { kHead = 0, kLeft = 1, kRight = 2 };
constexpr int kDeviceCount = 3;

struct DeviceSample {
  Pose pose;
  float trigger = 0, squeeze = 0;
  bool menu = false, a = false, b = false, trackpad = false, thumbstick = false;  // clicks
  bool tracked = true;
};

/// `text` for a message: bytes outside printable ASCII as \xNN, cut after 80 (a setting or a script
/// may hold anything).
inline std::string Shown(const std::string& text) {
  std::string out;
  for (const unsigned char c : text) {
    if (out.size() >= 80) return out + "... (" + std::to_string(text.size()) + " bytes)";
    if (c < 0x20 || c >= 0x7F) {
      char escape[8];
      std::snprintf(escape, sizeof escape, "\\x%02X", c);
      out += escape;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

class PoseScript {
 public:
  /// The largest pose script read (SPHXR_SIM_XR_POSES), in bytes.
  static constexpr long kMaxBytes = 16L << 20;
  /// The default motion: head at (0, 1.6, 0.5) looking 30 degrees down at a tank centred near
  /// (0, 1.0, -0.4); left controller held still; right controller circling (radius 0.1 m, 0.5 Hz)
  /// at (0.1, 1.0, -0.4) with its grip pointing down, trigger at 0.8.
  static PoseScript Default();
  /// Parses a script file; on error returns false with a one-line message naming the line.
  static bool Load(const std::string& path, PoseScript* out, std::string* error);
  static bool Parse(const std::string& text, PoseScript* out, std::string* error);

  DeviceSample Sample(Device device, double seconds) const;

 private:
  struct Key {
    double time;
    DeviceSample sample;
  };
  std::vector<Key> m_keys[kDeviceCount];
  double m_loopSeconds = 0;
};

}  // namespace sphxr::xr::simrt
