#include "pass_timer.h"

#include <algorithm>
#include <chrono>

namespace sphxr::render {

namespace {
double NowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

PassTimer::~PassTimer() {
  for (Frame& f : m_frames) {
    for (const Query& q : f.queries) {
      if (q.id) glDeleteQueries(1, &q.id);
    }
  }
  if (!m_free.empty()) glDeleteQueries(static_cast<GLsizei>(m_free.size()), m_free.data());
}

int PassTimer::NameIndex(const char* name) {
  const auto it = std::find(m_names.begin(), m_names.end(), name);
  if (it != m_names.end()) return static_cast<int>(it - m_names.begin());
  m_names.emplace_back(name);
  return static_cast<int>(m_names.size()) - 1;
}

GLuint PassTimer::TakeQuery() {
  if (m_free.empty()) {
    GLuint q = 0;
    glCreateQueries(GL_TIME_ELAPSED, 1, &q);
    return q;
  }
  const GLuint q = m_free.back();
  m_free.pop_back();
  return q;
}

PassTimer::Scope::Scope(PassTimer* timer, const char* name) : m_timer(timer) {
  Frame& f = timer->m_frames[static_cast<size_t>(timer->m_current)];
  if (timer->m_finishEachPass) {
    glFinish();
    f.queries.push_back({timer->NameIndex(name), 0, 0.0});
    m_started = NowSeconds();
    return;
  }
  const GLuint q = timer->TakeQuery();
  f.queries.push_back({timer->NameIndex(name), q, 0.0});
  glBeginQuery(GL_TIME_ELAPSED, q);
}

PassTimer::Scope::~Scope() {
  if (m_timer->m_finishEachPass) {
    glFinish();
    m_timer->m_frames[static_cast<size_t>(m_timer->m_current)].queries.back().ms = 1e3 * (NowSeconds() - m_started);
    return;
  }
  glEndQuery(GL_TIME_ELAPSED);
}

bool PassTimer::Collect(Frame* f, bool wait, DrawStats* stats) {
  if (!f->pending) return false;
  if (!wait && !f->queries.empty() && f->queries.back().id) {
    GLuint available = 0;
    glGetQueryObjectuiv(f->queries.back().id, GL_QUERY_RESULT_AVAILABLE, &available);
    if (!available) return false;
  }
  stats->passes.clear();
  for (const Query& q : f->queries) {
    GLuint64 ns = static_cast<GLuint64>(q.ms * 1e6);
    if (q.id) glGetQueryObjectui64v(q.id, GL_QUERY_RESULT, &ns);
    const std::string& name = m_names[static_cast<size_t>(q.name)];
    auto it = std::find_if(stats->passes.begin(), stats->passes.end(), [&](const PassTime& p) { return p.name == name; });
    if (it == stats->passes.end()) {
      stats->passes.push_back({name, 0.0});
      it = stats->passes.end() - 1;
    }
    it->gpuMs += static_cast<double>(ns) * 1e-6;
    if (q.id) m_free.push_back(q.id);
  }
  stats->views = f->views;
  f->queries.clear();
  f->pending = false;
  return true;
}

void PassTimer::BeginFrame() {
  // The slot this frame reuses must be read first; it is the oldest, normally done long ago.
  Frame& f = m_frames[static_cast<size_t>(m_current)];
  Collect(&f, /*wait=*/true, &m_latest);
  m_open = true;
}

void PassTimer::EndFrame(int views, DrawStats* stats) {
  if (!m_open) return;
  m_open = false;
  Frame& f = m_frames[static_cast<size_t>(m_current)];
  f.views = views;
  f.pending = true;
  m_current = (m_current + 1) % static_cast<int>(m_frames.size());
  // The newest frame whose results are in, oldest first so that the newest wins.
  for (size_t k = 1; k < m_frames.size(); ++k) {
    Frame& older = m_frames[(static_cast<size_t>(m_current) + k - 1) % m_frames.size()];
    Collect(&older, /*wait=*/false, &m_latest);
  }
  stats->passes = m_latest.passes;
  stats->views = m_latest.views;
}

}  // namespace sphxr::render
