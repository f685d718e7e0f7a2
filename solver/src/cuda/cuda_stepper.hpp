#pragma once
// The CUDA backend behind the time loop's interface (run.cpp; the CPU one is
// CpuStepper there). The particles live on the device for the whole run:
// the constructor uploads the store once, every step runs as kernels over
// the device arrays, and the host copy is refreshed only when host() is
// asked for (snapshots, the final state, a diagnostic). The loop bodies are
// those of the CPU driver (rubble/drivers/particle_rates.hpp, the
// integrators' per-particle steps, conserved_sums.hpp).
//
// Host-only header: no CUDA types, so run.cpp compiles with the C++ compiler.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/core/region.hpp"
#include "rubble/integrate/rk2_adaptive.hpp"
#include "rubble/io/conserved_log.hpp"
#include "rubble/io/conserved_sums.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/physics/rigid_body.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

// cuda_backend_counts(): rubble/run.hpp.

template <int D>
class CudaStepper {
 public:
  // Uploads ps, sorts along the space-filling curve and evaluates the
  // right-hand side once. Throws RunError for what the backend cannot run.
  // `resumed`: ps holds a restart snapshot's state, rates included: it is
  // uploaded as it is, neither sorted nor evaluated again.
  CudaStepper(const Scene& scene, ParticleStore<D>& ps, const Box<D>& domain, bool resumed = false);
  ~CudaStepper();
  CudaStepper(const CudaStepper&) = delete;
  CudaStepper& operator=(const CudaStepper&) = delete;

  void sort_particles();
  double dt_limit();
  void leapfrog(double dt);
  Rk2Result rk2(double dt, double tol, double dt_min);
  void damp(double f);
  // Bodies as wholes (relaxation in a body's frame, the launch of a collision).
  BodySums<D> body_sums(std::int32_t lo, std::int32_t hi);
  void damp_body(std::int32_t lo, std::int32_t hi, double f, Vec<D> mean, Vec<D> keep);
  void add_body_velocity(std::int32_t lo, std::int32_t hi, Vec<D> V, Vec<3> w, Vec<D> centre);
  // Rigid tools (physics/rigid_body.hpp): their states (a restart's list),
  // and the force and torque of the rest on a body's held particles.
  std::vector<double> tool_state() const;
  void set_tool_state(const std::vector<double>& list);
  ForceSums<D> held_force(std::int32_t lo, std::int32_t hi, Vec<D> point);
  // The free mass by material inside a measuring region ([[regions]]).
  RegionSums region_sums(const Region& r, int tool);
  std::size_t first_non_finite();
  ConservedRecord conserved(double t, std::int64_t step, double dt);
  // The energy bookkeeping (StepSequence): books, watchdog retries.
  const EnergyBooks& energy_books() const;
  void set_energy_books(const EnergyBooks& b);
  std::int64_t energy_retries() const;
  const ParticleStore<D>& host();  // downloads the device state into ps
  // The state check's last good state: the snapshot fields copied on the
  // device before each step (no host traffic), downloaded by last_good()
  // only when a step failed.
  void keep_good();
  const ParticleStore<D>& last_good();
  std::size_t size() const;        // the particle count (no download)
  std::int64_t bytes_downloaded() const;  // device-to-host bytes of host() so far
  std::int64_t correction_fallbacks() const;
  std::int64_t evaluations() const;
  bool solid() const;
  static constexpr const char* name = "cuda";

  // The device state and kernels (cuda_stepper.cu). Public only because
  // nvcc's extended __device__ lambdas may not live in a private nested class.
  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace rubble
