#pragma once
// The temporaries of thrust's and CUB's algorithms (a sort's buffers, a reduction's partial sums), kept
// between steps: a block freed by one algorithm is handed to the next that fits, so a steady frame
// allocates nothing (a cudaMalloc costs a driver call, and every cudaFree waits for the whole device).
// The thrust allocator of the backend's policy (launch/device.h); `Traits::AllocateBytes` and
// `FreeBytes` are the system's raw allocation (host memory, or cudaMalloc/cudaFree). Each block it
// allocates is counted; the blocks live until the backend goes.
#include <cstddef>
#include <map>

#include "launch/counter.h"

namespace sphxr::sim {

template <class Traits>
class KeptTemporaries {
 public:
  using value_type = char;  // the interface thrust's execute_with_allocator asks for

  explicit KeptTemporaries(LaunchCounter& counter) : m_counter(&counter) {}
  KeptTemporaries(const KeptTemporaries&) = delete;
  KeptTemporaries& operator=(const KeptTemporaries&) = delete;
  ~KeptTemporaries() {
    for (auto& [bytes, block] : m_free) Traits::FreeBytes(block);
    for (auto& [block, bytes] : m_used) Traits::FreeBytes(block);
  }

  /// The smallest free block of at least `bytes`, else a new one.
  char* allocate(std::ptrdiff_t bytes) {
    const size_t size = static_cast<size_t>(bytes > 0 ? bytes : 1);
    auto it = m_free.lower_bound(size);
    char* block = nullptr;
    size_t held = size;
    if (it != m_free.end()) {
      held = it->first;
      block = it->second;
      m_free.erase(it);
    } else {
      block = static_cast<char*>(Traits::AllocateBytes(size));
      m_counter->Allocation();
    }
    m_used.emplace(block, held);
    return block;
  }
  void deallocate(char* block, size_t /*bytes*/) {
    auto it = m_used.find(block);
    if (it == m_used.end()) return;
    m_free.emplace(it->second, block);
    m_used.erase(it);
  }

 private:
  LaunchCounter* m_counter;
  std::multimap<size_t, char*> m_free;  // by size
  std::map<char*, size_t> m_used;
};

}  // namespace sphxr::sim
