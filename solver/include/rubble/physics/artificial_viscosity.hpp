#pragma once
// Monaghan (1992, ARA&A 30:543) artificial viscosity.
//   mu_ab = hbar (v_ab . x_ab) / (r_ab^2 + eps hbar^2)   for v_ab . x_ab < 0, else 0
//   Pi_ab = (-alpha cbar mu_ab + beta mu_ab^2) / rhobar
// with x_ab = x_a - x_b, v_ab = v_a - v_b, eps = 0.01 and bars denoting pair
// means. hbar is Monaghan's smoothing length; rubble's h is the kernel support
// radius H, and for the cubic spline H = 2 h_Monaghan, so hbar = (H_a + H_b)/4;
// for the Wendland kernels hbar is the cubic spline's at the same kernel
// standard deviation (kernels.hpp, monaghan_h_factor).
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/physics/kernels.hpp"

namespace rubble {

struct ViscosityParams {
  Real alpha;
  Real beta;
};

// Monaghan's smoothing length from rubble's support radius H.
template <int D>
RUBBLE_HD_INLINE Real monaghan_h(KernelType k, Real H) { return monaghan_h_factor<D>(k) * H; }

// mu_ab (<= 0): the approach speed measured in units of the pair's smoothing length.
RUBBLE_HD_INLINE Real viscosity_mu(Real vx_dot, Real r2, Real hbar) {
  if (vx_dot >= Real(0)) return Real(0);
  return hbar * vx_dot / (r2 + Real(0.01) * hbar * hbar);
}

// Pi_ab for a pair; enters the momentum equation as -m_b Pi_ab grad W.
RUBBLE_HD_INLINE Real viscosity_pi(const ViscosityParams& av, Real mu, Real cbar, Real rhobar) {
  return (-av.alpha * cbar * mu + av.beta * mu * mu) / rhobar;
}

}  // namespace rubble
