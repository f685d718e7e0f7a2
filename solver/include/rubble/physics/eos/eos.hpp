#pragma once
// One entry point for every equation of state: the material's EOS is chosen
// at run time from the scene and dispatched here. Each EOS returns the
// pressure and the squared sound speed from (rho, u).
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/physics/eos/ideal_gas.hpp"

namespace rubble {

enum class EosKind : int { IdealGas = 0 };

// Plain-old-data so it can be copied to a device as it is.
struct EosParams {
  EosKind kind = EosKind::IdealGas;
  IdealGasParams ideal_gas{Real(1.4)};
};

struct EosState {
  Real p;   // pressure
  Real c2;  // squared sound speed
};

RUBBLE_HD_INLINE EosState eos_evaluate(const EosParams& e, Real rho, Real u) {
  switch (e.kind) {
    case EosKind::IdealGas:
    default:
      return {ideal_gas_pressure(e.ideal_gas, rho, u), ideal_gas_sound_speed2(e.ideal_gas, rho, u)};
  }
}

// The specific internal energy that gives pressure p at density rho, used
// to set initial conditions given in pressure.
RUBBLE_HD_INLINE Real eos_internal_energy_from_pressure(const EosParams& e, Real rho, Real p) {
  switch (e.kind) {
    case EosKind::IdealGas:
    default:
      return p / ((e.ideal_gas.gamma - Real(1)) * rho);
  }
}

}  // namespace rubble
