#include "sampling.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "sphxr/common/log.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {
namespace {

// Whole lattice cells of size dx that fit in `extent`; the relative slack absorbs float rounding of
// extents that are meant to be exact multiples (1e-6 is far below any spacing ratio we care about).
int64_t FitCount(float extent, float dx) {
  return std::max<int64_t>(0, static_cast<int64_t>(std::floor(static_cast<double>(extent) / dx * (1.0 + 1e-6))));
}

bool InsideExpanded(const Aabb& b, Vec3 p, float margin) {
  return p.x > b.min.x - margin && p.x < b.max.x + margin && p.y > b.min.y - margin && p.y < b.max.y + margin &&
         p.z > b.min.z - margin && p.z < b.max.z + margin;
}

// Samples the shell of a box on a lattice fitted to it exactly (n_a intervals per axis, spacing close to
// dx). Lattice index k_a runs over [-out, n_a + out]; a point belongs to the shell unless it is interior,
// i.e. in < k_a < n_a - in on every axis. outward: `layers` layers on and outside the faces (in = 0,
// out = layers - 1); inward: on and inside (in = layers - 1, out = 0). openTop leaves the +y face and
// everything above it out (the walls still reach the top edge).
// emit(point, faces): `faces` holds a bit for each face whose slab holds the point.
enum : unsigned { kFaceXMin = 1, kFaceXMax = 2, kFaceFloor = 4, kFaceTop = 8, kFaceZMin = 16, kFaceZMax = 32 };

template <class Emit>
void SampleShell(const Aabb& box, float dx, int layers, bool outward, bool openTop, Emit&& emit) {
  const float ext[3] = {box.max.x - box.min.x, box.max.y - box.min.y, box.max.z - box.min.z};
  const float lo[3] = {box.min.x, box.min.y, box.min.z};
  int64_t n[3];
  float s[3];
  for (int a = 0; a < 3; ++a) {
    n[a] = std::max<int64_t>(1, std::llround(ext[a] / dx));
    s[a] = ext[a] / static_cast<float>(n[a]);
  }
  const int64_t out = outward ? layers - 1 : 0;
  const int64_t in = outward ? 0 : layers - 1;
  const int64_t yTop = openTop ? n[1] : n[1] + out;
  for (int64_t kz = -out; kz <= n[2] + out; ++kz) {
    for (int64_t ky = -out; ky <= yTop; ++ky) {
      for (int64_t kx = -out; kx <= n[0] + out; ++kx) {
        const bool interiorX = kx > in && kx < n[0] - in;
        const bool interiorY = openTop ? ky > in : (ky > in && ky < n[1] - in);
        const bool interiorZ = kz > in && kz < n[2] - in;
        if (interiorX && interiorY && interiorZ) continue;
        // The faces whose slab (the face and the layers behind it) holds the point: edges and corners
        // belong to two or three.
        unsigned faces = 0;
        if (kx <= in) faces |= kFaceXMin;
        if (kx >= n[0] - in) faces |= kFaceXMax;
        if (ky <= in) faces |= kFaceFloor;
        if (!openTop && ky >= n[1] - in) faces |= kFaceTop;
        if (kz <= in) faces |= kFaceZMin;
        if (kz >= n[2] - in) faces |= kFaceZMax;
        emit(Vec3{lo[0] + s[0] * static_cast<float>(kx), lo[1] + s[1] * static_cast<float>(ky),
                  lo[2] + s[2] * static_cast<float>(kz)},
             faces);
      }
    }
  }
}

// The number of points SampleShell emits, without visiting them (a scene is counted, and may be
// refused, before anything is allocated: walking a fine lattice takes tens of seconds).
int64_t ShellCount(const Aabb& box, float dx, int layers, bool outward, bool openTop) {
  const float ext[3] = {box.max.x - box.min.x, box.max.y - box.min.y, box.max.z - box.min.z};
  int64_t n[3];
  for (int a = 0; a < 3; ++a) n[a] = std::max<int64_t>(1, std::llround(ext[a] / dx));
  const int64_t out = outward ? layers - 1 : 0;
  const int64_t in = outward ? 0 : layers - 1;
  const int64_t yTop = openTop ? n[1] : n[1] + out;
  const int64_t total = (n[0] + 2 * out + 1) * (yTop + out + 1) * (n[2] + 2 * out + 1);
  const int64_t insideX = std::max<int64_t>(0, n[0] - 2 * in - 1);
  const int64_t insideY = openTop ? std::max<int64_t>(0, yTop - in) : std::max<int64_t>(0, n[1] - 2 * in - 1);
  const int64_t insideZ = std::max<int64_t>(0, n[2] - 2 * in - 1);
  return total - insideX * insideY * insideZ;
}

// Within `margin` of a moving body's solid at its initial pose.
bool InsideBody(const RigidBodySetup& body, Vec3 p, float margin) {
  const Vec3 local = Rotate(Conjugate(Normalized(body.pose.orientation)), p - body.pose.position);
  Vec3 n;
  return UnionDistance(body.shapes.data(), static_cast<int>(body.shapes.size()), local, &n) < margin;
}

}  // namespace

