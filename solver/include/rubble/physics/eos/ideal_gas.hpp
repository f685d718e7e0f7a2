#pragma once
// Ideal-gas equation of state (seed paper eq. 10):
//   p = (gamma - 1) rho u,   c_s^2 = gamma p / rho = gamma (gamma - 1) u.
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"

namespace rubble {

struct IdealGasParams {
  Real gamma;
};

RUBBLE_HD_INLINE Real ideal_gas_pressure(const IdealGasParams& g, Real rho, Real u) {
  return (g.gamma - Real(1)) * rho * u;
}

RUBBLE_HD_INLINE Real ideal_gas_sound_speed2(const IdealGasParams& g, Real /*rho*/, Real u) {
  return g.gamma * (g.gamma - Real(1)) * u;
}

}  // namespace rubble
