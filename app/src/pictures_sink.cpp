#include "pictures_sink.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "output_files.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace sphxr::app {

Status PicturesSink::Create(const Options& options, std::optional<sim::SurfaceParams> surface, RunSummary* summary,
                            std::unique_ptr<PicturesSink>* out) {
  std::unique_ptr<PicturesSink> sink(new PicturesSink(options, surface, summary));
  if (!options.framesDir.empty()) {
    if (Status s = MakeOutputDirectory("--frames", options.framesDir); !s) return s;
  }
  render::RenderQuality quality = render::RenderQuality::kHigh;
  render::ParseRenderQuality(options.renderQuality, &quality);
  if (Status s = OfflinePictures::Create(options.imageWidth, options.imageHeight, &sink->m_pictures, options.glDebug, quality);
      !s) {
    return Status::Error("--screenshot/--frames: " + s.message());
  }
  *out = std::move(sink);
  return Status::Ok();
}

// A picture is drawn from a snapshot, as in the window: in water mode from the extracted surface mesh
// (the scene's "surface" section), with the paddles at their poses.
Status PicturesSink::Picture(Simulation& simulation, const std::string& path) {
  const render::RenderMode mode = m_options.particleImages ? render::RenderMode::kParticles : render::RenderMode::kWater;
  SurfaceRequest surface;
  surface.enabled = mode == render::RenderMode::kWater;
  surface.params = m_surface.value_or(sim::SurfaceParams{});
  if (Status s = CaptureSnapshot(simulation.Solver(), simulation.Paddles(), surface, &m_snap); !s) {
    return Status::Error("picture: " + s.message());
  }
  m_snap.setup = simulation.Setup();
  return m_pictures->Write(MakeFrameScene(m_snap, mode), path);
}

Status PicturesSink::DueFrames(Simulation& simulation) {
  if (m_options.framesDir.empty()) return Status::Ok();
  while (simulation.Solver().Time() >= static_cast<double>(m_frameIndex) / m_options.fps - 1e-9) {
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%05lld.png", static_cast<long long>(m_frameIndex));
    const std::string path = (std::filesystem::path(m_options.framesDir) / name).string();
    if (Status s = Picture(simulation, path); !s) return s;
    ++m_summary->frames;
    ++m_frameIndex;
  }
  return Status::Ok();
}

Status PicturesSink::OnStart(Simulation& simulation) {
  // Frame k shows the state after the first step at or past t = k / fps. A run from a state file goes on
  // with the first frame after the state's time (the earlier run drew those up to it), so continued
  // runs number and draw their frames as the whole run does.
  const double start = m_summary->startTime;
  if (start > 0.0) {
    m_frameIndex = static_cast<int64_t>(std::floor(start * m_options.fps));
    while (static_cast<double>(m_frameIndex) / m_options.fps - 1e-9 <= start) ++m_frameIndex;
  }
  m_firstFrame = m_frameIndex;
  return DueFrames(simulation);
}

Status PicturesSink::OnStep(Simulation& simulation, const sim::StepInfo&) { return DueFrames(simulation); }

Status PicturesSink::Finish(Simulation& simulation, bool) {
  if (m_summary->frames > 0) {
    const std::string ffmpeg = FindOnPath("ffmpeg");
    if (ffmpeg.empty()) {
      SPHXR_LOG_INFO("ffmpeg is not on the PATH: the frames stay a PNG sequence");
    } else {
      m_movie = (std::filesystem::path(m_options.framesDir) / "movie.mp4").string();
      // From the earliest frame of the unbroken sequence ending in this run's: a run continued into its
      // first run's directory makes the whole run's movie.
      int64_t movieStart = m_firstFrame;
      while (movieStart > 0) {
        char name[64];
        std::snprintf(name, sizeof(name), "frame_%05lld.png", static_cast<long long>(movieStart - 1));
        std::error_code ec;
        if (!std::filesystem::is_regular_file(std::filesystem::path(m_options.framesDir) / name, ec)) break;
        --movieStart;
      }
      // ... and ending at this run's last frame (not at older, higher-numbered files in the directory).
      const std::string command = Format("'%s' -y -loglevel error -framerate %g -start_number %lld -i '%s/frame_%%05d.png' "
                                         "-frames:v %lld -pix_fmt yuv420p -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' '%s'",
                                         ffmpeg.c_str(), m_options.fps, static_cast<long long>(movieStart),
                                         m_options.framesDir.c_str(), static_cast<long long>(m_frameIndex - movieStart),
                                         m_movie.c_str());
      if (std::system(command.c_str()) != 0) {
        SPHXR_LOG_WARN("ffmpeg could not make %s; the PNG frames are there", m_movie.c_str());
        m_movie.clear();
      }
    }
  }
  if (!m_options.screenshotPath.empty()) {
    if (Status s = Picture(simulation, m_options.screenshotPath); !s) return s;
  }
  return Status::Ok();
}

}  // namespace sphxr::app