int LogCutBlocks(const SceneSetup& scene) {
  const float dx = scene.params.spacing;
  int cut = 0;
  std::string first;
  for (size_t b = 0; b < scene.fluid.size(); ++b) {
    const Aabb& box = scene.fluid[b].box;
    const float asked[3] = {box.max.x - box.min.x, box.max.y - box.min.y, box.max.z - box.min.z};
    float filled[3];
    bool whole = true;
    for (int a = 0; a < 3; ++a) {
      filled[a] = static_cast<float>(FitCount(asked[a], dx)) * dx;
      // FitCount's own slack: an extent meant to be a whole number of spacings is one.
      whole = whole && static_cast<double>(asked[a]) - filled[a] <= 1e-6 * static_cast<double>(asked[a]) + 1e-7 * dx;
    }
    if (whole) continue;
    if (cut++ == 0) {
      first = Format("fluid[%zu]: filled %g x %g x %g m of the %g x %g x %g m asked for (whole layers of the spacing %g m)",
                     b, filled[0], filled[1], filled[2], asked[0], asked[1], asked[2], dx);
    }
  }
  // One line for the scene, however many blocks (a scene may hold tens of thousands).
  if (cut == 1) SPHXR_LOG_INFO("%s", first.c_str());
  if (cut > 1) SPHXR_LOG_INFO("%s; and %d more blocks of the %zu are cut to whole layers", first.c_str(), cut - 1, scene.fluid.size());
  return cut;
}

int64_t SampleFluid(const SceneSetup& scene, std::vector<Vec4>* out) {
  const float dx = scene.params.spacing;
  int64_t count = 0;
  for (const FluidBlock& block : scene.fluid) {
    const int64_t nx = FitCount(block.box.max.x - block.box.min.x, dx);
    const int64_t ny = FitCount(block.box.max.y - block.box.min.y, dx);
    const int64_t nz = FitCount(block.box.max.z - block.box.min.z, dx);
    if (!out && scene.obstacles.empty() && scene.bodies.empty()) {  // counting only: the lattice is full
      count += nx * ny * nz;
      continue;
    }
    // Hydrostatic start: the layer at depth d below the block's top sits where a column compressed to
    // the Tait density rho(s) = rho0 (1 + rho0 g s / B)^(1/gamma) puts it: depth
    // D(d) = int_0^d rho0/rho ds (closed form) below the compressed top. Only the vertical component of
    // gravity compresses. The column stands on the block's floor: the lowest layer stays half a spacing
    // above it (where the uncompressed lattice has it, one spacing from the floor's boundary particles)
    // and the surface comes down. Anchoring the top instead left a gap of the whole column's compression
    // under the water (3.4 mm in deep_tank), which the column fell into and rang in its acoustic mode.
    const float top = block.box.min.y + static_cast<float>(ny) * dx;
    const double a = scene.params.restDensity * std::max(0.0, -static_cast<double>(scene.gravity.y)) /
                     scene.params.stiffness;
    const double e = 1.0 - 1.0 / scene.params.exponent;
    const bool compress = block.hydrostatic && a > 0.0;
    // ((1 + a d)^e - 1) / (a e), written so that it stays finite as e -> 0 (exponent 1, allowed): there
    // it is log(1 + a d) / a.
    auto compressedDepth = [&](double d) {
      const double l = std::log1p(a * d);
      return std::abs(e) < 1e-12 ? l / a : std::expm1(e * l) / (a * e);
    };
    const double bottom = block.box.min.y + 0.5 * dx;
    const double bottomDepth = compress ? compressedDepth(top - bottom) : 0.0;
    auto layerY = [&](int64_t j) -> float {
      const float y = block.box.min.y + (static_cast<float>(j) + 0.5f) * dx;
      if (!compress) return y;
      return static_cast<float>(bottom + bottomDepth - compressedDepth(top - y));
    };
    for (int64_t k = 0; k < nz; ++k) {
      for (int64_t j = 0; j < ny; ++j) {
        for (int64_t i = 0; i < nx; ++i) {
          const Vec3 p{block.box.min.x + (static_cast<float>(i) + 0.5f) * dx, layerY(j),
                       block.box.min.z + (static_cast<float>(k) + 0.5f) * dx};
          bool blocked = false;
          for (const Aabb& o : scene.obstacles) blocked = blocked || InsideExpanded(o, p, 0.5f * dx);
          for (const RigidBodySetup& b : scene.bodies) blocked = blocked || InsideBody(b, p, 0.5f * dx);
          if (blocked) continue;
          ++count;
          if (out) out->push_back(MakeVec4(p));
        }
      }
    }
  }
  return count;
}

