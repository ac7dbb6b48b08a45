#pragma once
// SPHXR_HD marks functions compiled for both the host (CPU backend) and the device (CUDA backend).
#if defined(__CUDACC__)
#define SPHXR_HD __host__ __device__
#define SPHXR_INLINE __forceinline__
#else
#define SPHXR_HD
#define SPHXR_INLINE inline __attribute__((always_inline))
#endif
