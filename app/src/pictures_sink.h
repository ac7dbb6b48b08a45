#pragma once
// `--frames DIR` and `--screenshot FILE.png`, a sink of the Simulation (simulation.h): pictures drawn
// without a display (EGL).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "sphxr/app/headless.h"
#include "sphxr/app/options.h"
#include "sphxr/app/pictures.h"
#include "sphxr/app/simulation.h"
#include "sphxr/sim/surface.h"

namespace sphxr::app {

/// --frames DIR (a PNG every 1/fps simulated s, then DIR/movie.mp4 when ffmpeg is on the PATH) and
/// --screenshot FILE.png (the last state). The GL context is made by Create, before the run, so a
/// machine without EGL fails in a second.
class PicturesSink : public SimulationSink {
 public:
  static Status Create(const Options& options, std::optional<sim::SurfaceParams> surface, RunSummary* summary,
                       std::unique_ptr<PicturesSink>* out);
  Status OnStart(Simulation& simulation) override;
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  /// The movie and the screenshot.
  Status Finish(Simulation& simulation, bool interrupted) override;
  /// DIR/movie.mp4 when Finish made it, else empty.
  const std::string& Movie() const { return m_movie; }

 private:
  PicturesSink(const Options& options, std::optional<sim::SurfaceParams> surface, RunSummary* summary)
      : m_options(options), m_surface(surface), m_summary(summary) {}
  Status Picture(Simulation& simulation, const std::string& path);
  Status DueFrames(Simulation& simulation);

  const Options& m_options;
  std::optional<sim::SurfaceParams> m_surface;
  RunSummary* m_summary;
  std::unique_ptr<OfflinePictures> m_pictures;
  SimSnapshot m_snap;
  int64_t m_frameIndex = 0;
  int64_t m_firstFrame = 0;
  std::string m_movie;
};

}  // namespace sphxr::app
