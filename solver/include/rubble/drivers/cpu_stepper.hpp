#pragma once
// The CPU (OpenMP) backend and the CPU stepper the time loop drives.
//
// CpuBackend<D> supplies what the step sequence (step_sequence.hpp) asks
// of a backend, over a host ParticleStore: OpenMP loops (HostLoops), the
// sort along the space-filling curve, the cell-list neighbour search with
// lists kept across continuity-density evaluations while they hold, the
// CPU's own pair loops that take each pair once (hydro and both solid
// passes), and self-gravity (direct or the octree). It only loops and
// moves data: every formula is a RUBBLE_HD function of rubble/physics/.
//
// CpuStepper<D> is the time loop's interface on the CPU (run.cpp; the CUDA
// one is CudaStepper): the scene's RunPhysics, the backend and the step
// sequence, plus the host copies the loop asks for.
// Implemented in solver/src/cpu_stepper.cpp.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/drivers/host_loops.hpp"
#include "rubble/drivers/particle_rates.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/drivers/step_sequence.hpp"
#include "rubble/gravity/self_gravity.hpp"
#include "rubble/io/conserved_log.hpp"
#include "rubble/neighbors/cell_list.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

// The neighbour lists as the `each` of rubble/drivers/particle_rates.hpp.
struct ListNeighbors {
  const NeighborLists& nbrs;
  std::uint32_t a;
  template <class F>
  void operator()(F&& f) const {
    nbrs.for_each(a, f);
  }
};

template <int D>
class CpuBackend : public HostLoops<D> {
 public:
  using Neighbours = ListNeighbors;
  using OwnNeighbours = ListNeighbors;  // the lists hold each particle's own radius too

  CpuBackend(const RunPhysics& physics, ParticleStore<D>& ps, const Box<D>& domain);

  const MaterialParams* materials() const { return materials_.data(); }

  // f(i, its neighbours) for every particle: the cost varies with the
  // neighbour count, so threads take blocks of 256 as they finish.
  template <class F>
  void for_each_neighbours(const char* /*what*/, F f) const {
    const std::size_t n = this->size();
#pragma omp parallel for schedule(dynamic, 256)
    for (std::size_t a = 0; a < n; ++a) {
      const std::uint32_t ia = static_cast<std::uint32_t>(a);
      f(ia, ListNeighbors{nbrs_, ia});
    }
  }
  template <class F>
  void for_each_in_own_radius(const char* what, const Real* /*R*/, F f) const {
    for_each_neighbours(what, f);
  }

  template <class T>
  static void zero(HostArray<T>& a) {
    for (T& x : a) x = T{};
  }
  static std::int64_t read_count(const HostArray<unsigned long long>& a) { return std::int64_t(a[0]); }

  void sort(const Box<D>& domain);
  // The lists of every pair within max(R_a, R_b). keepable: continuity
  // density, whose lists search_still_holds may keep.
  void search(const Real* R, bool keepable);
  // The last keepable search listed every pair closer than max(R_a, R_b).
  // A pair that interacts now is closer than max(h_a, h_b) and was at most
  // d_a + d_b <= 2 d farther apart at the search (d: the largest distance
  // any particle has moved since), so it is listed if every particle has
  // h + 2 d <= R.
  bool search_still_holds(const Real* R) const;
  void self_gravity(const StoreView<D>& s);

  bool hydro_pair_once(const RhsContext<D>& c);
  bool solid_gradients_pair_once(const RhsContext<D>& c, unsigned long long* fallbacks);
  bool solid_forces_pair_once(const RhsContext<D>& c);

  // Continuity density: keep the lists across evaluations while they hold
  // (default); off, every evaluation searches (RunOptions::keep_neighbour_lists).
  void keep_neighbour_lists(bool on) { keep_lists_ = on; }
  std::int64_t searches() const { return searches_; }
  // Frees the lists, the cell list and the pair loops' scratch (the run is over).
  void release_work_memory();

 private:
  ParticleStore<D>& ps_;
  std::vector<MaterialParams> materials_;
  Box<D> domain_;
  CellList<D> cells_;
  NeighborLists nbrs_;
  // Continuity density: the positions at the last search, and whether its
  // lists still index the particles (a sort permutes them)
  std::vector<Vec<D>> x_at_search_;
  bool lists_in_order_ = false;
  bool keep_lists_ = true;
  std::int64_t searches_ = 0;
  SelfGravity gravity_;  // off unless the scene's [gravity] turns it on (3-D)
  std::vector<GradientSums<D>> grad_sums_;  // solids: pass 1's neighbour sums
  std::vector<Mat<D>> sd_sums_;             // ... and the stress diffusion's, when a material diffuses
};