int64_t SampleBoundary(const SceneSetup& scene, std::vector<Vec4>* out, std::vector<float>* viscosity) {
  const float dx = scene.params.spacing;
  // Each wall particle's viscosity coefficient from its wall's friction; a particle on an edge or a
  // corner of the tank takes the largest of its faces' (a no-slip floor's edge along a free-slip wall
  // is still the floor's).
  const SolverParams& params = scene.params;
  const TankFriction& friction = scene.friction;
  const std::pair<unsigned, float> faceAlpha[] = {
      {kFaceXMin, WallFrictionAlpha(params, friction.xMin)},   {kFaceXMax, WallFrictionAlpha(params, friction.xMax)},
      {kFaceFloor, WallFrictionAlpha(params, friction.floor)}, {kFaceTop, WallFrictionAlpha(params, friction.top)},
      {kFaceZMin, WallFrictionAlpha(params, friction.zMin)},   {kFaceZMax, WallFrictionAlpha(params, friction.zMax)}};
  const float obstacleAlpha = WallFrictionAlpha(params, friction.obstacles);
  int64_t count = 0;
  bool tankPass = true;
  auto emit = [&](Vec3 p, unsigned faces) {
    ++count;
    if (out) out->push_back(MakeVec4(p));
    if (!viscosity) return;
    float alpha = tankPass ? 0.0f : obstacleAlpha;
    if (tankPass) {
      for (const auto& [face, a] : faceAlpha) {
        if (faces & face) alpha = std::max(alpha, a);
      }
    }
    viscosity->push_back(alpha);
  };
  // The boundary surface lies half a spacing behind the solid's face, where the next lattice layer of
  // the fluid would be: the fluid's first layer (half a spacing inside the face) is then one spacing from
  // the boundary particles, as in a continued lattice. With the boundary on the face itself, Akinci's
  // volume V_b = 1 / sum_k W_bk (which is large for a single sheet) over-counts the density of the first
  // fluid layer by about 50 % with the cubic spline at support 2 dx; one spacing away, by about 6 %.
  const float half = 0.5f * dx;
  Aabb tank = scene.tank;
  tank.min = tank.min - Vec3{half, half, half};
  tank.max = tank.max + Vec3{half, half, half};
  if (scene.openTop) tank.max.y = scene.tank.max.y;
  std::vector<Aabb> inner;
  for (const Aabb& o : scene.obstacles) {
    Aabb b = o;
    const Vec3 c = (o.min + o.max) * 0.5f;
    b.min = Vec3{std::min(c.x, o.min.x + half), std::min(c.y, o.min.y + half), std::min(c.z, o.min.z + half)};
    b.max = Vec3{std::max(c.x, o.max.x - half), std::max(c.y, o.max.y - half), std::max(c.z, o.max.z - half)};
    inner.push_back(b);
  }
  if (!out && !viscosity) {  // counting only
    count = ShellCount(tank, dx, scene.boundaryLayers, /*outward=*/true, scene.openTop);
    for (const Aabb& b : inner) count += ShellCount(b, dx, scene.boundaryLayers, /*outward=*/false, false);
    return count;
  }
  SampleShell(tank, dx, scene.boundaryLayers, /*outward=*/true, scene.openTop, emit);
  tankPass = false;
  for (const Aabb& b : inner) SampleShell(b, dx, scene.boundaryLayers, /*outward=*/false, false, emit);
  return count;
}

