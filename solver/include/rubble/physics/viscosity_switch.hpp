#pragma once
// A time-dependent artificial-viscosity coefficient per particle (the
// "switch" of Morris & Monaghan 1997, J. Comput. Phys. 136:41, with the
// bounded source of Rosswog, Davies, Thielemann & Piran 2000, A&A 360:171;
// docs/physics.md, "Viscosity switch"). Each particle of a material with
// viscosity.switch = "morris_monaghan" carries its own alpha_a, evolved as
//
//   d alpha_a/dt = -(alpha_a - alpha_min) / tau_a + max(-div v_a, 0) (alpha_max - alpha_a)
//   tau_a = h_a / (l c_a)
//
// with h_a Monaghan's smoothing length (monaghan_h of the support radius),
// c_a the sound speed and l the decay constant (viscosity.decay, 0.1 by
// default: the default of Price's codes, ndspmhd's and Phantom's
// avdecayconst). Away from compression alpha decays to alpha_min within a
// few tau (~ 10 h/c at l = 0.1: a few smoothing lengths of a sound wave's
// travel); a converging flow drives it towards alpha_max (the material's
// viscosity.alpha) at the rate -div v. The quadratic term scales with it,
// beta_a = beta alpha_a / alpha_max (Morris & Monaghan's beta = 2 alpha at
// the default beta = 2 alpha_max). A pair uses the mean of its two
// particles' coefficients (hydro.hpp), as with constant coefficients.
//
// -div v_a is the SPH continuity rate over rho: drho_a/dt / rho_a =
// (1/(Omega_a rho_a)) sum_b m_b v_ab . grad_a W_ab(h_a), which the force
// loop sums anyway (hydro.hpp), so the switch costs no neighbour pass.
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/physics/artificial_viscosity.hpp"

namespace rubble {

struct ViscositySwitchParams {
  bool enabled = false;
  Real alpha_min = Real(0.1);  // floor that alpha decays to
  Real decay = Real(0.1);      // l of tau = h/(l c)
};

// d alpha/dt of one particle: `compression` = max(-div v, 0) [1/s],
// h_monaghan [m], cs [m/s]; alpha_max the material's viscosity.alpha.
RUBBLE_HD_INLINE Real viscosity_switch_rate(Real alpha, Real compression, Real h_monaghan, Real cs, Real alpha_max,
                                            const ViscositySwitchParams& p) {
  const Real decay_rate = h_monaghan > Real(0) ? p.decay * cs / h_monaghan : Real(0);  // 1/tau
  const Real source = compression > Real(0) ? compression * (alpha_max - alpha) : Real(0);
  return -(alpha - p.alpha_min) * decay_rate + source;
}

// alpha0 + w d alpha/dt, never below 0 (the bounds alpha_min and alpha_max
// are restored at the end of the step, viscosity_switch_bound).
RUBBLE_HD_INLINE Real integrated_switch_alpha(Real alpha0, Real w, Real rate) {
  const Real a = alpha0 + w * rate;
  return a > Real(0) ? a : Real(0);
}

// alpha held to [alpha_min, alpha_max] (an explicit step can overshoot
// either bound of the exact solution, which stays between them).
RUBBLE_HD_INLINE Real viscosity_switch_bound(Real alpha, Real alpha_max, const ViscositySwitchParams& p) {
  return alpha < p.alpha_min ? p.alpha_min : (alpha > alpha_max ? alpha_max : alpha);
}

// The coefficients a particle with the switch brings to its pairs: alpha_a,
// and beta scaled with it (beta alpha_a / alpha_max).
RUBBLE_HD_INLINE ViscosityParams switched_viscosity(const ViscosityParams& material, Real alpha) {
  return ViscosityParams{alpha, material.alpha > Real(0) ? material.beta * alpha / material.alpha : material.beta};
}

}  // namespace rubble