template <int D>
class CpuStepper {
 public:
  // `resumed`: the store holds a restart snapshot's state, rates included,
  // in the order it was written: neither sorted nor evaluated again (also
  // what a caller that sorts and evaluates itself asks for).
  CpuStepper(const Scene& scene, ParticleStore<D>& ps, const Box<D>& domain, bool resumed, bool keep_lists = true);
  CpuStepper(const CpuStepper&) = delete;
  CpuStepper& operator=(const CpuStepper&) = delete;

  void sort_particles() { steps_.sort_particles(); }
  void evaluate() { steps_.evaluate(); }
  double dt_limit() { return double(steps_.dt_limit()); }
  void leapfrog(double dt) { steps_.leapfrog(Real(dt)); }
  Rk2Result rk2(double dt, double tol, double dt_min) { return steps_.rk2(Real(dt), Real(tol), Real(dt_min)); }
  void damp(double f) { steps_.damp(Real(f)); }
  // Bodies as wholes (relaxation in a body's frame, the launch of a collision).
  BodySums<D> body_sums(std::int32_t lo, std::int32_t hi) { return steps_.body_sums(lo, hi); }
  void damp_body(std::int32_t lo, std::int32_t hi, double f, Vec<D> mean, Vec<D> keep) {
    steps_.damp_body(lo, hi, Real(f), mean, keep);
  }
  void add_body_velocity(std::int32_t lo, std::int32_t hi, Vec<D> V, Vec<3> w, Vec<D> centre) {
    steps_.add_body_velocity(lo, hi, V, w, centre);
  }
  // Rigid tools (physics/rigid_body.hpp): their states (a restart's list),
  // and the force and torque of the rest on a body's held particles.
  std::vector<double> tool_state() const { return steps_.tool_state(); }
  void set_tool_state(const std::vector<double>& list) { steps_.set_tool_state(list); }
  ForceSums<D> held_force(std::int32_t lo, std::int32_t hi, Vec<D> point) { return steps_.held_force(lo, hi, point); }
  // The free mass by material inside a measuring region ([[regions]]).
  RegionSums region_sums(const Region& r, int tool) { return steps_.region_sums(r, tool); }
  // Index of the first particle with a non-finite state, or n.
  std::size_t first_non_finite() { return steps_.check_state().first_bad; }
  ConservedRecord conserved(double t, std::int64_t step, double dt) const {
    ConservedRecord r = measure_conserved<D>(ps_, t, step, dt, g_);
    r.book(steps_.energy_books().wall_work, steps_.energy_books().floor_energy);
    return r;
  }
  // The energy bookkeeping (StepSequence): books, watchdog retries.
  const EnergyBooks& energy_books() const { return steps_.energy_books(); }
  void set_energy_books(const EnergyBooks& b) { steps_.set_energy_books(b); }
  std::int64_t energy_retries() const { return steps_.energy_retries(); }
  const ParticleStore<D>& host() const { return ps_; }  // the state, on the host
  // The state check's last good state: the snapshot fields as they were
  // before the step, written to NAME.failed.h5 when the step fails. Those a
  // step changes are copied before each step; the constant ones (mass,
  // material, id, boundary flags, flaws) are taken from the store only when
  // the state is asked for, since no step changes them and the particles are
  // sorted only between steps (issue #14: 20 bytes per particle less held,
  // and less copied every step).
  void keep_good();
  const ParticleStore<D>& last_good();
  // After the time loop: the last good state and the driver's neighbour
  // data are no longer needed (run_loop, before it copies the final state).
  void release_work_memory();
  std::size_t size() const { return ps_.n; }
  std::int64_t bytes_downloaded() const { return 0; }  // the state never leaves the host
  std::int64_t correction_fallbacks() const { return steps_.correction_fallbacks(); }
  std::int64_t evaluations() const { return steps_.evaluations(); }
  bool solid() const { return physics_.on.solid; }
  const RhsPhaseSeconds& rhs_phase_seconds() const { return steps_.phase_seconds(); }
  std::int64_t neighbour_searches() const { return backend_.searches(); }
  static constexpr const char* name = "cpu";

 private:
  ParticleStore<D>& ps_;
  RunPhysics physics_;
  CpuBackend<D> backend_;
  StepSequence<D, CpuBackend<D>> steps_;
  ParticleStore<D> good_;       // keep_good()
  Vec<D> g_ = Vec<D>::zero();  // simulation.gravity (its potential energy)
};

}  // namespace rubble
