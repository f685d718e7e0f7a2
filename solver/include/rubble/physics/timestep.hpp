#pragma once
// Time-step limits (PHYSICS.md §1; Monaghan 1992, ARA&A 30:543). hM is
// Monaghan's smoothing length (half of rubble's support radius, see
// artificial_viscosity.hpp).
//   Courant:  dt <= C hM / (c + 0.6 (alpha c + beta max|mu|))
//   force:    dt <= f sqrt(hM / |a|)
// 0.6 is Monaghan's coefficient. Until issue #14 rubble used PHYSICS.md's
// "more conservative variant" 1.2, which cost it 32 % more steps than
// Phantom on the 3-D Sedov blast at the same Courant number
// (docs/performance.md); the ladder passes with 0.6 as it did with 1.2.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"

namespace rubble {

RUBBLE_HD_INLINE Real courant_dt(Real courant, Real hM, Real c, Real alpha, Real beta, Real mu_max) {
  const Real speed = c + Real(0.6) * (alpha * c + beta * mu_max);
  return speed > Real(0) ? courant * hM / speed : Real(1e30);
}

RUBBLE_HD_INLINE Real force_dt(Real factor, Real hM, Real a_abs) {
  return a_abs > Real(0) ? factor * std::sqrt(hM / a_abs) : Real(1e30);
}

}  // namespace rubble
