#pragma once
// The boundary particles on a backend's system (Traits as in backend_impl.h): the walls and obstacles
// (sampled once, sorted once, their volumes after Akinci et al. 2012) and the moving bodies (paddles:
// canonical body-frame particles and their sorted world copies each step, stages/bodies.h).
#include <thrust/iterator/counting_iterator.h>

#include <vector>

#include "launch/device.h"
#include "sphxr/common/status.h"
#include "sphxr/sim/fields.h"
#include "stages.h"
#include "stages/bodies.h"
#include "store/raw.h"

namespace sphxr::sim {

template <class Traits>
class WallStore {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  explicit WallStore(DeviceOps<Traits>& device) : m_dev(device) {}

  /// Sorts the walls' particles by cell code once, builds their cell ranges, volumes and (under
  /// wall_density) the list of the cells that hold them, and the near-boundary flag of every cell.
  /// `g` is the grid whose boundary pointers are this store's (it is re-made between the passes).
  template <class MakeGrid>
  Status Init(const HostBoundary& boundary, const Physics& physics, size_t cells, const MakeGrid& grid) {
    if (physics.wallDensity && boundary.invReference.size() != boundary.size()) {
      // The force stage reads every wall particle's p_b/rho_b^2 under wall_density: without a reference
      // per boundary particle there would be nothing to compute it from.
      return Status::Error("walls with their own density need one reference per boundary particle "
                           "(sampling.h WallInverseReferences)");
    }
    m_dev.Resize(m_start, cells);
    m_dev.Resize(m_end, cells);
    m_dev.Resize(m_near, cells);
    const int nb = static_cast<int>(boundary.size());
    const bool wallDensity = physics.wallDensity;
    Vector<Vec4> unsorted;
    Vector<float> unsortedAlpha, unsortedReference;
    m_dev.Assign(unsorted, boundary.position.begin(), boundary.position.end());
    m_dev.Assign(unsortedAlpha, boundary.viscosity.begin(), boundary.viscosity.end());
    m_dev.Assign(unsortedReference, boundary.invReference.begin(), boundary.invReference.end());
    m_dev.Resize(m_position, nb);
    m_dev.Resize(m_alpha, nb);
    m_dev.Resize(m_invReference, wallDensity ? nb : 0);
    m_dev.Resize(m_pressureTerm, wallDensity ? nb : 0);
    Vector<uint32_t> keys, order;
    m_dev.Resize(keys, nb);
    m_dev.Resize(order, nb);
    m_dev.Fill(m_start, kEmptyCell);
    m_dev.Fill(m_end, kEmptyCell);
    if (nb > 0) {
      m_dev.ForEach(nb, CellCodeStage{grid(), Raw(unsorted), Raw(keys), Raw(order)});
      m_dev.SortPairs(keys, order);
      Vector<Vec4> sorted;
      m_dev.Resize(sorted, nb);
      m_dev.Gather(order.begin(), order.end(), unsorted.begin(), sorted.begin());
      m_dev.Gather(order.begin(), order.end(), unsortedAlpha.begin(), m_alpha.begin());
      if (wallDensity) m_dev.Gather(order.begin(), order.end(), unsortedReference.begin(), m_invReference.begin());
      m_dev.ForEach(nb, CellRangeStage{grid(), Raw(sorted), Raw(keys), Raw(m_start), Raw(m_end), nb});
      m_dev.ForEach(nb,
                         BoundaryVolumeStage{grid(), Raw(sorted), Raw(m_position), physics.boundaryGamma * physics.restDensity,
                                             physics.kernel});
    }
    // The cells that hold boundary particles: the walls' own pressure runs over them.
    m_wallCells.clear();
    if (wallDensity) {
      m_dev.Resize(m_wallCells, cells);
      const thrust::counting_iterator<uint32_t> cell(0);
      const int found = m_dev.CopyIf(cell, cell + cells, m_start.begin(), m_wallCells.begin(), NonEmptyCell{});
      m_dev.Resize(m_wallCells, static_cast<size_t>(found));
      m_wallCells.shrink_to_fit();  // (a vector keeps its capacity: 4 B per grid cell for the whole run)
    }
    // Which cells have boundary particles in their 27-cell neighbourhood (the walls never move).
    m_dev.ForEach(static_cast<int>(cells), BoundaryNearStage{grid(), Raw(m_near)});
    return Status::Ok();
  }

