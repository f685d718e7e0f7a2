#pragma once
// The SPH equations of hydrodynamics as pair interactions (PHYSICS.md §1;
// Price 2012 eqs. 33-35 in rubble's notation). For particle a and neighbour b,
// with g_a = grad_a W(r_ab, h_a), g_b = grad_a W(r_ab, h_b), gbar = (g_a+g_b)/2:
//
//   dv_a/dt  = - sum_b m_b [ p_a/(Omega_a rho_a^2) g_a + p_b/(Omega_b rho_b^2) g_b + Pi_ab gbar ]
//   du_a/dt  =   p_a/(Omega_a rho_a^2) sum_b m_b v_ab . g_a + 1/2 sum_b m_b Pi_ab v_ab . gbar
//   drho_a/dt =  1/Omega_a sum_b m_b v_ab . g_a           (continuity density)
//
// With summation density Omega is the grad-h factor (Price 2012). With
// continuity density Omega = 1 and both g_a and g_b are replaced by the
// kernel-averaged gradient gbar (`symmetric`, Monaghan 1992 §3): with h
// varying strongly across a density jump (8x in 1-D Sod), the unaveraged
// form lets the first low-density particle at the jump decompress without
// bound, while the averaged form keeps the pair geometry the same for both
// particles. The pair force is antisymmetric in (a,b), so linear
// momentum is conserved to round-off, and du/dt is the time derivative of
// the thermal energy consistent with the work done by the pressure force.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/physics/artificial_conductivity.hpp"
#include "rubble/physics/artificial_viscosity.hpp"
#include "rubble/physics/kernels.hpp"

namespace rubble {

// Pressure-gradient force on a from b (per unit m_b), grad-h form.
template <int D>
RUBBLE_HD_INLINE Vec<D> pressure_acceleration(Real p_a_over_orho2, Real p_b_over_orho2,
                                              const Vec<D>& g_a, const Vec<D>& g_b) {
  return -(p_a_over_orho2 * g_a + p_b_over_orho2 * g_b);
}

// p / (Omega rho^2), the per-particle factor of the grad-h equations.
RUBBLE_HD_INLINE Real pressure_factor(Real p, Real omega, Real rho) { return p / (omega * rho * rho); }

// What one particle brings to a pair interaction.
template <int D>
struct HydroParticle {
  Vec<D> x, v;
  Real m, rho, p, u, h, omega, cs;
  ViscosityParams av;  // of the particle's material
  Real alpha_u;        // conductivity coefficient (0 = off)
};

template <int D>
struct HydroPairRates {
  Vec<D> dvdt;  // contribution to dv_a/dt
  Real dudt;    // contribution to du_a/dt
  Real drhodt;  // contribution to drho_a/dt (used with continuity density)
  Real mu;      // |mu_ab| for the Courant condition
};

// The complete hydrodynamic interaction of b on a; dx = x_a - x_b (minimum
// image). Both backends loop over neighbours and add these up.
// Material coefficients of a pair are the arithmetic means of the two
// particles' values, which keeps the pair force antisymmetric.
template <int D>
RUBBLE_HD_INLINE HydroPairRates<D> hydro_pair(KernelType kernel, const HydroParticle<D>& a,
                                              const HydroParticle<D>& b, const Vec<D>& dx,
                                              bool symmetric = false) {
  HydroPairRates<D> out{Vec<D>::zero(), Real(0), Real(0), Real(0)};
  const Real r2 = norm2(dx);
  const Real r = std::sqrt(r2);
  if (r <= Real(0)) return out;
  if (r >= a.h && r >= b.h) return out;

  Vec<D> g_a = kernel_grad<D>(kernel, dx, a.h);
  Vec<D> g_b = kernel_grad<D>(kernel, dx, b.h);
  const Vec<D> gbar = Real(0.5) * (g_a + g_b);
  if (symmetric) g_a = g_b = gbar;
  const Vec<D> dv = a.v - b.v;

  const Real fa = pressure_factor(a.p, a.omega, a.rho);
  const Real fb = pressure_factor(b.p, b.omega, b.rho);

  // Monaghan viscosity with pair-mean coefficients.
  const ViscosityParams av{Real(0.5) * (a.av.alpha + b.av.alpha), Real(0.5) * (a.av.beta + b.av.beta)};
  const Real hbar = monaghan_h<D>(kernel, Real(0.5) * (a.h + b.h));
  const Real mu = viscosity_mu(dot(dv, dx), r2, hbar);
  const Real rhobar = Real(0.5) * (a.rho + b.rho);
  const Real pi_ab = (mu < Real(0)) ? viscosity_pi(av, mu, Real(0.5) * (a.cs + b.cs), rhobar) : Real(0);

  out.dvdt = b.m * (pressure_acceleration<D>(fa, fb, g_a, g_b) - pi_ab * gbar);
  out.dudt = b.m * (fa * dot(dv, g_a) + Real(0.5) * pi_ab * dot(dv, gbar));
  out.drhodt = b.m * dot(dv, g_a) / a.omega;
  out.mu = -mu;

  const Real alpha_u = Real(0.5) * (a.alpha_u + b.alpha_u);
  if (alpha_u > Real(0)) {
    const Real F_ab = dot(gbar, dx) / r;  // gbar = xhat F_ab
    const Real vsig_u = conductivity_signal_speed(a.p, b.p, rhobar);
    out.dudt += b.m * conductivity_dudt(alpha_u, vsig_u, a.u, b.u, rhobar, F_ab);
  }
  return out;
}

}  // namespace rubble
