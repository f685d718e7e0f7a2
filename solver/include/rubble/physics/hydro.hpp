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

// One particle of a pair with the factors its side of every pair term uses
// computed once: its kernel's 1/h and sigma/h^n, p/(Omega rho^2) and
// 1/Omega. A neighbour loop prepares particle a once for all its neighbours
// (issue #14: the per-pair divisions were most of the force loop's time).
template <int D>
struct HydroSide {
  HydroParticle<D> q;
  KernelAt<D> K;
  Real f;          // pressure_factor(p, omega, rho)
  Real inv_omega;  // 1/Omega, read only on a's side (0 on a neighbour's)
};

// `neighbour`: the side of b, whose 1/Omega no pair term reads.
template <int D>
RUBBLE_HD_INLINE HydroSide<D> hydro_side(KernelType kernel, const HydroParticle<D>& q, bool neighbour = false) {
  return HydroSide<D>{q, kernel_at<D>(kernel, q.h), pressure_factor(q.p, q.omega, q.rho),
                      neighbour ? Real(0) : Real(1) / q.omega};
}

// The complete hydrodynamic interaction of b on a; dx = x_a - x_b (minimum
// image). Both backends loop over neighbours and add these up.
// Material coefficients of a pair are the arithmetic means of the two
// particles' values, which keeps the pair force antisymmetric.
template <int D>
RUBBLE_HD_INLINE HydroPairRates<D> hydro_pair(const HydroSide<D>& sa, const HydroSide<D>& sb, const Vec<D>& dx,
                                              bool symmetric = false) {
  const HydroParticle<D>& a = sa.q;
  const HydroParticle<D>& b = sb.q;
  HydroPairRates<D> out{Vec<D>::zero(), Real(0), Real(0), Real(0)};
  const Real r2 = norm2(dx);
  const Real h_max = a.h > b.h ? a.h : b.h;
  if (r2 >= h_max * h_max) return out;  // most entries beyond the support stop here, before the root
  const Real r = std::sqrt(r2);
  if (r <= Real(0)) return out;
  if (r >= a.h && r >= b.h) return out;
  const Real inv_r = Real(1) / r;

  Vec<D> g_a = kernel_grad<D>(sa.K, dx, r, inv_r);
  Vec<D> g_b = kernel_grad<D>(sb.K, dx, r, inv_r);
  const Vec<D> gbar = Real(0.5) * (g_a + g_b);
  if (symmetric) g_a = g_b = gbar;
  const Vec<D> dv = a.v - b.v;

  // Monaghan viscosity with pair-mean coefficients.
  const ViscosityParams av{Real(0.5) * (a.av.alpha + b.av.alpha), Real(0.5) * (a.av.beta + b.av.beta)};
  const Real hbar = monaghan_h<D>(sa.K.k, Real(0.5) * (a.h + b.h));
  const Real mu = viscosity_mu(dot(dv, dx), r2, hbar);
  const Real rhobar = Real(0.5) * (a.rho + b.rho);
  const Real pi_ab = (mu < Real(0)) ? viscosity_pi(av, mu, Real(0.5) * (a.cs + b.cs), rhobar) : Real(0);

  const Real dv_ga = dot(dv, g_a);
  out.dvdt = b.m * (pressure_acceleration<D>(sa.f, sb.f, g_a, g_b) - pi_ab * gbar);
  out.dudt = b.m * (sa.f * dv_ga + Real(0.5) * pi_ab * dot(dv, gbar));
  out.drhodt = b.m * dv_ga * sa.inv_omega;
  out.mu = -mu;

  const Real alpha_u = Real(0.5) * (a.alpha_u + b.alpha_u);
  if (alpha_u > Real(0)) {
    const Real F_ab = dot(gbar, dx) * inv_r;  // gbar = xhat F_ab
    const Real vsig_u = conductivity_signal_speed(a.p, b.p, rhobar);
    out.dudt += b.m * conductivity_dudt(alpha_u, vsig_u, a.u, b.u, rhobar, F_ab);
  }
  return out;
}

// The same for two particles not prepared beforehand (tests, single pairs).
template <int D>
RUBBLE_HD_INLINE HydroPairRates<D> hydro_pair(KernelType kernel, const HydroParticle<D>& a,
                                              const HydroParticle<D>& b, const Vec<D>& dx,
                                              bool symmetric = false) {
  return hydro_pair<D>(hydro_side<D>(kernel, a), hydro_side<D>(kernel, b, true), dx, symmetric);
}

}  // namespace rubble
