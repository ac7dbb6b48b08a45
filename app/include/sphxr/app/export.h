#pragma once
// Particle export that ParaView and Blender read: binary little-endian PLY (vertices with properties)
// and legacy VTK polydata. Fields come from the one field list (sim/fields.h), so a new field is
// exported without touching this file.
#include <cstdint>
#include <string>

#include "sphxr/common/status.h"
#include "sphxr/sim/diffuse.h"
#include "sphxr/sim/fields.h"
#include "sphxr/sim/surface.h"

namespace sphxr::app {

/// The step and simulated time a file holds, so that files can be lined up without the CSV: a PLY
/// comment `comment step N time T`, VTK field data (TIME, double; CYCLE, int: ParaView's names), an OBJ
/// comment `# step N time T`. A negative step writes none of them.
struct ExportStamp {
  int64_t step = -1;
  double time = 0.0;  // s
};

Status WritePly(const std::string& path, const sim::HostFluid& fluid, const ExportStamp& stamp = {});
Status WriteVtk(const std::string& path, const sim::HostFluid& fluid, const ExportStamp& stamp = {});
/// The diffuse particles (spray, foam, bubbles; sim/diffuse.h) as binary PLY: x y z, lifetime (s),
/// velocity_x/y/z, kind (uchar: 0 spray, 1 foam, 2 bubble), oldest first.
Status WriteDiffusePly(const std::string& path, const sim::HostDiffuse& diffuse, const ExportStamp& stamp = {});
/// The surface mesh (a triangle soup, sim/surface.h): binary PLY with per-vertex normals, or OBJ.
Status WriteSurfacePly(const std::string& path, const sim::SurfaceMesh& mesh, const ExportStamp& stamp = {});
Status WriteSurfaceObj(const std::string& path, const sim::SurfaceMesh& mesh, const ExportStamp& stamp = {});

}  // namespace sphxr::app
