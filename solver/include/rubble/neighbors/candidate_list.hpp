#pragma once
// A particle's candidate neighbours gathered once and offered again: the
// summation-density kernel of the CUDA backend (cuda_stepper.cu) walks the
// grid once per particle into this list, in the thread's own (local)
// memory, and its smoothing-length Newton iterations (particle_rates.hpp:
// summation_density_particle, two to five passes over the neighbours)
// read the list instead of walking the grid again. The list holds the b
// within a's own search radius (GridOwnRadius in uniform_grid.hpp), all a
// Newton iteration can use, since its h never exceeds that radius.
//
// Capacity is fixed at compile time (no allocation on the device). A
// particle with more candidates does not fit: gather() returns false and
// the caller walks the grid on every iteration instead, offering the same
// particles in the same order, so the results do not depend on which path
// ran.
#include <cstdint>

#include "rubble/core/hd.hpp"

namespace rubble {

// Room for the neighbours within kSearchSkin H = 1.05 H (the
// summation-density search radius, search_radius.hpp) at the defaults of
// kernels.hpp with room to spare: in 3-D the Wendland C6 kernel has about
// 180 within H, so ~210 within 1.05 H; in 2-D ~45; in 1-D 8. A particle
// that searched again at kRegrowSkin H = 1.3 H (~395 in 3-D for Wendland C6)
// may not fit: it walks the grid instead (same result).
template <int D>
inline constexpr std::uint32_t kCandidateListCapacity = D == 1 ? 32 : D == 2 ? 128 : 384;

template <std::uint32_t Capacity>
struct CandidateList {
  std::uint32_t n = 0;
  bool overflow = false;
  std::uint32_t idx[Capacity];

  // Gather every b that `each` offers; false when they did not all fit.
  template <class Each>
  RUBBLE_HD bool gather(const Each& each) {
    n = 0;
    overflow = false;
    each([&](std::uint32_t b) {
      if (n < Capacity) idx[n++] = b;
      else overflow = true;
    });
    return !overflow;
  }

  // The gathered b, in the order they were offered (an `each`).
  template <class F>
  RUBBLE_HD void operator()(F&& f) const {
    for (std::uint32_t k = 0; k < n; ++k) f(idx[k]);
  }
};

}  // namespace rubble
