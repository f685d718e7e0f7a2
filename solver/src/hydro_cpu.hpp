#pragma once
// The CPU (OpenMP) driver of the hydrodynamic right-hand side. It only loops
// and moves data: every formula it applies is a RUBBLE_HD function from
// rubble/physics/, shared with the CUDA driver and the unit tests.
#include <cstdint>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/gravity/self_gravity.hpp"
#include "rubble/neighbors/cell_list.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/physics/artificial_viscosity.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/kernel_type.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

// Per-material coefficients in a device-friendly form.
struct MaterialParams {
  EosParams eos;
  ViscosityParams av;
  Real alpha_u;  // artificial conductivity (0 = off)
};

std::vector<MaterialParams> material_params_from_scene(const Scene& scene);

template <int D>
class HydroCpu {
 public:
  HydroCpu(const Scene& scene, ParticleStore<D>& ps, const Box<D>& domain);

  // Sort the particles along the space-filling curve (call between steps).
  void sort_particles();
  // Density (and h), pressure, sound speed, and all time derivatives at the
  // current state of the store.
  void evaluate();
  // Largest stable time step at the last evaluated state (Courant and force limits).
  Real dt_limit() const;

  const Box<D>& domain() const { return domain_; }
  bool summation_density() const { return summation_; }
  std::int64_t neighbor_rebuilds() const { return rebuilds_; }

 private:
  void build_neighbors(const std::vector<Real>& search_radius);
  void summation_density_and_h();
  void h_from_continuity_density();
  void equation_of_state();
  void rates();
  void self_gravity();

  ParticleStore<D>& ps_;
  Box<D> domain_;
  std::vector<MaterialParams> materials_;
  KernelType kernel_;
  Real hfact_;
  Real courant_, force_factor_;
  bool summation_;
  CellList<D> cells_;
  NeighborLists nbrs_;
  std::vector<Real> search_radius_;
  std::int64_t rebuilds_ = 0;
  SelfGravity gravity_;  // off unless the scene's [gravity] turns it on (3-D)
};

}  // namespace rubble