  /// The walls' part of a grid view.
  void Fill(GridView* g) {
    g->boundaryStart = Raw(m_start);
    g->boundaryEnd = Raw(m_end);
    g->boundaryNear = Raw(m_near);
    g->boundary = Raw(m_position);
    g->boundaryAlpha = Raw(m_alpha);
    g->boundaryPressureTerm = Raw(m_pressureTerm);
    g->boundaryInvReference = Raw(m_invReference);
  }

  void Download(HostBoundary* out) const {
    out->position.resize(m_position.size());
    m_dev.Download(m_position.begin(), m_position.end(), out->position.begin(), /*asked=*/true);
    out->viscosity.resize(m_alpha.size());
    m_dev.Download(m_alpha.begin(), m_alpha.end(), out->viscosity.begin(), /*asked=*/true);
    out->invReference.resize(m_invReference.size());  // empty unless the walls have their own density
    // (Download copies nothing for an empty range: a copy of nothing would dereference a null begin)
    m_dev.Download(m_invReference.begin(), m_invReference.end(), out->invReference.begin(), /*asked=*/true);
  }

  int Count() const { return static_cast<int>(m_position.size()); }
  /// Linear indices of the cells holding wall particles (wall_density only; else empty).
  const Vector<uint32_t>& WallCells() const { return m_wallCells; }
  /// p_b / rho_b^2 of every wall particle (wall_density only), written by the walls' own pressure stage.
  float* PressureTerm() { return Raw(m_pressureTerm); }

 private:
  DeviceOps<Traits>& m_dev;
  Vector<Vec4> m_position;
  Vector<float> m_alpha;
  Vector<float> m_pressureTerm;  // per boundary particle, walls with their own density only
  Vector<float> m_invReference;
  Vector<uint32_t> m_start, m_end;
  Vector<uint8_t> m_near;        // per cell: a boundary particle in its 27 cells
  Vector<uint32_t> m_wallCells;
};

template <class Traits>
class BodyStore {
  template <class T>
  using Vector = typename Traits::template Vector<T>;

 public:
  explicit BodyStore(DeviceOps<Traits>& device) : m_dev(device) {}

  bool Empty() const { return m_hostStates.empty(); }
  int Count() const { return static_cast<int>(m_hostStates.size()); }
  int ParticleCount() const { return static_cast<int>(m_position.size()); }

  void Init(const std::vector<Vec4>& local, const std::vector<uint32_t>& bodyOf, const std::vector<float>& alpha,
            const std::vector<ShapePrimitive>& shapes, size_t cells) {
    const size_t nb = local.size();
    m_dev.Assign(m_local, local.begin(), local.end());
    m_dev.Assign(m_ofLocal, bodyOf.begin(), bodyOf.end());
    m_dev.Assign(m_alphaLocal, alpha.begin(), alpha.end());
    m_dev.Assign(m_shapes, shapes.begin(), shapes.end());
    m_dev.Resize(m_keys, nb);
    m_dev.Resize(m_order, nb);
    m_dev.Resize(m_position, nb);
    m_dev.Resize(m_velocity, nb);
    m_dev.Resize(m_of, nb);
    m_dev.Resize(m_force, nb);
    m_dev.Fill(m_force, Vec4{});
    m_dev.Resize(m_start, cells);
    m_dev.Resize(m_end, cells);
    m_dev.Resize(m_near, cells);
    m_dev.Fill(m_near, uint8_t{0});
  }

  void SetStates(const std::vector<BodyState>& states) {
    m_hostStates = states;
    m_dev.Assign(m_states, states.begin(), states.end());
  }

  /// The bodies' part of a grid view.
  void Fill(GridView* g) {
    g->bodyCount = Count();
    g->bodyStart = Raw(m_start);
    g->bodyEnd = Raw(m_end);
    g->body = Raw(m_position);
    g->bodyVelocity = Raw(m_velocity);
    g->movingNear = Raw(m_near);
  }

