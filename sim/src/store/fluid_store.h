#pragma once
// The fluid's particle store on a backend's system (Traits as in backend_impl.h): every field of the list
// (sphxr/sim/fields.h), the Z-order sort that keeps them in cell order, the cells' ranges and the
// neighbour-list scratch. Resize, reorder, upload and download loop over the one field list, so a new
// field cannot be forgotten by the sort.
#include <thrust/copy.h>
#include <thrust/fill.h>
#include <thrust/for_each.h>
#include <thrust/gather.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/memory.h>
#include <thrust/sort.h>

#include <type_traits>

#include "sphxr/sim/fields.h"
#include "stages.h"
#include "store/raw.h"

namespace sphxr::sim {

template <class Traits>
class FluidStore {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  int Count() const { return static_cast<int>(m_fields.position.size()); }

  /// Sizes the cell ranges for a grid of `cells` cells.
  void SizeCells(size_t cells) {
    m_start.resize(cells);
    m_end.resize(cells);
  }
  size_t Cells() const { return m_start.size(); }

  void Upload(const HostFluid& fluid) {
    const size_t n = fluid.size();
#define SPHXR_UPLOAD_FIELD(type, name) \
  m_fields.name.resize(n);             \
  if (n > 0) thrust::copy(fluid.name.begin(), fluid.name.end(), m_fields.name.begin());  /* (as in Download) */
    SPHXR_FLUID_FIELDS(SPHXR_UPLOAD_FIELD)
#undef SPHXR_UPLOAD_FIELD
    m_keys.resize(n);
    m_order.resize(n);
    m_scratchVec4.resize(n);
    m_scratchFloat.resize(n);
    m_scratchU32.resize(n);
    m_scratchI32.resize(n);
  }

  void Download(HostFluid* out) const {
    out->resize(m_fields.position.size());
    if (out->size() == 0) return;  // (thrust's host copy of nothing dereferences a null begin: UB)
#define SPHXR_DOWNLOAD_FIELD(type, name) thrust::copy(m_fields.name.begin(), m_fields.name.end(), out->name.begin());
    SPHXR_FLUID_FIELDS(SPHXR_DOWNLOAD_FIELD)
#undef SPHXR_DOWNLOAD_FIELD
  }

  /// Cell codes, the stable Z-order sort with every field reordered, and the cells' ranges: after it
  /// the grid `g` (whose fluid ranges are this store's) holds the particles where they are now.
  void Regrid(const GridView& g) {
    CellCodes(g);
    Sort();
    CellRanges(g);
  }
  /// Each particle's Morton cell code and its index, the sort's keys and values (Huang et al. 2013, §3.1);
  /// where the device flag `gate` is 0, the codes of the last sort (CellCodeStage).
  void CellCodes(const GridView& g, const int* gate = nullptr) {
    thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), Count(),
                       CellCodeStage{g, Raw(m_fields.position), Raw(m_keys), Raw(m_order), gate});
  }
  /// The stable sort by cell code and the gather of every field of the list.
  void Sort() {
    thrust::stable_sort_by_key(Traits::Policy(), m_keys.begin(), m_keys.end(), m_order.begin());
    Reorder();
  }
  /// cellStart/cellEnd of every cell from the sorted codes.
  void CellRanges(const GridView& g) {
    const int n = Count();
    thrust::fill(Traits::Policy(), m_start.begin(), m_start.end(), kEmptyCell);
    thrust::for_each_n(Traits::Policy(), thrust::counting_iterator<int>(0), n,
                       CellRangeStage{g, Raw(m_fields.position), Raw(m_keys), Raw(m_start), Raw(m_end), n});
  }

  FluidView View() {
    FluidView v;
#define SPHXR_VIEW_OF(type, name) v.name = Raw(m_fields.name);
    SPHXR_FLUID_FIELDS(SPHXR_VIEW_OF)
#undef SPHXR_VIEW_OF
    v.count = Count();
    return v;
  }

  /// The neighbour-list scratch, sized for the particle count and `capacity` slots each.
  NeighbourList Neighbours(int capacity) {
    const size_t n = static_cast<size_t>(Count());
    if (m_neighbourIndex.size() != n * static_cast<size_t>(capacity)) m_neighbourIndex.resize(n * capacity);
    if (m_neighbourCount.size() != n) m_neighbourCount.resize(n);
    return NeighbourList{Raw(m_neighbourIndex), Raw(m_neighbourCount), capacity};
  }

  const uint32_t* Start() const { return Raw(m_start); }
  const uint32_t* End() const { return Raw(m_end); }
  Vector<uint32_t>& StartVector() { return m_start; }
  Vector<uint32_t>& EndVector() { return m_end; }
  /// Every particle's Morton key, sorted (valid after Regrid).
  Vector<uint32_t>& Keys() { return m_keys; }
  Vector<int32_t>& Idle() { return m_fields.idle; }

 private:
  struct Fields {
#define SPHXR_DEVICE_FIELD(type, name) Vector<type> name;
    SPHXR_FLUID_FIELDS(SPHXR_DEVICE_FIELD)
#undef SPHXR_DEVICE_FIELD
  };

  template <class T>
  Vector<T>& Scratch() {
    if constexpr (std::is_same_v<T, Vec4>) return m_scratchVec4;
    else if constexpr (std::is_same_v<T, float>) return m_scratchFloat;
    else if constexpr (std::is_same_v<T, int32_t>) return m_scratchI32;
    else {
      static_assert(std::is_same_v<T, uint32_t>, "add a scratch buffer for this type");
      return m_scratchU32;
    }
  }

  /// Applies the sort permutation to every field of the list (one gather and one O(1) swap each).
  void Reorder() {
    auto policy = Traits::Policy();
#define SPHXR_REORDER_FIELD(type, name)                                                               \
  {                                                                                                   \
    auto& scratch = Scratch<type>();                                                                  \
    thrust::gather(policy, m_order.begin(), m_order.end(), m_fields.name.begin(), scratch.begin()); \
    m_fields.name.swap(scratch);                                                                      \
  }
    SPHXR_FLUID_FIELDS(SPHXR_REORDER_FIELD)
#undef SPHXR_REORDER_FIELD
  }

  Fields m_fields;
  Vector<uint32_t> m_keys, m_order;
  Vector<Vec4> m_scratchVec4;
  Vector<float> m_scratchFloat;
  Vector<uint32_t> m_scratchU32;
  Vector<int32_t> m_scratchI32;
  Vector<uint32_t> m_start, m_end;  // per cell: the sorted particles' range
  Vector<uint32_t> m_neighbourIndex, m_neighbourCount;
};

}  // namespace sphxr::sim
