#pragma once
// The computational domain: an axis-aligned box, periodic in any subset of
// axes. Open axes only bound the particles for the spatial order; periodic
// axes wrap positions and separations (minimum-image convention).
#include "rubble/core/vec.hpp"

namespace rubble {

template <int D>
struct Box {
  Vec<D> lo = Vec<D>::zero();
  Vec<D> hi = Vec<D>::zero();
  bool periodic[D] = {};

  RUBBLE_HD Real length(int axis) const { return hi[axis] - lo[axis]; }

  // Separation a - b with the minimum-image convention on periodic axes.
  RUBBLE_HD Vec<D> separation(const Vec<D>& a, const Vec<D>& b) const {
    Vec<D> d = a - b;
    for (int k = 0; k < D; ++k) {
      if (!periodic[k]) continue;
      const Real L = hi[k] - lo[k];
      if (d[k] > Real(0.5) * L) d[k] -= L;
      else if (d[k] < Real(-0.5) * L) d[k] += L;
    }
    return d;
  }

  // Map a position back into [lo, hi) on periodic axes.
  RUBBLE_HD Vec<D> wrap(Vec<D> x) const {
    for (int k = 0; k < D; ++k) {
      if (!periodic[k]) continue;
      const Real L = hi[k] - lo[k];
      while (x[k] >= hi[k]) x[k] -= L;
      while (x[k] < lo[k]) x[k] += L;
    }
    return x;
  }
};

}  // namespace rubble
