// What the OpenMP runtime of this process was told about waiting (openmp_wait.h).
#include "sphxr/sim/openmp_wait.h"

#include <omp.h>
#include <pthread.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "sphxr/common/log.h"

namespace sphxr::sim {

const char* OpenMpWaitSetting() {
  static const std::string setting = [] {
    for (const char* name : {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "KMP_BLOCKTIME"}) {
      const char* v = std::getenv(name);
      if (v != nullptr && *v != '\0') return std::string(name) + "=" + v + ", set by the user";
    }
    return std::string("the runtime's default");
  }();
  return setting.c_str();
}

int MaxSolverThreads() { return std::max(64, 4 * omp_get_num_procs()); }

Status CheckThreadsCanStart(int threads, const std::string& what) {
  // Each probe thread waits until all are started, so that they exist at once, as an OpenMP team
  // does; a small stack each (the team's own stacks are the runtime's).
  if (threads <= 0) threads = omp_get_num_procs();
  const int extra = threads - 1;
  if (extra <= 0) return Status::Ok();
  std::vector<pthread_t> started;
  started.reserve(static_cast<size_t>(extra));
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, 64 * 1024);
  int error = 0;
  struct Gate {
    pthread_mutex_t mutex = PTHREAD_MUTEX_INITIALIZER;
    pthread_cond_t open = PTHREAD_COND_INITIALIZER;
    bool released = false;
  } gate;
  auto wait = [](void* arg) -> void* {
    Gate* g = static_cast<Gate*>(arg);
    pthread_mutex_lock(&g->mutex);
    while (!g->released) pthread_cond_wait(&g->open, &g->mutex);
    pthread_mutex_unlock(&g->mutex);
    return nullptr;
  };
  for (int k = 0; k < extra; ++k) {
    pthread_t t;
    error = pthread_create(&t, &attr, wait, &gate);
    if (error != 0) break;
    started.push_back(t);
  }
  pthread_attr_destroy(&attr);
  pthread_mutex_lock(&gate.mutex);
  gate.released = true;
  pthread_cond_broadcast(&gate.open);
  pthread_mutex_unlock(&gate.mutex);
  for (pthread_t t : started) pthread_join(t, nullptr);
  if (error == 0) return Status::Ok();
  return Status::Error(
      Format("%s: this process cannot start %d threads (it started %zu more: %s; a limit on "
             "processes, ulimit -u?); give fewer threads",
             what.c_str(), threads, started.size(), std::strerror(error)));
}

}  // namespace sphxr::sim
