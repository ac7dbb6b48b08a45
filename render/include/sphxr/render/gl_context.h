#pragma once
// OpenGL without a window: an EGL surfaceless context (Mesa's EGL_PLATFORM_SURFACELESS_MESA, or the
// default display when that platform is missing) and an offscreen framebuffer to draw into and read
// back. Used by headless runs (--screenshot, --frames) and by the tests.
#include <cstdint>
#include <memory>
#include <vector>

#include "sphxr/common/status.h"

namespace sphxr::render {

class HeadlessContext {
 public:
  /// Creates a GL 4.5 core context and makes it current on this thread. `debug` asks for a debug
  /// context (KHR_debug output on). Fails with one clear line when EGL or GL 4.5 is missing.
  static Status Create(bool debug, std::unique_ptr<HeadlessContext>* out);
  ~HeadlessContext();
  HeadlessContext(const HeadlessContext&) = delete;
  HeadlessContext& operator=(const HeadlessContext&) = delete;
  void MakeCurrent();

 private:
  HeadlessContext() = default;
  void* m_display = nullptr;
  void* m_context = nullptr;
};

/// RGBA8 pixels, rows bottom-up as OpenGL reads them unless `topDown`.
struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
  const uint8_t* At(int x, int y) const { return &rgba[4 * (static_cast<size_t>(y) * width + x)]; }
  /// Flips rows in place (GL's bottom-up to a file's top-down).
  void FlipRows();
};

/// A framebuffer object with an RGBA8 colour and a depth attachment (needs a current context).
class OffscreenTarget {
 public:
  static Status Create(int width, int height, std::unique_ptr<OffscreenTarget>* out);
  ~OffscreenTarget();
  uint32_t Framebuffer() const { return m_fbo; }
  int Width() const { return m_width; }
  int Height() const { return m_height; }
  /// Reads the colour attachment (rows bottom-up).
  Image Read() const;
  /// Reads the depth attachment as window depths in [0, 1] (rows bottom-up).
  std::vector<float> ReadDepth() const;

 private:
  OffscreenTarget() = default;
  uint32_t m_fbo = 0, m_color = 0, m_depth = 0;
  int m_width = 0, m_height = 0;
};

/// Reads the currently bound read framebuffer's region (rows bottom-up).
Image ReadPixels(uint32_t framebuffer, int x, int y, int width, int height);

/// "4.5 (Core Profile) Mesa 22.3.6, llvmpipe" style one-liner of the current context.
const char* GlDescription();

}  // namespace sphxr::render
