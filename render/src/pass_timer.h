#pragma once
// GPU time per pass from GL_TIME_ELAPSED queries, read a frame or two late so that reading never waits
// for the GPU. Passes of the same name in one frame (one per view) are summed. With `finishEachPass`
// (RendererConfig::finishEachPass, the benchmarks) each pass is finished before and after and timed on
// the clock instead: exact on a software rasteriser, which draws binned commands whenever it flushes,
// so that a query can hold another pass's work.
#include <epoxy/gl.h>

#include <array>
#include <string>
#include <vector>

#include "sphxr/render/renderer.h"

namespace sphxr::render {

class PassTimer {
 public:
  explicit PassTimer(bool finishEachPass = false) : m_finishEachPass(finishEachPass) {}
  ~PassTimer();
  PassTimer(const PassTimer&) = delete;
  PassTimer& operator=(const PassTimer&) = delete;

  /// Times the GL commands between construction and destruction under `name`.
  class Scope {
   public:
    Scope(PassTimer* timer, const char* name);
    ~Scope();
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    PassTimer* m_timer;
    double m_started = 0.0;  // s, with finishEachPass
  };

  void BeginFrame();
  /// Ends the frame of `views` views; `stats` gets the newest completed frame's pass times.
  void EndFrame(int views, DrawStats* stats);

 private:
  struct Query {
    int name = 0;  // index into m_names
    GLuint id = 0;  // 0: `ms` holds the time (finishEachPass)
    double ms = 0.0;
  };
  struct Frame {
    std::vector<Query> queries;
    int views = 0;
    bool pending = false;
  };
  int NameIndex(const char* name);
  GLuint TakeQuery();
  /// Reads `f` into `stats` when its results are there (or when `wait`), and recycles its queries.
  bool Collect(Frame* f, bool wait, DrawStats* stats);
  std::array<Frame, 3> m_frames;
  int m_current = 0;
  bool m_open = false;
  std::vector<std::string> m_names;
  std::vector<GLuint> m_free;
  DrawStats m_latest;
  bool m_finishEachPass = false;
};

}  // namespace sphxr::render
