#pragma once
// What the window and the headset spend on drawing, and how they give it back when the frame does not
// fit: the render quality (render::RenderQuality: shadow resolution, spray and foam) starts where the
// command line puts it (--render-quality, default high) and, under --quality auto, is lowered one level
// when the frames of a window of frames take longer than the display period. It is never raised again
// in a run (a level that did not fit once would be tried and dropped over and over).
#include <cstdio>
#include <string>
#include <vector>

#include "sphxr/common/status.h"
#include "sphxr/render/renderer.h"

namespace sphxr::app {

class RenderBudget {
 public:
  /// `adaptive`: lower the quality when frames do not fit (--quality auto).
  RenderBudget(render::RenderQuality start, bool adaptive) : m_quality(start), m_adaptive(adaptive) {}

  /// Frames judged together: the median of this many intervals decides.
  static constexpr int kWindow = 45;
  /// A frame fits when it takes at most this much of the display period.
  static constexpr double kHeadroom = 1.1;

  /// After each displayed frame: its interval and the display period (ms). True when the quality was
  /// lowered just now (Quality() is the new level; the caller hands it to the renderer and logs Why()).
  bool Observe(double frameMs, double periodMs);
  render::RenderQuality Quality() const { return m_quality; }
  const std::string& Why() const { return m_why; }

 private:
  render::RenderQuality m_quality;
  bool m_adaptive;
  std::vector<double> m_frames;
  std::string m_why;
};

/// "render quality high; GPU per eye (ms): shadow 0.41, sky 0.12, ..." for a summary.
std::string RenderSummary(render::RenderQuality quality, const render::DrawStats& stats);

/// --frame-stats in the window and the headset: one CSV row per displayed frame (the frame, its interval, the
/// render quality, and the GPU time of each pass, GL_TIME_ELAPSED, summed over the frame's views). A row
/// is written whole or not at all; a write that fails stops the file with one line.
class FrameStatsCsv {
 public:
  FrameStatsCsv() = default;
  ~FrameStatsCsv();
  FrameStatsCsv(const FrameStatsCsv&) = delete;
  FrameStatsCsv& operator=(const FrameStatsCsv&) = delete;
  /// Opens (truncates) `path`; one line naming the file when it cannot.
  Status Open(const std::string& path);
  bool IsOpen() const { return m_file != nullptr; }
  /// Writes one frame's row; the columns are fixed by the first row's passes (later passes are added
  /// to no column; a pass missing from a row is written empty).
  Status Append(int64_t frame, double intervalMs, render::RenderQuality quality, const render::DrawStats& stats);

 private:
  FILE* m_file = nullptr;
  std::string m_path;
  std::vector<std::string> m_columns;
};

}  // namespace sphxr::app