namespace {

// The rest lattice of spacing dx around a fluid particle at the origin: fluid at x >= 0, boundary
// sheets at x = -1 .. -layers (in spacings), each boundary particle with Akinci's volume
// V_b = 1 / sum_k W_bk over an infinite wall of those sheets. Sums run over a cube wide enough for
// the kernel support.
struct RestLattice {
  const CubicSpline& kernel;
  float dx;
  int layers;
  int reach = static_cast<int>(std::ceil(kernel.H / dx)) + 1;

  float W(int i, int j, int k) const { return kernel.W(dx * std::sqrt(static_cast<float>(i * i + j * j + k * k))); }
  // Normal (x) component of gradW_0j = (x_0 - x_j) GradFactor(r) for x_j = (i, j, k) dx.
  float GradX(int i, int j, int k) const {
    const float r = dx * std::sqrt(static_cast<float>(i * i + j * j + k * k));
    return r > 0.0f ? -static_cast<float>(i) * dx * kernel.GradFactor(r) : 0.0f;
  }
  // sum over the fluid lattice points with first index in [iFrom, iTo] of f(i, j, k).
  template <class F>
  double SumFluid(int iFrom, int iTo, F f) const {
    double sum = 0.0;
    for (int i = iFrom; i <= iTo; ++i)
      for (int j = -reach; j <= reach; ++j)
        for (int k = -reach; k <= reach; ++k) sum += f(i, j, k);
    return sum;
  }
  // sum_b V_b f(b) over the boundary sheets.
  template <class F>
  double SumBoundary(F f) const {
    double sum = 0.0;
    for (int l = 1; l <= layers; ++l) {
      double sheetNeighbours = 0.0;  // sum_k W_bk for b in sheet -l
      for (int m = 1; m <= layers; ++m)
        for (int j = -reach; j <= reach; ++j)
          for (int k = -reach; k <= reach; ++k) sheetNeighbours += W(l - m, j, k);
      const double volume = 1.0 / sheetNeighbours;
      for (int j = -reach; j <= reach; ++j)
        for (int k = -reach; k <= reach; ++k) sum += volume * f(-l, j, k);
    }
    return sum;
  }
  double Dx3() const { return static_cast<double>(dx) * dx * dx; }
};

}  // namespace

float WallDensityCorrection(const CubicSpline& kernel, float dx, int layers) {
  const RestLattice lattice{kernel, dx, layers};
  auto w = [&](int i, int j, int k) { return lattice.W(i, j, k); };
  const double fluidSum = lattice.SumFluid(0, lattice.reach, w);  // sum_j W_0j over the fluid half space
  const double boundarySum = lattice.SumBoundary(w);             // sum_b V_b W_0b
  // rho0 = m sum W_f + gamma rho0 sum V_b W_b with m = rho0 dx^3.
  return static_cast<float>((1.0 - lattice.Dx3() * fluidSum) / boundarySum);
}

float WallGradientCorrection(const CubicSpline& kernel, float dx, int layers) {
  const RestLattice lattice{kernel, dx, layers};
  auto gx = [&](int i, int j, int k) { return lattice.GradX(i, j, k); };
  const double missing = lattice.SumFluid(-lattice.reach, -1, gx);  // the fluid that is not there: x < 0
  const double boundary = lattice.SumBoundary(gx);                  // sum_b V_b gradW_0b
  // m sum_missing gradW = gamma_grad rho0 sum_b V_b gradW with m = rho0 dx^3.
  return static_cast<float>(lattice.Dx3() * missing / boundary);
}

float PbfRestGradientSum(const CubicSpline& kernel, float dx, float volume) {
  const RestLattice lattice{kernel, dx, 1};
  // |grad_j C_i|^2 = (V |grad W_ij|)^2 over the whole lattice around i (the sum of the gradients, the
  // i = j term of the constraint's gradient, is zero at rest by symmetry).
  const double sum = lattice.SumFluid(-lattice.reach, lattice.reach, [&](int i, int j, int k) {
    const float r = dx * std::sqrt(static_cast<float>(i * i + j * j + k * k));
    if (r <= 0.0f || r >= kernel.H) return 0.0;
    const double g = static_cast<double>(volume) * r * kernel.GradFactor(r);
    return g * g;
  });
  return static_cast<float>(sum);
}

