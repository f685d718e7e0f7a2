#pragma once
// Loops over a host ParticleStore with OpenMP: the particle loops,
// reductions, scratch arrays and store copies that the integrators and the
// step sequence ask of a system (integrate/leapfrog.hpp, rk2_adaptive.hpp,
// drivers/step_sequence.hpp). The CPU backend is built on it
// (solver/src/cpu_backend.hpp); so are the tests' small host systems.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rubble/integrate/leapfrog.hpp"
#include "rubble/particles/particle_store.hpp"
#include "rubble/particles/store_view.hpp"

namespace rubble {

template <class T>
using HostArray = std::vector<T>;

template <int D>
class HostLoops {
 public:
  template <class T>
  using Array = HostArray<T>;
  using Store = ParticleStore<D>;

  explicit HostLoops(ParticleStore<D>& ps) : ps_(ps) {}

  std::size_t size() const { return ps_.n; }
  StoreView<D> view() const { return ps_.view(); }

  // f(i) for every i < n: a particle's own work, which costs about the same
  // for every particle (static schedule; serial below 4097 particles, where
  // starting the threads costs more than the loop).
  template <class F>
  void for_each(const char* /*what*/, std::size_t n, F f) const {
#pragma omp parallel for if (n > 4096)
    for (std::size_t i = 0; i < n; ++i) f(static_cast<std::uint32_t>(i));
  }

  // op over f(i) for i < n, from init: one partial result per thread,
  // combined in turn (exact for the minima, maxima and counts it serves).
  template <class T, class F, class Op>
  T reduce(std::size_t n, F f, T init, Op op) const {
    T result = init;
#pragma omp parallel if (n > 4096)
    {
      T mine = init;
#pragma omp for nowait
      for (std::size_t i = 0; i < n; ++i) mine = op(mine, f(static_cast<std::uint32_t>(i)));
#pragma omp critical(rubble_host_reduce)
      result = op(result, mine);
    }
    return result;
  }

  IntegratorScratch<D, HostArray, ParticleStore<D>>& integrator_scratch() { return scratch_; }
  void save_state(ParticleStore<D>& copy) const { copy = ps_; }
  void restore_state(const ParticleStore<D>& copy) const { ps_ = copy; }
  static StoreView<D> view_of(ParticleStore<D>& copy) { return copy.view(); }

  // Frees what the integrators kept between steps (the run is over).
  void release_integrator_scratch() { scratch_ = {}; }

 private:
  ParticleStore<D>& ps_;
  IntegratorScratch<D, HostArray, ParticleStore<D>> scratch_;
};

}  // namespace rubble
