#pragma once
// Particle export that ParaView and Blender read: binary little-endian PLY (vertices with properties)
// and legacy VTK polydata. Fields come from the one field list (sim/fields.h), so a new field is
// exported without touching this file.
#include <string>

#include "sphxr/common/status.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/surface.h"

namespace sphxr::app {

Status WritePly(const std::string& path, const sim::HostFluid& fluid);
Status WriteVtk(const std::string& path, const sim::HostFluid& fluid);
/// The surface mesh (a triangle soup, sim/surface.h): binary PLY with per-vertex normals, or OBJ.
Status WriteSurfacePly(const std::string& path, const sim::SurfaceMesh& mesh);
Status WriteSurfaceObj(const std::string& path, const sim::SurfaceMesh& mesh);

}  // namespace sphxr::app
