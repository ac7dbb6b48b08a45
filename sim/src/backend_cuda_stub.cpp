// Linked instead of backend_cuda.cu when the CUDA backend is not built.
#include "backend.h"

namespace sphxr::sim {

std::unique_ptr<Backend> MakeCudaBackend(std::string* why) {
  if (why) *why = "this sphxr was built without the CUDA backend (configure with -DSPHXR_CUDA=ON and a CUDA toolkit)";
  return nullptr;
}
int CudaDevices() { return 0; }
bool CudaCompiled() { return false; }

}  // namespace sphxr::sim
