#pragma once
// The counted device operations of one backend: every kernel launch, fill, sort, gather, reduction, scan,
// compaction, copy between host and device and vector growth of a step goes through here, and each one
// counts what it asks of the device (launch/counter.h, sphxr/sim/launch_counts.h). The stores, the
// launchers, the solvers and the post-step stages call these, never thrust directly
// (tests/sim/launch_layer_test.cpp holds the sources to that).
//
// The policy is `Traits::Policy(temporaries)`: on CUDA thrust::cuda::par_nosync on the backend's stream
// (no algorithm waits for the device unless its result goes to the host), on the CPU systems their
// parallel policy; on every system with the temporaries kept between steps (launch/temporaries.h).
//
// Counting: `Traits::kCountsAs` is CountModel::kCuda for the CUDA backend and cpu-reference (each
// algorithm counts the kernels it runs on CUDA, launch/kernels.h; a result read on the host is a copy
// back and a wait), CountModel::kCpu for the CPU backend (each algorithm or parallel loop is one
// launch; nothing waits, as the host is the device). On both, a grown vector and a new temporary
// block are allocations.
#include <thrust/copy.h>
#include <thrust/count.h>
#include <thrust/fill.h>
#include <thrust/for_each.h>
#include <thrust/gather.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/reduce.h>
#include <thrust/scan.h>
#include <thrust/sort.h>
#include <thrust/transform_reduce.h>

#include <cstddef>
#include <cstdint>

#include "sphxr/common/hd.h"

#include "launch/counter.h"
#include "launch/kernels.h"
#include "launch/temporaries.h"

namespace sphxr::sim {

enum class CountModel { kCuda, kCpu };

/// An exclusive scan's total: the last item's offset plus the last item (one work item).
struct ScanTotalStage {
  const uint32_t* in;
  const uint32_t* offsets;
  size_t last;
  uint32_t* total;
  SPHXR_HD void operator()(int) const { *total = offsets[last] + in[last]; }
};

template <class Traits>
class DeviceOps {
  static constexpr bool kCuda = Traits::kCountsAs == CountModel::kCuda;

 public:
  const LaunchCounts& Counts() const { return m_counter.Counts(); }
  LaunchCounter& Counter() { return m_counter; }
  auto Policy() { return Traits::Policy(m_temporaries); }

