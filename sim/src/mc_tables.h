#pragma once
// The marching-cubes case table (Lorensen & Cline 1987), derived here at compile time instead of typed
// in: for each of the 256 inside/outside patterns of a cell's corners, the surface crosses every edge
// whose corners differ; on each face the crossings are joined by segments, and the segments of the six
// faces close into loops, each triangulated as a fan.
//
// Conventions:
//   corner c = x + 2y + 4z (bits of c), case bit c set when corner c is inside (phi > iso);
//   edge e joins corners EdgeCorner(e, 0) < EdgeCorner(e, 1): edges 0-3 along x (at y + 2z = e),
//   4-7 along y (x + 2z = e - 4), 8-11 along z (x + 2y = e - 8). A vertex on an edge is always
//   interpolated from its lower corner to its upper one, so the two cells sharing an edge compute
//   bitwise the same point (no cracks, and welding by exact equality works).
//   Faces with two inside corners on a diagonal (ambiguous faces) separate the inside corners. The
//   rule looks only at the face's own corners, so the two cells sharing a face always agree: the
//   surface is closed wherever the field is below the iso level at the grid's border.
//   Triangles are counter-clockwise seen from outside the water (normal towards lower phi).
#include <cstdint>

namespace sphxr::sim {

inline constexpr int kMcMaxVertices = 15;  // at most 5 triangles per cell (checked below)

struct McTables {
  uint8_t vertexCount[256];          // vertices (3 per triangle) of each case
  int8_t edges[256][kMcMaxVertices]; // edge of each vertex, triangles in order; -1 after the last
};

constexpr int McEdgeCorner(int e, int end) {
  const int axis = e / 4, o = e % 4;
  int lo = 0;
  if (axis == 0) lo = ((o & 1) << 1) | ((o >> 1) << 2);
  else if (axis == 1) lo = (o & 1) | ((o >> 1) << 2);
  else lo = (o & 1) | ((o >> 1) << 1);
  return end == 0 ? lo : lo | (1 << axis);
}

constexpr int McEdgeOf(int c0, int c1) {
  const int diff = c0 ^ c1;
  const int axis = diff == 1 ? 0 : (diff == 2 ? 1 : 2);
  const int lo = c0 & c1;
  const int x = lo & 1, y = (lo >> 1) & 1, z = (lo >> 2) & 1;
  if (axis == 0) return y + 2 * z;
  if (axis == 1) return 4 + x + 2 * z;
  return 8 + x + 2 * y;
}

/// True when edges a and b lie on a common face of the cell.
constexpr bool McEdgesShareFace(int a, int b) {
  for (int axis = 0; axis < 3; ++axis) {
    if (a / 4 == axis || b / 4 == axis) continue;  // an edge lies on the two faces across the other axes
    const int sideA = (McEdgeCorner(a, 0) >> axis) & 1, sideB = (McEdgeCorner(b, 0) >> axis) & 1;
    if (sideA == sideB) return true;
  }
  return false;
}

constexpr McTables MakeMcTables() {
  McTables t{};
  for (int mask = 0; mask < 256; ++mask) {
    auto inside = [mask](int c) { return ((mask >> c) & 1) != 0; };
    int next[12];
    for (int& n : next) n = -1;
    // Each face: corners counter-clockwise about the outward normal. Walking that way, a crossing from
    // an inside corner to an outside one is an exit, the reverse an entry; the inside part of the face
    // is bounded by [entry, inside corners, exit] and a surface segment exit -> that entry.
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};  // counter-clockwise about +axis
        int corner[4] = {};
        for (int k = 0; k < 4; ++k) {
          const int kk = side == 1 ? k : 3 - k;  // reversed for the face whose outward normal is -axis
          corner[k] = (side << axis) | (uv[kk][0] << u) | (uv[kk][1] << v);
        }
        int crossing[4] = {}, isExit[4] = {}, count = 0;
        for (int k = 0; k < 4; ++k) {
          const int a = corner[k], b = corner[(k + 1) % 4];
          if (inside(a) != inside(b)) {
            crossing[count] = McEdgeOf(a, b);
            isExit[count] = inside(a) ? 1 : 0;
            ++count;
          }
        }
        // Crossings alternate exit/entry; each exit joins the entry just before it (the same inside run).
        for (int k = 0; k < count; ++k) {
          if (isExit[k]) next[crossing[k]] = crossing[(k + count - 1) % count];
        }
      }
    }
    // Every crossed edge is the exit of one face and the entry of the other: the segments form loops.
    bool used[12] = {};
    int n = 0;
    for (int start = 0; start < 12; ++start) {
      if (next[start] < 0 || used[start]) continue;
      int loop[12] = {}, len = 0;
      for (int e = start; !used[e]; e = next[e]) {
        used[e] = true;
        loop[len++] = e;
      }
      // A fan from loop[s] whose diagonals never join two vertices of one face: the cell across that
      // face may hold a segment or a diagonal between the same two points, and the edge would then be
      // shared by four triangles (two sheets touching along it).
      int s = 0;
      for (; s < len; ++s) {
        bool ok = true;
        for (int k = 2; k + 1 < len && ok; ++k) ok = !McEdgesShareFace(loop[s], loop[(s + k) % len]);
        if (ok) break;
      }
      if (s == len) throw "marching cubes: a loop without a fan that avoids face diagonals";
      // The loop runs clockwise seen from outside (its right-hand normal points into the water), so the
      // fan takes it backwards.
      for (int k = 1; k + 1 < len; ++k) {
        if (n + 3 > kMcMaxVertices) throw "marching cubes: more than 5 triangles in a case";
        t.edges[mask][n++] = static_cast<int8_t>(loop[s]);
        t.edges[mask][n++] = static_cast<int8_t>(loop[(s + k + 1) % len]);
        t.edges[mask][n++] = static_cast<int8_t>(loop[(s + k) % len]);
      }
    }
    t.vertexCount[mask] = static_cast<uint8_t>(n);
    for (int k = n; k < kMcMaxVertices; ++k) t.edges[mask][k] = -1;
  }
  return t;
}

inline constexpr McTables kMcTables = MakeMcTables();

}  // namespace sphxr::sim
