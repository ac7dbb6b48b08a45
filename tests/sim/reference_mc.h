#pragma once
// A plain serial marching cubes, written for the tests (and the surface benchmark's baseline): loop over
// the cells in order, look up the case, emit each triangle's vertices by interpolation on its edges.
// It shares only the case table (sim/src/mc_tables.h) with the histogram-pyramid code; the
// enumeration, the corner and edge geometry and the interpolation are its own.
#include <cmath>
#include <cstdint>
#include <vector>

#include "mc_tables.h"
#include "sphxr/sim/surface.h"

namespace sphxr::test {

struct ReferenceMesh {
  std::vector<float> positions;  // xyz, 3 vertices per triangle
  std::vector<float> normals;    // xyz, -grad phi normalised (when asked for)
  int64_t VertexCount() const { return static_cast<int64_t>(positions.size() / 3); }
};

/// Marching cubes over `field` (grid.Samples() values, x fastest); inside is value > iso. With
/// `normals`, each vertex also gets -grad phi (central differences at the edge's two samples, one-sided
/// on the border, interpolated like the position), normalised.
inline ReferenceMesh ReferenceMarchingCubes(const sim::SurfaceGrid& grid, const std::vector<float>& field, float iso,
                                            bool normals = false) {
  ReferenceMesh mesh;
  const int nx = grid.nx, ny = grid.ny, nz = grid.nz;
  auto at = [&](int i, int j, int k) { return field[static_cast<size_t>(i) + static_cast<size_t>(nx) * (j + static_cast<size_t>(ny) * k)]; };
  auto gradient = [&](int i, int j, int k, float* g) {
    const int p[3] = {i, j, k}, n[3] = {nx, ny, nz};
    for (int d = 0; d < 3; ++d) {
      int lo[3] = {i, j, k}, hi[3] = {i, j, k};
      if (p[d] > 0) lo[d] -= 1;
      if (p[d] < n[d] - 1) hi[d] += 1;
      const int steps = hi[d] - lo[d];
      g[d] = steps == 0 ? 0.0f : (at(hi[0], hi[1], hi[2]) - at(lo[0], lo[1], lo[2])) / (static_cast<float>(steps) * grid.cellSize);
    }
  };
  // Corner c of a cell: offset (c & 1, c >> 1 & 1, c >> 2 & 1).
  static constexpr int kOffset[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                                        {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  for (int k = 0; k + 1 < nz; ++k) {
    for (int j = 0; j + 1 < ny; ++j) {
      for (int i = 0; i + 1 < nx; ++i) {
        float v[8];
        int mask = 0;
        for (int c = 0; c < 8; ++c) {
          v[c] = at(i + kOffset[c][0], j + kOffset[c][1], k + kOffset[c][2]);
          if (v[c] > iso) mask |= 1 << c;
        }
        const int count = sim::kMcTables.vertexCount[mask];
        for (int n = 0; n < count; ++n) {
          const int e = sim::kMcTables.edges[mask][n];
          const int a = sim::McEdgeCorner(e, 0), b = sim::McEdgeCorner(e, 1);
          const float t = (iso - v[a]) / (v[b] - v[a]);
          for (int d = 0; d < 3; ++d) {
            const int base = d == 0 ? i : (d == 1 ? j : k);
            const float o = d == 0 ? grid.origin.x : (d == 1 ? grid.origin.y : grid.origin.z);
            const float pa = o + static_cast<float>(base + kOffset[a][d]) * grid.cellSize;
            const float pb = o + static_cast<float>(base + kOffset[b][d]) * grid.cellSize;
            mesh.positions.push_back(pa + t * (pb - pa));
          }
          if (normals) {
            float ga[3], gb[3], g[3];
            gradient(i + kOffset[a][0], j + kOffset[a][1], k + kOffset[a][2], ga);
            gradient(i + kOffset[b][0], j + kOffset[b][1], k + kOffset[b][2], gb);
            float len2 = 0.0f;
            for (int d = 0; d < 3; ++d) {
              g[d] = ga[d] + t * (gb[d] - ga[d]);
              len2 += g[d] * g[d];
            }
            const float inv = len2 > 0.0f ? -1.0f / std::sqrt(len2) : 0.0f;
            for (int d = 0; d < 3; ++d) mesh.normals.push_back(len2 > 0.0f ? g[d] * inv : (d == 1 ? 1.0f : 0.0f));
          }
        }
      }
    }
  }
  return mesh;
}

}  // namespace sphxr::test
