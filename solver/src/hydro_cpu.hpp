#pragma once
// The CPU (OpenMP) driver of the hydrodynamic right-hand side. It only loops
// and moves data: every formula it applies is a RUBBLE_HD function from
// rubble/physics/, shared with the CUDA driver and the unit tests.
#include <cstdint>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/drivers/material_params.hpp"
#include "rubble/drivers/particle_rates.hpp"
#include "rubble/gravity/self_gravity.hpp"
#include "rubble/neighbors/cell_list.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/physics/artificial_viscosity.hpp"
#include "rubble/physics/eos/eos.hpp"
#include "rubble/physics/kernel_type.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

// Wall seconds spent in each part of the right-hand side, summed over the
// run (what `rubble run --timings` and the benchmarks print).
struct RhsPhaseSeconds {
  double neighbours = 0;  // cell list build and neighbour lists
  double density = 0;     // summation density and h (or h from continuity density)
  double eos = 0;         // pressure and sound speed (and the plastic return in an evaluation)
  double forces = 0;      // rates: pressure, viscosity, conductivity, stress, gravity, XSPH, walls
  double end_step = 0;    // porosity, plasticity and shifting after a step
};

template <int D>
class HydroCpu {
 public:
  HydroCpu(const Scene& scene, ParticleStore<D>& ps, const Box<D>& domain);

  // Sort the particles along the space-filling curve (call between steps).
  void sort_particles();
  // Density (and h), pressure, sound speed, and all time derivatives at the
  // current state of the store.
  void evaluate();
  // The same, for a leapfrog step with the staggered stress update
  // (simulation.stress_update = "staggered", leapfrog.hpp): the store holds
  // v_{1/2} and the step's starting S and rho; between the two solid passes
  // S and rho advance by dt with pass 1's rates (staggered_update_particle),
  // so the forces are those of the step's end.
  void evaluate_staggered(Real dt);
  // After the integrator's last update of a step: porous states back onto
  // the loading envelope, and the plastic return mapping (with plastic-strain
  // accumulation) at the step's final state. Nothing when neither is used.
  // alpha_start: the distention at the start of the step (porous runs).
  void end_step(const Real* alpha_start, Real dt);
  // Largest stable time step at the last evaluated state (Courant and force limits).
  Real dt_limit();

  const Box<D>& domain() const { return domain_; }
  bool summation_density() const { return summation_; }
  std::int64_t neighbor_rebuilds() const { return rebuilds_; }
  // Continuity density: keep the lists across evaluations while they hold
  // (default); off, every evaluation searches (RunOptions::keep_neighbour_lists).
  void keep_neighbour_lists(bool on) { keep_lists_ = on; }
  // Frees the neighbour lists, the cell list and the search radii once the
  // run is over (the next evaluation would rebuild them), so that the final
  // state's copy does not add to the run's peak memory (issue #14).
  void release_work_memory() {
    nbrs_ = NeighborLists{};
    cells_ = CellList<D>{};
    std::vector<Real>().swap(search_radius_);
    std::vector<Vec<D>>().swap(x_at_search_);
    lists_in_order_ = false;
    std::vector<SolidInverses>().swap(solid_inv_);
    std::vector<GradientSums<D>>().swap(grad_sums_);
    std::vector<Mat<D>>().swap(sd_sums_);
    std::vector<Mat<D>>().swap(stagger_Lm_);
    std::vector<Real>().swap(stagger_du_);
    std::vector<Real>().swap(as_chi_);
  }
  // Calls of evaluate() so far (each evaluates every particle once).
  std::int64_t evaluations() const { return evaluations_; }
  // Solids: does the run evolve the deviatoric stress (the Solid feature set)?
  bool solid() const { return solid_; }
  // Kernel-gradient correction: particle evaluations where the correction
  // matrix was ill-conditioned and the identity was used instead (summed
  // over all evaluations), and the same for the last evaluation.
  std::int64_t correction_fallbacks() const { return fallbacks_total_; }
  std::int64_t correction_fallbacks_last() const { return fallbacks_last_; }
  const RhsPhaseSeconds& phase_seconds() const { return phases_; }

 private:
  RhsContext<D> context();  // pointers into the store: valid until it is resized
  void build_neighbors(const std::vector<Real>& search_radius);
  void summation_density_and_h();
  void h_from_continuity_density();
  bool lists_still_hold() const;
  void equation_of_state();
  void rates();        // feature set Hydro: pressure, viscosity, conductivity
  void solid_rates();  // feature set Solid: full stress, Jaumann rate, artificial stress
  void hold_boundaries();
  void self_gravity();
  void xsph_velocity();  // XSPH correction to dx/dt (when simulation.xsph > 0)
  void plastic_return(bool accumulate);  // yield: S back onto the surface
  void shift_particles(Real dt);  // particle shifting after an accepted step
  void wall_extrapolation();  // extrapolated walls: state from the free particles
  void body_force();      // simulation.gravity

  ParticleStore<D>& ps_;
  Box<D> domain_;
  std::vector<MaterialParams> materials_;
  KernelType kernel_;
  Real hfact_;
  Real courant_, force_factor_, h_tolerance_;
  bool summation_;
  CellList<D> cells_;
  NeighborLists nbrs_;
  std::vector<Real> search_radius_;
  // Continuity density: the positions at the last search, and whether its
  // lists still index the particles (a sort permutes them); the lists are
  // kept while every pair that can interact is still in them
  // (lists_still_hold, hydro_cpu.cpp)
  std::vector<Vec<D>> x_at_search_;
  bool lists_in_order_ = false;
  bool keep_lists_ = true;
  std::int64_t rebuilds_ = 0;
  SelfGravity gravity_;  // off unless the scene's [gravity] turns it on (3-D)
  bool solid_ = false;
  bool kernel_correction_ = false;
  bool stress_diffusion_ = false;  // a solid material diffuses its deviator
  bool artificial_stress_ = false;
  std::vector<Mat<D>> art_R_;   // solids with artificial stress: R_a (scratch)
  Real stagger_dt_ = 0;         // inside evaluate_staggered: its dt (0 otherwise)
  std::vector<Real> as_chi_;    // evaluate_staggered with artificial stress: chi_a (scratch)
  std::vector<Mat<D>> stagger_Lm_;  // evaluate_staggered: pass 1's mass-weighted gradient (scratch)
  std::vector<Real> stagger_du_;    // evaluate_staggered: the energy rate's correction (scratch)
  std::vector<SolidInverses> solid_inv_;  // solids: 1/H, 1/rho^2 per particle (scratch of solid_rates)
  std::vector<GradientSums<D>> grad_sums_;  // solids: pass 1's neighbour sums (scratch of solid_rates)
  std::vector<Mat<D>> sd_sums_;  // ... and the stress diffusion's, when a material diffuses (else empty)
  std::int64_t fallbacks_total_ = 0, fallbacks_last_ = 0;
  Real xsph_epsilon_ = 0;  // 0 = off
  Real shifting_ = 0;       // particle shifting coefficient A (0 = off)
  std::vector<Vec<D>> shift_;  // particle shifting: this step's shifts (scratch)
  bool porosity_ = false, plasticity_ = false, damage_ = false, body_force_ = false, wall_extrapolation_ = false;
  bool viscosity_switch_ = false;  // a material has the viscosity switch (end-of-step bounds)
  bool coulomb_walls_ = false;     // a wall has Coulomb friction (end-of-step friction anchors)
  Vec<D> g_ = Vec<D>::zero();  // simulation.gravity
  std::int64_t evaluations_ = 0;
  RhsPhaseSeconds phases_;
};

}  // namespace rubble