  /// The body particles at their start-of-step pose: cell codes, stable sort, world positions and rigid
  /// velocities in sorted order, cell ranges, and the near-cell flags over each body's bounding box.
  void Place(const GridView& g) {
    const int nb = static_cast<int>(m_local.size());
    m_dev.ForEach(nb,
                       BodyCellStage{g, Raw(m_states), Raw(m_local), Raw(m_ofLocal), Raw(m_keys), Raw(m_order)});
    m_dev.SortPairs(m_keys, m_order);
    m_dev.ForEach(nb,
                       BodyPlaceStage{Raw(m_states), Raw(m_local), Raw(m_ofLocal), Raw(m_alphaLocal), Raw(m_order),
                                      Raw(m_position), Raw(m_velocity), Raw(m_of)});
    m_dev.Fill(m_start, kEmptyCell);
    m_dev.ForEach(nb, CellRangeStage{g, Raw(m_position), Raw(m_keys), Raw(m_start), Raw(m_end), nb});
    m_dev.Fill(m_near, uint8_t{0});
    for (const BodyState& s : m_hostStates) {
      const MovingNearStage stage = MovingNearStage::Around(g, s.position, s.boundRadius, Raw(m_near));
      m_dev.ForEach(stage.Items(), stage);
    }
  }

  /// Each fluid particle's p_i / rho_i^2 for the reaction (written by the force stage or a solver).
  float* PressureTerm(int fluidCount) {
    m_dev.Resize(m_pressureTerm, static_cast<size_t>(fluidCount));
    return Raw(m_pressureTerm);
  }

  /// The fluid's force on each body particle (BodyReactionStage) from PressureTerm.
  void React(const GridView& g, const FluidView& fluid, const Physics& physics) {
    m_dev.ForEach(ParticleCount(),
                       BodyReactionStage{g, fluid, physics, Raw(m_pressureTerm), Raw(m_force)});
  }

  /// Fluid particles out of the bodies' solids at their end-of-step pose.
  void PushOut(const FluidView& fluid, const Physics& physics) {
    m_dev.ForEach(fluid.count,
                       PushOutStage{fluid, Raw(m_states), Raw(m_shapes), Count(), physics.bodyClearance});
  }

  void Loads(std::vector<BodyLoad>* out) const {
    out->assign(m_hostStates.size(), BodyLoad{});
    if (m_hostStates.empty()) return;
    std::vector<Vec4> force(m_force.size()), position(m_position.size());
    std::vector<uint32_t> of(m_of.size());
    m_dev.Download(m_force.begin(), m_force.end(), force.begin(), /*asked=*/true);
    m_dev.Download(m_position.begin(), m_position.end(), position.begin(), /*asked=*/true);
    m_dev.Download(m_of.begin(), m_of.end(), of.begin(), /*asked=*/true);
    // Serial sums in the sorted order: the same result on every run and thread count.
    std::vector<double> sums(6 * m_hostStates.size(), 0.0);
    for (size_t b = 0; b < force.size(); ++b) {
      const uint32_t k = of[b];
      if (k >= m_hostStates.size()) continue;
      const Vec3 f = Xyz(force[b]);
      const Vec3 t = Cross(Xyz(position[b]) - m_hostStates[k].position, f);
      double* s = &sums[6 * k];
      s[0] += f.x, s[1] += f.y, s[2] += f.z, s[3] += t.x, s[4] += t.y, s[5] += t.z;
    }
    for (size_t k = 0; k < out->size(); ++k) {
      const double* s = &sums[6 * k];
      (*out)[k].force = Vec3{static_cast<float>(s[0]), static_cast<float>(s[1]), static_cast<float>(s[2])};
      (*out)[k].torque = Vec3{static_cast<float>(s[3]), static_cast<float>(s[4]), static_cast<float>(s[5])};
    }
  }

  void Download(std::vector<Vec4>* position, std::vector<Vec4>* velocity) const {
    position->resize(m_position.size());
    velocity->resize(m_velocity.size());
    if (m_position.empty()) return;  // (thrust's host copy of nothing dereferences a null begin: UB)
    m_dev.Download(m_position.begin(), m_position.end(), position->begin(), /*asked=*/true);
    m_dev.Download(m_velocity.begin(), m_velocity.end(), velocity->begin(), /*asked=*/true);
  }

 private:
  DeviceOps<Traits>& m_dev;
  Vector<Vec4> m_local;         // body frame, w = Psi_b
  Vector<uint32_t> m_ofLocal;   // body index of each canonical particle
  Vector<float> m_alphaLocal;   // alpha of each canonical particle
  Vector<ShapePrimitive> m_shapes;
  Vector<BodyState> m_states;
  std::vector<BodyState> m_hostStates;  // empty: no bodies, no body work
  Vector<uint32_t> m_keys, m_order, m_of;
  Vector<Vec4> m_position, m_velocity, m_force;  // sorted
  Vector<uint32_t> m_start, m_end;
  Vector<uint8_t> m_near;
  Vector<float> m_pressureTerm;  // per fluid particle
};

}  // namespace sphxr::sim
