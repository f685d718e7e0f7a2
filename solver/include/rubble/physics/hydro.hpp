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
//
// The geometric form (simulation.pressure_force = "geometric"; continuity
// density only): the pressure enters as (p_a + p_b)/(rho_a rho_b) and the
// density and energy equations weigh the neighbours by their volume m_b/rho_b,
//
//   dv_a/dt  = - sum_b m_b [ (p_a + p_b)/(rho_a rho_b) + Pi_ab ] gbar
//   du_a/dt  =   p_a/rho_a sum_b (m_b/rho_b) v_ab . gbar + 1/2 sum_b m_b Pi_ab v_ab . gbar
//   drho_a/dt =  rho_a sum_b (m_b/rho_b) v_ab . gbar
//
// (the "geometric density average force" of Wadsley, Keller & Quinn 2017,
// MNRAS 471:2357, compared at planetary material boundaries by Ruiz-Bonilla
// et al. 2022, MNRAS 512:4660; the volume-weighted continuity equation of
// Ott & Schnetter 2003 for multiphase flow). Where rho_a = rho_b it is the
// standard form; across a density jump under uniform pressure the standard
// form's sum_b m_b/rho_b^2 g does not vanish and pushes the light side away,
// while sum_b (m_b/rho_b) g ~ grad 1 = 0 does. Still antisymmetric (momentum
// to round-off), and du/dt is again p/rho^2 times the drho/dt of the same
// sum, so the pressure work is booked exactly as before.
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
  bool geometric;  // the geometric pressure force (both sides of a pair alike)
};

// `neighbour`: the side of b, whose 1/Omega no pair term reads.
// `geometric`: the geometric pressure force (continuity density; above).
template <int D>
RUBBLE_HD_INLINE HydroSide<D> hydro_side(KernelType kernel, const HydroParticle<D>& q, bool neighbour = false,
                                         bool geometric = false) {
  return HydroSide<D>{q, kernel_at<D>(kernel, q.h), pressure_factor(q.p, q.omega, q.rho),
                      neighbour ? Real(0) : Real(1) / q.omega, geometric};
}

// What a pair's two sides share: the kernel gradients, the velocity
// difference and the viscous and conductive factors. dx = x_a - x_b
// (minimum image); `active` is false outside both supports (and for r = 0),
// where the pair adds nothing.
template <int D>
struct HydroPairTerms {
  bool active;
  Vec<D> g_a, g_b, gbar;  // grad_a W(r, h_a), grad_a W(r, h_b), their mean (all gbar when `symmetric`)
  Vec<D> dv;              // v_a - v_b
  Real mu, pi_ab;         // Monaghan's mu_ab and Pi_ab
  Real alpha_u, vsig_u, rhobar, F_ab;  // conductivity (alpha_u = 0: off)
};

template <int D>
RUBBLE_HD_INLINE HydroPairTerms<D> hydro_pair_terms(const HydroSide<D>& sa, const HydroSide<D>& sb, const Vec<D>& dx,
                                                    bool symmetric = false) {
  const HydroParticle<D>& a = sa.q;
  const HydroParticle<D>& b = sb.q;
  HydroPairTerms<D> t{};
  t.active = false;
  const Real r2 = norm2(dx);
  const Real h_max = a.h > b.h ? a.h : b.h;
  if (r2 >= h_max * h_max) return t;  // most entries beyond the support stop here, before the root
  const Real r = std::sqrt(r2);
  if (r <= Real(0)) return t;
  if (r >= a.h && r >= b.h) return t;
  t.active = true;
  const Real inv_r = Real(1) / r;

  t.g_a = kernel_grad<D>(sa.K, dx, r, inv_r);
  t.g_b = kernel_grad<D>(sb.K, dx, r, inv_r);
  t.gbar = Real(0.5) * (t.g_a + t.g_b);
  if (symmetric) t.g_a = t.g_b = t.gbar;
  t.dv = a.v - b.v;

  // Monaghan viscosity with pair-mean coefficients.
  const ViscosityParams av{Real(0.5) * (a.av.alpha + b.av.alpha), Real(0.5) * (a.av.beta + b.av.beta)};
  const Real hbar = monaghan_h<D>(sa.K.k, Real(0.5) * (a.h + b.h));
  t.mu = viscosity_mu(dot(t.dv, dx), r2, hbar);
  t.rhobar = Real(0.5) * (a.rho + b.rho);
  t.pi_ab = (t.mu < Real(0)) ? viscosity_pi(av, t.mu, Real(0.5) * (a.cs + b.cs), t.rhobar) : Real(0);

  t.alpha_u = Real(0.5) * (a.alpha_u + b.alpha_u);
  if (t.alpha_u > Real(0)) {
    t.F_ab = dot(t.gbar, dx) * inv_r;  // gbar = xhat F_ab
    t.vsig_u = conductivity_signal_speed(a.p, b.p, t.rhobar);
  }
  return t;
}

