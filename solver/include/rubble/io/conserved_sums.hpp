#pragma once
// The per-particle terms of conserved.csv (conserved_log.hpp), as plain data
// that the CPU sums in a loop and the CUDA backend with a device reduction.
// Sums run in double whatever Real is.
#include <cmath>
#include <cstddef>
#include <cstdint>

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

// Particle i's energy in three parts: kinetic 1/2 m |v|^2, internal m u and
// gravitational, 1/2 m phi (self-gravity) minus m g.x for a free particle in
// a uniform external field g (simulation.gravity; boundary particles are
// held, so their potential is constant and left out).
struct EnergyTerms {
  double kinetic = 0, internal = 0, gravitational = 0;
};
template <int D>
RUBBLE_HD_INLINE EnergyTerms energy_terms_particle(const StoreView<D>& s, std::size_t i, const Vec<D>& g) {
  EnergyTerms e;
  const double m = s.m[i];
  double v2 = 0;
  for (int k = 0; k < D; ++k) v2 += double(s.v[i][k]) * double(s.v[i][k]);
  e.kinetic = 0.5 * m * v2;
  if (s.u) e.internal = m * s.u[i];
  if (s.phi) e.gravitational = 0.5 * m * double(s.phi[i]);
  if (!(s.boundary && s.boundary[i]))
    for (int k = 0; k < D; ++k) e.gravitational -= m * double(g[k]) * double(s.x[i][k]);
  return e;
}

// Particle i's terms. With the missing axes zero, L = m x cross v gives L_z
// alone in 2-D and nothing in 1-D.
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
  const EnergyTerms e = energy_terms_particle<D>(s, i, g);
  r.kinetic = e.kinetic;
  r.internal = e.internal;
  r.gravitational = e.gravitational;
  return r;
}

// Mass and mass-weighted position and velocity of a body (StepSequence::body_sums).
template <int D>
struct BodySums {
  double m = 0;
  Vec<D> mx{}, mv{};
};
template <int D>
struct BodySumOp {
  RUBBLE_HD BodySums<D> operator()(const BodySums<D>& a, const BodySums<D>& b) const {
    BodySums<D> r;
    r.m = a.m + b.m;
    r.mx = a.mx + b.mx;
    r.mv = a.mv + b.mv;
    return r;
  }
};

// The energy watchdog's sums (drivers/step_sequence.hpp): the total energy
// and the energy scale its bound is a fraction of.
struct EnergySums {
  double total = 0;
  double scale = 0;
  RUBBLE_HD EnergySums operator+(const EnergySums& o) const { return {total + o.total, scale + o.scale}; }
};

// Particle i's total energy (energy_terms_particle) and its share of the
// scale: every energy it holds or can exchange, taken positive,
//   m (1/2 |v|^2 + |u| + (|p| + |S|)/rho) + 1/2 m |phi|,
// (|p| + |S|)/rho the work its stress can do per unit mass (so a body at rest
// under load has a scale though its energy may be zero); the body force's
// potential, which depends on the origin, is not part of it.
template <int D>
RUBBLE_HD_INLINE EnergySums energy_sums_particle(const StoreView<D>& s, std::size_t i, const Vec<D>& g) {
  const EnergyTerms e = energy_terms_particle<D>(s, i, g);
  const double m = s.m[i];
  double stress = s.p ? std::fabs(double(s.p[i])) : 0.0;
  if (s.S) stress += std::sqrt(double(double_dot(s.S[i], s.S[i])));
  double scale = e.kinetic + std::fabs(e.internal) + m * stress / double(s.rho[i]);
  if (s.phi) scale += 0.5 * m * std::fabs(double(s.phi[i]));
  return {e.kinetic + e.internal + e.gravitational, scale};
}

// What the energy bookkeeping has summed over the accepted steps of a run
// (conserved.csv's booked columns; carried by restart snapshots).
struct EnergyBooks {
  double wall_work = 0;          // work of the held particles on the rest [J]
  double floor_energy = 0;       // energy the internal-energy floor added [J]
  std::int64_t floor_events = 0;  // particle-steps raised to the floor
  double wall_power = 0;         // the held particles' power at the last evaluation [W]
};

}  // namespace rubble
