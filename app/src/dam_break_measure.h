#pragma once
// The dam-break measures of a scene's "probe" section (scene_file.h DamBreakProbe): the surge front and
// the column height, in the dimensionless units of the experiments.
#include "sphxr/app/scene_file.h"
#include "sphxr/sim/fields.h"

namespace sphxr::app {

struct DamBreakMeasure {
  float front;   // Z = x_front / a
  float height;  // H = h / 2a
};
DamBreakMeasure MeasureDamBreak(const DamBreakProbe& probe, const sim::HostFluid& fluid, float spacing);

}  // namespace sphxr::app