  /// f(i) for i in [0, n): one kernel.
  template <class F>
  void ForEach(int n, const F& f) {
    if (n <= 0) return;
    thrust::for_each_n(Policy(), thrust::counting_iterator<int>(0), n, f);
    Algorithm(kernels::kParallelFor);
  }
  template <class It, class T>
  void Fill(It first, It last, const T& value) {
    if (first == last) return;
    thrust::fill(Policy(), first, last, value);
    Algorithm(kernels::kParallelFor);
  }
  template <class V>
  void Fill(V& v, const typename V::value_type& value) {
    Fill(v.begin(), v.end(), value);
  }
  /// v.resize(n): a kernel for the new elements' values; above the capacity, an allocation, a kernel
  /// copying the old elements and the old storage's free (cudaFree waits for the device).
  template <class V>
  void Resize(V& v, size_t n) {
    const size_t size = v.size();
    const size_t capacity = v.capacity();
    if (n == size) return;
    v.resize(n);
    if (n < size) return;
    m_counter.Launch();
    if (n <= capacity) return;
    m_counter.Allocation();
    if constexpr (kCuda) {
      if (size > 0) m_counter.Launch();
      if (capacity > 0) m_counter.Sync();
    }
  }
  /// The stable sort of `values` by `keys` (radix sort of 32-bit keys on CUDA).
  template <class K, class V>
  void SortPairs(K& keys, V& values) {
    const auto n = static_cast<int64_t>(keys.size());
    thrust::stable_sort_by_key(Policy(), keys.begin(), keys.end(), values.begin());
    if (n > 1) Algorithm(kernels::SortPairs(n));
  }
  /// dst[k] = src[map[k]] for k in [0, last - first).
  template <class Map, class Src, class Dst>
  void Gather(Map first, Map last, Src src, Dst dst) {
    if (first == last) return;
    thrust::gather(Policy(), first, last, src, dst);
    Algorithm(kernels::kParallelFor);
  }
  /// combine over op(i), i in [0, n), read back to the host.
  template <class T, class Op, class Combine>
  T TransformReduce(int n, const Op& op, T init, const Combine& combine) {
    const thrust::counting_iterator<int> first(0);
    const T r = thrust::transform_reduce(Policy(), first, first + n, op, init, combine);
    Algorithm(kernels::Reduce(n));
    ReadBack();
    return r;
  }
  /// The sum of [first, first + n) written to `out` in device memory; nothing waits (CUB's
  /// DeviceReduce::Sum on CUDA, its temporaries kept).
  template <class It, class T>
  void SumInto(It first, int n, T* out) {
    Traits::SumInto(m_temporaries, first, n, out);
    Algorithm(kernels::Reduce(n));
  }
  /// The sum of [first, last), read back to the host.
  template <class It, class T>
  T Reduce(It first, It last, T init) {
    const T r = thrust::reduce(Policy(), first, last, init);
    Algorithm(kernels::Reduce(last - first));
    ReadBack();
    return r;
  }
  /// How many of [first, last) satisfy `pred`, read back to the host.
  template <class It, class Pred>
  int CountIf(It first, It last, const Pred& pred) {
    const auto r = thrust::count_if(Policy(), first, last, pred);
    Algorithm(kernels::Reduce(last - first));
    ReadBack();
    return static_cast<int>(r);
  }
  /// The items of [first, last) (or of their stencil) that satisfy `pred`, compacted into `out`; returns
  /// their count (read back to the host).
  template <class In, class Out, class Pred>
  int CopyIf(In first, In last, Out out, const Pred& pred) {
    const Out end = thrust::copy_if(Policy(), first, last, out, pred);
    Algorithm(kernels::kSelect);
    ReadBack();
    return static_cast<int>(end - out);
  }
  template <class In, class Stencil, class Out, class Pred>
  int CopyIf(In first, In last, Stencil stencil, Out out, const Pred& pred) {
    const Out end = thrust::copy_if(Policy(), first, last, stencil, out, pred);
    Algorithm(kernels::kSelect);
    ReadBack();
    return static_cast<int>(end - out);
  }
  template <class In, class Out>
  void ExclusiveScan(In first, In last, Out out) {
    if (first == last) return;
    thrust::exclusive_scan(Policy(), first, last, out);
    Algorithm(kernels::kScan);
  }
  template <class In, class Out, class T, class Op>
  void ExclusiveScan(In first, In last, Out out, T init, const Op& op) {
    if (first == last) return;
    thrust::exclusive_scan(Policy(), first, last, out, init, op);
    Algorithm(kernels::kScan);
  }
  /// The exclusive scan of the first `n` items of `in` into `out`, and its total, read back to the host
  /// (one copy and one wait, not two).
  template <class V>
  uint32_t ExclusiveScanTotal(const V& in, size_t n, V& out) {
    if (n == 0) return 0;
    ExclusiveScan(in.begin(), in.begin() + n, out.begin());
    Resize(m_total, 1);
    ForEach(1, ScanTotalStage{thrust::raw_pointer_cast(in.data()), thrust::raw_pointer_cast(out.data()), n - 1,
                              thrust::raw_pointer_cast(m_total.data())});
    return Read(m_total, 0);
  }
  /// One element of a device vector, read back to the host.
  template <class V>
  typename V::value_type Read(const V& v, size_t i) {
    const typename V::value_type r = v[i];
    ReadBack();
    return r;
  }
  /// [first, last) of a device vector into host memory at `out`; `asked`: an output asked for it.
  template <class It, class HostIt>
  void Download(It first, It last, HostIt out, bool asked) {
    if (first == last) return;
    thrust::copy(first, last, out);
    m_counter.Download(asked);
    if constexpr (kCuda) m_counter.Sync();
  }
  /// Host memory [first, last) into a device vector at `out` (sized by the caller).
  template <class HostIt, class It>
  void Upload(HostIt first, HostIt last, It out) {
    if (first == last) return;
    thrust::copy(first, last, out);
    m_counter.Upload();
    if constexpr (kCuda) m_counter.Sync();  // cudaMemcpy from pageable memory waits for the stream
  }
  /// v = [first, last) of host memory: its size, then the copy.
  template <class V, class HostIt>
  void Assign(V& v, HostIt first, HostIt last) {
    Resize(v, static_cast<size_t>(last - first));
    Upload(first, last, v.begin());
  }
  /// The host waits for everything launched so far.
  void Sync() {
    if constexpr (kCuda) m_counter.Sync();
  }

 private:
  /// One algorithm: on CUDA `kernels` kernels, on the CPU one launch. (Its temporaries count when
  /// KeptTemporaries allocates a block.)
  void Algorithm(int kernels) { m_counter.Launch(kCuda ? kernels : 1); }
  void ReadBack() {
    m_counter.Download();
    if constexpr (kCuda) m_counter.Sync();
  }

  LaunchCounter m_counter;
  KeptTemporaries<Traits> m_temporaries{m_counter};
  typename Traits::template Vector<uint32_t> m_total;  // ExclusiveScanTotal's
};

}  // namespace sphxr::sim
