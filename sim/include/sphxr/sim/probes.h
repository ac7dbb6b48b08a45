#pragma once
// Probes: what a user measures in a run without exporting every particle. Pressure sensors,
// water-level gauges, and the force and torque of the fluid on a moving body. The solver evaluates the
// sensors and gauges on its backend in every step, one work item per probe over the neighbour grid
// (sim/src/stages/probes.h), on the state at the start of the step: positions, densities and pressures
// that belong together.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sphxr/sim/rigid.h"
#include "sphxr/sim/vec.h"

namespace sphxr::sim {

/// A pressure sensor: the Shepard-normalised kernel average of the fluid pressure,
///   p = sum_j V_j p_j W(x - x_j) / sum_j V_j W(x - x_j),  V_j = m / rho_j,
/// at x = at - offset * normal. With a wall's outward normal (from the water into the wall) and `at` on
/// the wall's face, x sits `offset` into the water, where the first layer of particles is.
struct PressureProbe {
  std::string name;
  Vec3 at;                      // m
  Vec3 normal;                  // the wall's outward unit normal; zero: a point in the water (offset 0)
  std::optional<float> offset;  // m along -normal; default half a spacing (zero without a normal)
};

/// A water-level gauge: the vertical line at (x, z) from `bottom` to `top` (default: the tank's floor and
/// top). It reads the height where the kernel-interpolated fluid fraction phi(y) = sum_j V_j W(x - x_j)
/// first falls below 1/2 going up, after having reached 1/2. A lone particle's phi peaks at V W(0) =
/// 1/pi at the default support of 2 spacings, so isolated spray never counts.
struct LevelGauge {
  std::string name;
  float x = 0.0f, z = 0.0f;       // m
  std::optional<float> bottom, top;  // m
};

/// The force and torque of the fluid on moving body `body` (SceneSetup::bodies: a paddle or a scene's
/// box body): the sum of the pressure and viscous reactions on its boundary particles, which is also
/// what the paddles' haptics are built from (Solver::LastBodyLoad).
struct ForceProbe {
  std::string name;
  int body = -1;
};

struct ProbeSet {
  std::vector<PressureProbe> pressure;
  std::vector<LevelGauge> level;
  std::vector<ForceProbe> force;
  bool Empty() const { return pressure.empty() && level.empty() && force.empty(); }
};

/// One reading of every probe of a set, in the set's order.
struct ProbeSample {
  double time = 0.0;   // s, simulated: the state the reading describes
  int64_t steps = 0;   // steps taken from the run's start up to that state
  std::vector<float> pressure;  // Pa; NaN: dry (shepard below the probe's dry threshold)
  std::vector<float> shepard;   // sum_j V_j W at each pressure probe (about 1 inside the water)
  std::vector<float> level;     // m; NaN: the fluid fraction never reaches 1/2 on the line
  std::vector<BodyLoad> load;   // N and N m; the torque about the body's origin
};

/// The fraction of the kernel's volume integral on the water's side of a flat wall for a point `offset`
/// from the wall's face (1 for a point away from walls): what sum_j V_j W is at that point next to a
/// flooded wall. Host only.
float KernelFractionInside(float offset, float supportRadius);

/// The fraction of the kernel's volume integral around `point` that lies in the tank and outside its
/// obstacles: what sum_j V_j W is at that point when the water floods everything around it. 1 a support
/// from every face; KernelFractionInside of the distance next to one flat face; less in an edge or a
/// corner (about a quarter and an eighth at the faces, 0.66 and 0.53 half a spacing from two and three
/// faces at the default support). Host only; numerical (Simpson) where two faces or an obstacle are
/// within the support, to about 1e-4.
float KernelFractionInRegion(Vec3 point, const Aabb& tank, const std::vector<Aabb>& obstacles, float supportRadius);

/// A pressure probe is dry when its Shepard sum is below half of KernelFractionInRegion at its point:
/// half of what the water gives it there when the water floods the walls around it, which is what it has
/// when the free surface of still water passes through the point (half of its kernel in the air). A lone
/// drop of one particle on the probe gives 1/pi ~ 0.32 against a threshold of 0.5 (away from walls),
/// 0.41 (half a spacing from a flat wall at the default support), 0.33 in a vertical edge and 0.27 in a
/// corner: there the sensor reads the water that can reach it, as a flooded corner sensor must.
inline constexpr float kDryFraction = 0.5f;
float ProbeDryThreshold(Vec3 point, const Aabb& tank, const std::vector<Aabb>& obstacles, float supportRadius);

/// The level gauges' sampling: the line is walked upward in steps of kLevelCoarse spacings (the fraction
/// falls from 1 to 0 over a kernel support, two spacings, so no surface is stepped over; an air gap
/// thinner than a spacing may be); the step in which phi falls below 1/2 is sampled again at kLevelFine
/// spacings, and the crossing found by linear interpolation between the two samples around it.
inline constexpr float kLevelCoarse = 1.0f;
inline constexpr float kLevelFine = 0.125f;
inline constexpr float kLevelFraction = 0.5f;

}  // namespace sphxr::sim
