#pragma once
#include <thrust/memory.h>

namespace sphxr::sim {

/// The raw pointer to a thrust vector's elements (host or device; const stays const), for the stages'
/// plain views. Shared by the stores, the solvers and the surface.
template <class V>
auto Raw(V& v) {
  return thrust::raw_pointer_cast(v.data());
}

}  // namespace sphxr::sim
