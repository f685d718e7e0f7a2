#pragma once
// The per-particle terms of conserved.csv (conserved_log.hpp), as plain data
// that the CPU sums in a loop and the CUDA backend with a device reduction.
// Sums run in double whatever Real is.
#include <cstddef>

#include "rubble/core/hd.hpp"
#include "rubble/particles/store_view.hpp"

namespace rubble {

struct ConservedSums {
  double mass = 0;
  double momentum[3] = {0, 0, 0};          // components beyond Dim are 0
  double angular_momentum[3] = {0, 0, 0};  // L = sum m x cross v; 2-D: only [2]
  double kinetic = 0;                      // sum 1/2 m |v|^2
  double internal = 0;                     // sum m u
  double gravitational = 0;                // 1/2 sum m phi (self-gravity) - sum m g.x (external field)

  RUBBLE_HD ConservedSums operator+(const ConservedSums& o) const {
    ConservedSums r;
    r.mass = mass + o.mass;
    for (int k = 0; k < 3; ++k) {
      r.momentum[k] = momentum[k] + o.momentum[k];
      r.angular_momentum[k] = angular_momentum[k] + o.angular_momentum[k];
    }
    r.kinetic = kinetic + o.kinetic;
    r.internal = internal + o.internal;
    r.gravitational = gravitational + o.gravitational;
    return r;
  }
};

// Particle i's terms. With the missing axes zero, L = m x cross v gives L_z
// alone in 2-D and nothing in 1-D.
// A uniform external acceleration g (simulation.gravity) adds the potential
// energy -m g.x of free particles (boundary particles are held, so their
// potential is constant and left out).
template <int D>
RUBBLE_HD_INLINE ConservedSums conserved_particle(const StoreView<D>& s, std::size_t i,
                                                  const Vec<D>& g = Vec<D>::zero()) {
  ConservedSums r;
  const double m = s.m[i];
  double x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
  for (int k = 0; k < D; ++k) {
    x[k] = s.x[i][k];
    v[k] = s.v[i][k];
  }
  r.mass = m;
  for (int k = 0; k < 3; ++k) r.momentum[k] = m * v[k];
  r.angular_momentum[0] = m * (x[1] * v[2] - x[2] * v[1]);
  r.angular_momentum[1] = m * (x[2] * v[0] - x[0] * v[2]);
  r.angular_momentum[2] = m * (x[0] * v[1] - x[1] * v[0]);
  r.kinetic = 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (s.u) r.internal = m * s.u[i];
  if (s.phi) r.gravitational = 0.5 * m * double(s.phi[i]);
  if (!(s.boundary && s.boundary[i]))
    for (int k = 0; k < D; ++k) r.gravitational -= m * double(g[k]) * x[k];
  return r;
}

}  // namespace rubble
