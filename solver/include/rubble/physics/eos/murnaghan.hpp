#pragma once
// Murnaghan equation of state (seed paper eq. 7; Murnaghan 1944, PNAS 30:244):
//   p  = (K0/n) [(ρ/ρ0)^n − 1]
//   c² = dp/dρ = (K0/ρ0) (ρ/ρ0)^(n−1)
// Isothermal: the specific internal energy does not enter. n = 1 is the
// linear "weakly compressible" law p = K0 (ρ/ρ0 − 1) of the rubber rings
// (Gray, Monaghan & Swift 2001). The tension cut-off (EosLimits::rho_limit)
// is applied by eos.hpp, not here.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"

namespace rubble {

struct MurnaghanParams {
  Real rho0 = 0;  // reference density ρ0 > 0 [kg/m³]
  Real K0 = 0;    // zero-pressure bulk modulus K0 > 0 [Pa]
  Real n = 0;     // pressure derivative of the bulk modulus, n > 0
};

// (η^n − 1)/n written as expm1(n ln η)/n: exact to round-off near η = 1,
// where the difference of two numbers close to 1 would lose digits.
RUBBLE_HD_INLINE Real murnaghan_pressure(const MurnaghanParams& m, Real rho) {
  const Real eta = rho / m.rho0;
  return m.K0 / m.n * std::expm1(m.n * std::log(eta));
}

RUBBLE_HD_INLINE Real murnaghan_sound_speed2(const MurnaghanParams& m, Real rho) {
  const Real eta = rho / m.rho0;
  return m.K0 / m.rho0 * std::pow(eta, m.n - Real(1));
}

}  // namespace rubble