// Particle a's rates from the pair's terms (a's side of the equations above).
template <int D>
RUBBLE_HD_INLINE HydroPairRates<D> hydro_pair_rates_a(const HydroPairTerms<D>& t, const HydroSide<D>& sa,
                                                      const HydroSide<D>& sb) {
  HydroPairRates<D> out{Vec<D>::zero(), Real(0), Real(0), Real(0)};
  if (!t.active) return out;
  const Real dv_ga = dot(t.dv, t.g_a);
  if (sa.geometric) {  // continuity density: g_a = g_b = gbar, Omega = 1
    const Real inv_rho_ab = Real(1) / (sa.q.rho * sb.q.rho);
    out.dvdt = -sb.q.m * ((sa.q.p + sb.q.p) * inv_rho_ab + t.pi_ab) * t.gbar;
    out.dudt = sb.q.m * (sa.q.p * inv_rho_ab * dv_ga + Real(0.5) * t.pi_ab * dot(t.dv, t.gbar));
    out.drhodt = sa.q.rho * (sb.q.m / sb.q.rho) * dv_ga;
  } else {
    out.dvdt = sb.q.m * (pressure_acceleration<D>(sa.f, sb.f, t.g_a, t.g_b) - t.pi_ab * t.gbar);
    out.dudt = sb.q.m * (sa.f * dv_ga + Real(0.5) * t.pi_ab * dot(t.dv, t.gbar));
    out.drhodt = sb.q.m * dv_ga * sa.inv_omega;
  }
  out.mu = -t.mu;
  if (t.alpha_u > Real(0))
    out.dudt += sb.q.m * conductivity_dudt(t.alpha_u, t.vsig_u, sa.q.u, sb.q.u, t.rhobar, t.F_ab);
  return out;
}

// The same pair's terms seen from b (dx -> -dx): every gradient and dv
// change sign and g_a, g_b swap; the rest is symmetric. Negation is exact,
// so these are bit for bit the terms hydro_pair_terms gives for (b, a).
template <int D>
RUBBLE_HD_INLINE HydroPairTerms<D> hydro_pair_terms_seen_from_b(const HydroPairTerms<D>& t) {
  HydroPairTerms<D> m = t;
  m.g_a = -t.g_b;
  m.g_b = -t.g_a;
  m.gbar = -t.gbar;
  m.dv = -t.dv;
  return m;
}

// Particle b's rates from the same terms, so that a loop computing each
// pair once gets the numbers of one that computes it from both sides. b's
// side needs its 1/Omega (continuity density).
template <int D>
RUBBLE_HD_INLINE HydroPairRates<D> hydro_pair_rates_b(const HydroPairTerms<D>& t, const HydroSide<D>& sa,
                                                      const HydroSide<D>& sb) {
  return hydro_pair_rates_a<D>(hydro_pair_terms_seen_from_b<D>(t), sb, sa);
}

// The complete hydrodynamic interaction of b on a; dx = x_a - x_b (minimum
// image). Both backends loop over neighbours and add these up.
// Material coefficients of a pair are the arithmetic means of the two
// particles' values, which keeps the pair force antisymmetric.
template <int D>
RUBBLE_HD_INLINE HydroPairRates<D> hydro_pair(const HydroSide<D>& sa, const HydroSide<D>& sb, const Vec<D>& dx,
                                              bool symmetric = false) {
  return hydro_pair_rates_a<D>(hydro_pair_terms<D>(sa, sb, dx, symmetric), sa, sb);
}

// The same for two particles not prepared beforehand (tests, single pairs).
template <int D>
RUBBLE_HD_INLINE HydroPairRates<D> hydro_pair(KernelType kernel, const HydroParticle<D>& a,
                                              const HydroParticle<D>& b, const Vec<D>& dx,
                                              bool symmetric = false, bool geometric = false) {
  return hydro_pair<D>(hydro_side<D>(kernel, a, false, geometric), hydro_side<D>(kernel, b, true, geometric), dx,
                       symmetric);
}

}  // namespace rubble
