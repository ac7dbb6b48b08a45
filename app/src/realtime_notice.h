#pragma once
// The line an interactive run (window, headset) logs once when this machine cannot keep its scene in
// real time: the water then moves slowed down, and the user should know why and what to change.
#include <optional>
#include <string>

namespace sphxr::app {

class RealTimeNotice {
 public:
  /// `what`: the scene's name, its particle count, method, backend and threads, as the line names them.
  RealTimeNotice(std::string scene, int particles, std::string method, std::string device, int threads);
  /// A rate window of the worker: simulated seconds per wall second over it, and the wall seconds since
  /// the run (or its last reset) began. The first window after kSettleSeconds decides: below kThreshold
  /// the line is returned (and logged by the caller), once; later windows return nothing.
  std::optional<std::string> Observe(double simPerWall, double wallSinceStart);
  /// A reset or a new scene: the next windows decide again.
  void Restart() { m_decided = false; }

  static constexpr double kSettleSeconds = 1.0;  // the first second holds the start-up's first frames
  static constexpr double kThreshold = 0.9;

 private:
  std::string m_scene, m_method, m_device;
  int m_particles, m_threads;
  bool m_decided = false;
};

}  // namespace sphxr::app
