#pragma once
// The backends' boundary for exceptions. thrust reports a failed CUDA call or allocation by throwing
// (thrust::system_error, std::bad_alloc), but nothing throws across a module (STYLE.md): the entries of
// a backend that return a Status run their work through GuardBackend, which turns an exception into one
// line for the user naming the backend and the stage.
#include <exception>
#include <new>

#include "sphxr/common/log.h"
#include "sphxr/common/status.h"

namespace sphxr::sim {

/// Runs `work` (returning Status). `what` names the work; `*lastStage`, when given, the last stage that
/// finished before the exception (the failed launch is in the stage after it).
template <class F>
Status GuardBackend(const char* backend, const char* what, const F& work, const char* const* lastStage = nullptr) {
  const auto where = [&]() -> std::string {
    std::string w = what;
    if (lastStage) w += *lastStage ? std::string(" (after the ") + *lastStage + " stage)" : " (in its first stage)";
    return w;
  };
  try {
    return work();
  } catch (const std::bad_alloc&) {
    return Status::Error(Format("%s backend: out of memory in %s: use a smaller scene (fewer particles or a "
                                "larger spacing)", backend, where().c_str()));
  } catch (const std::exception& e) {  // thrust::system_error (a CUDA error) is a std::runtime_error
    return Status::Error(Format("%s backend: %s failed: %s", backend, where().c_str(), e.what()));
  }
}

}  // namespace sphxr::sim
