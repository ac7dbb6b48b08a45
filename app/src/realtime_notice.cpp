#include "realtime_notice.h"

#include <utility>

#include "sphxr/common/log.h"

namespace sphxr::app {

RealTimeNotice::RealTimeNotice(std::string scene, int particles, std::string method, std::string device, int threads)
    : m_scene(std::move(scene)), m_method(std::move(method)), m_device(std::move(device)), m_particles(particles),
      m_threads(threads) {}

std::optional<std::string> RealTimeNotice::Observe(double simPerWall, double wallSinceStart) {
  if (m_decided || !(wallSinceStart >= kSettleSeconds)) return std::nullopt;
  m_decided = true;
  if (!(simPerWall < kThreshold)) return std::nullopt;
  const std::string threads = m_device == "cuda" ? "" : Format(", %d threads", m_threads);
  return Format("%s: this machine keeps %.2f of real time (%d particles, %s on %s%s): the water moves slowed "
                "down; --quality auto picks a spacing that keeps real time%s",
                m_scene.c_str(), simPerWall, m_particles, m_method.c_str(), m_device.c_str(), threads.c_str(),
                m_device == "cuda" ? "" : ", or run it on a GPU (--device cuda)");
}

}  // namespace sphxr::app