float WallFluidSum(const CubicSpline& kernel, float dx) {
  const RestLattice lattice{kernel, dx, 1};
  // Seen from the boundary particle at -1: the fluid points at i >= 0 are at offsets i + 1.
  return static_cast<float>(lattice.SumFluid(1, lattice.reach + 1, [&](int i, int j, int k) { return lattice.W(i, j, k); }));
}

std::vector<float> WallInverseReferences(const SceneSetup& scene, const CubicSpline& kernel,
                                         const std::vector<Vec4>& boundary, float floorFraction) {
  const float dx = scene.params.spacing;
  const Aabb& tank = scene.tank;
  const int64_t n[3] = {FitCount(tank.max.x - tank.min.x, dx), FitCount(tank.max.y - tank.min.y, dx),
                        FitCount(tank.max.z - tank.min.z, dx)};
  const float lo[3] = {tank.min.x, tank.min.y, tank.min.z};
  const int reach = static_cast<int>(std::ceil(kernel.H / dx)) + 1;
  const float floorSum = floorFraction * WallFluidSum(kernel, dx);
  std::vector<float> out(boundary.size());
  for (size_t b = 0; b < boundary.size(); ++b) {
    const float xb[3] = {boundary[b].x, boundary[b].y, boundary[b].z};
    int64_t from[3], to[3];
    for (int a = 0; a < 3; ++a) {
      const int64_t c = static_cast<int64_t>(std::floor((xb[a] - lo[a]) / dx - 0.5f));
      from[a] = std::max<int64_t>(0, c - reach);
      to[a] = std::min<int64_t>(n[a] - 1, c + reach + 1);
    }
    double sum = 0.0;
    for (int64_t k = from[2]; k <= to[2]; ++k)
      for (int64_t j = from[1]; j <= to[1]; ++j)
        for (int64_t i = from[0]; i <= to[0]; ++i) {
          const Vec3 p{lo[0] + (static_cast<float>(i) + 0.5f) * dx, lo[1] + (static_cast<float>(j) + 0.5f) * dx,
                       lo[2] + (static_cast<float>(k) + 0.5f) * dx};
          const float r = std::sqrt((p.x - xb[0]) * (p.x - xb[0]) + (p.y - xb[1]) * (p.y - xb[1]) + (p.z - xb[2]) * (p.z - xb[2]));
          if (r >= kernel.H) continue;
          bool blocked = false;
          for (const Aabb& o : scene.obstacles) blocked = blocked || InsideExpanded(o, p, 0.5f * dx);
          if (!blocked) sum += kernel.W(r);
        }
    out[b] = static_cast<float>(1.0 / std::max<double>(sum, floorSum));
  }
  return out;
}

int NeighbourCapacity(float supportFactor) {
  const double lattice = 4.0 / 3.0 * 3.14159265358979 * supportFactor * supportFactor * supportFactor;
  return static_cast<int>(std::ceil(1.4 * lattice));
}

GridShape MakeGridShape(const SceneSetup& scene) {
  const float support = scene.params.spacing * scene.params.supportFactor;
  const float margin = static_cast<float>(scene.boundaryLayers) * scene.params.spacing * 1.1f + 0.5f * support;
  // A solver whose neighbour lists last several steps (PBF's skin) searches its lists to the support
  // plus their margin, and its stale cells must still hold every particle within the support of any
  // point: cells of the support plus the margin (the 27 around a cell reach that far).
  const SolverInfo& method = SolverInfoOf(scene.method);
  const float cell = support + (method.listMargin ? method.listMargin(scene.params) : 0.0f);
  GridShape g;
  g.cellSize = cell;
  g.origin = Vec3{scene.tank.min.x - margin, scene.tank.min.y - margin, scene.tank.min.z - margin};
  // In double, and saturated: a huge tank must come out as a huge grid (refused by ValidateScene), not
  // as a float-to-int overflow (undefined; INT_MIN on x86, which passed the size check).
  auto dim = [&](float lo, float hi) {
    const double n = std::ceil((static_cast<double>(hi) - lo + 2.0 * margin) / cell) + 1.0;
    return n < 2147483647.0 ? static_cast<int>(n) : 2147483647;
  };
  g.nx = dim(scene.tank.min.x, scene.tank.max.x);
  g.ny = dim(scene.tank.min.y, scene.tank.max.y);
  g.nz = dim(scene.tank.min.z, scene.tank.max.z);
  return g;
}

}  // namespace sphxr::sim
