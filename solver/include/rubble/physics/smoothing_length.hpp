#pragma once
// Smoothing length and density (Springel & Hernquist 2002; Price 2012,
// J. Comput. Phys. 231:759, §2.2). rubble's h is the kernel support radius:
//   h_a = hfact (m_a / rho_a)^(1/D),
// so h/Δx = hfact on a lattice. With summation density, h_a and rho_a are
// solved together: rho_a = sum_b m_b W(r_ab, h_a) and the relation above,
// by Newton iteration on f(h) = rho_sum(h) - rho(h). The grad-h factor
//   Omega_a = 1 - (dh_a/drho_a) sum_b m_b dW(r_ab, h_a)/dh_a,
//   dh_a/drho_a = -h_a / (D rho_a),
// makes the equations of motion exactly conservative with variable h.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"

namespace rubble {

template <int D>
RUBBLE_HD_INLINE Real h_from_density(Real hfact, Real m, Real rho) {
  const Real vol = m / rho;
  if constexpr (D == 1) return hfact * vol;
  else if constexpr (D == 2) return hfact * std::sqrt(vol);
  else return hfact * std::cbrt(vol);
}

template <int D>
RUBBLE_HD_INLINE Real density_from_h(Real hfact, Real m, Real h) {
  const Real s = hfact / h;
  Real sD = s;
  for (int k = 1; k < D; ++k) sD *= s;
  return m * sD;
}

// Omega_a from the sum S = sum_b m_b dW(r_ab,h_a)/dh_a (self term included).
template <int D>
RUBBLE_HD_INLINE Real grad_h_omega(Real h, Real rho, Real dwdh_sum) {
  return Real(1) + h / (Real(D) * rho) * dwdh_sum;
}

// One Newton step for h: f(h) = rho_sum(h) - rho_h(h),
// f'(h) = sum m dW/dh + D rho_h / h. Returns the new h, limited to a
// factor-of-two change per step so a poor start cannot overshoot.
template <int D>
RUBBLE_HD_INLINE Real newton_h_step(Real h, Real rho_sum, Real dwdh_sum, Real hfact, Real m) {
  const Real rho_h = density_from_h<D>(hfact, m, h);
  const Real f = rho_sum - rho_h;
  const Real df = dwdh_sum + Real(D) * rho_h / h;
  Real h_new = (df != Real(0)) ? h - f / df : h;
  if (!(h_new > Real(0.5) * h)) h_new = Real(0.5) * h;  // also catches NaN
  if (h_new > Real(2) * h) h_new = Real(2) * h;
  return h_new;
}

}  // namespace rubble
