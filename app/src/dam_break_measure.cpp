#include "dam_break_measure.h"

#include <algorithm>

#include "sphxr/sim/measure.h"

namespace sphxr::app {

DamBreakMeasure MeasureDamBreak(const DamBreakProbe& probe, const sim::HostFluid& fluid, float spacing) {
  const int minPerBin = DamBreakMinPerBin(probe, spacing);
  DamBreakMeasure m;
  m.front = sim::SurgeFront(fluid, probe.wallX, spacing, minPerBin) / probe.columnWidth;
  m.height = sim::ColumnHeight(fluid, probe.floorY, probe.wallX, spacing, std::max(1, minPerBin / 2)) /
             (2.0f * probe.columnWidth);
  return m;
}

}  // namespace sphxr::app
