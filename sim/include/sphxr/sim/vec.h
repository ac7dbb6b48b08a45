#pragma once
// sim's names for the math module's types (sphxr/common/math.h), so that sim::Vec3 and the like keep
// naming them; the functions on them are found by argument-dependent lookup.
#include "sphxr/common/math.h"

namespace sphxr::sim {

using sphxr::Aabb;
using sphxr::Pose;
using sphxr::Quat;
using sphxr::Vec3;
using sphxr::Vec4;

}  // namespace sphxr::sim
