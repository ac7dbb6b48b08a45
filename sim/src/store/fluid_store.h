#pragma once
// The fluid's particle store on a backend's system (Traits as in backend_impl.h): every field of the list
// (sphxr/sim/fields.h), the Z-order sort that keeps them in cell order, the cells' ranges and the
// neighbour-list scratch. Resize, reorder, upload and download loop over the one field list, so a new
// field cannot be forgotten by the sort.
#include "launch/device.h"
#include "sphxr/sim/fields.h"
#include "stages.h"
#include "store/raw.h"

namespace sphxr::sim {

template <class Traits>
class FluidStore {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  explicit FluidStore(DeviceOps<Traits>& device) : m_dev(device) {}

  int Count() const { return static_cast<int>(m_fields.position.size()); }

  /// Sizes the cell ranges for a grid of `cells` cells.
  void SizeCells(size_t cells) {
    m_dev.Resize(m_start, cells);
    m_dev.Resize(m_end, cells);
  }
  size_t Cells() const { return m_start.size(); }

  void Upload(const HostFluid& fluid) {
    const size_t n = fluid.size();
#define SPHXR_UPLOAD_FIELD(type, name) m_dev.Assign(m_fields.name, fluid.name.begin(), fluid.name.end());
    SPHXR_FLUID_FIELDS(SPHXR_UPLOAD_FIELD)
#undef SPHXR_UPLOAD_FIELD
#define SPHXR_SIZE_SORTED(type, name) m_dev.Resize(m_sorted.name, n);
    SPHXR_FLUID_FIELDS(SPHXR_SIZE_SORTED)
#undef SPHXR_SIZE_SORTED
    m_dev.Resize(m_keys, n);
    m_dev.Resize(m_order, n);
  }

  void Download(HostFluid* out) const {
    out->resize(m_fields.position.size());
    if (out->size() == 0) return;  // (thrust's host copy of nothing dereferences a null begin: UB)
#define SPHXR_DOWNLOAD_FIELD(type, name) \
  m_dev.Download(m_fields.name.begin(), m_fields.name.end(), out->name.begin(), /*asked=*/true);
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
    m_dev.ForEach(Count(), CellCodeStage{g, Raw(m_fields.position), Raw(m_keys), Raw(m_order), gate});
  }
  /// The stable sort by cell code (one key-and-index radix sort) and the gather of every field of the list.
  void Sort() {
    m_dev.SortPairs(m_keys, m_order);
    Reorder();
  }
  /// cellStart/cellEnd of every cell from the sorted codes.
  void CellRanges(const GridView& g) {
    const int n = Count();
    m_dev.Fill(m_start, kEmptyCell);
    m_dev.ForEach(n, CellRangeStage{g, Raw(m_fields.position), Raw(m_keys), Raw(m_start), Raw(m_end), n});
  }

  FluidView View() { return ViewOf(m_fields, Count()); }

  /// The neighbour-list scratch, sized for the particle count and `capacity` slots each.
  NeighbourList Neighbours(int capacity) {
    const size_t n = static_cast<size_t>(Count());
    m_dev.Resize(m_neighbourIndex, n * static_cast<size_t>(capacity));
    m_dev.Resize(m_neighbourCount, n);
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

  static FluidView ViewOf(Fields& f, int count) {
    FluidView v;
#define SPHXR_VIEW_OF(type, name) v.name = Raw(f.name);
    SPHXR_FLUID_FIELDS(SPHXR_VIEW_OF)
#undef SPHXR_VIEW_OF
    v.count = count;
    return v;
  }

  /// Applies the sort permutation to every field of the list: one gather of all of them into the
  /// second set (ReorderFieldsStage), then an O(1) swap of each.
  void Reorder() {
    const int n = Count();
    m_dev.ForEach(n, ReorderFieldsStage{ViewOf(m_fields, n), ViewOf(m_sorted, n), Raw(m_order)});
#define SPHXR_SWAP_FIELD(type, name) m_fields.name.swap(m_sorted.name);
    SPHXR_FLUID_FIELDS(SPHXR_SWAP_FIELD)
#undef SPHXR_SWAP_FIELD
  }

  DeviceOps<Traits>& m_dev;
  Fields m_fields;
  Fields m_sorted;  // the reorder's destination, swapped with m_fields after it
  Vector<uint32_t> m_keys, m_order;
  Vector<uint32_t> m_start, m_end;  // per cell: the sorted particles' range
  Vector<uint32_t> m_neighbourIndex, m_neighbourCount;
};

}  // namespace sphxr::sim
