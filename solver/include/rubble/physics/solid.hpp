#pragma once
// The SPH equations of elastic solids as pair interactions (PHYSICS.md §1;
// Libersky & Petschek 1990; Benz & Asphaug 1994; Gray, Monaghan & Swift
// 2001). With the total stress sigma = -p I + S and gbar the kernel-averaged
// gradient grad_a W (continuity density, Omega = 1):
//
//   dv_a/dt   = sum_b m_b [ sigma_a/rho_a^2 + sigma_b/rho_b^2 + (R_a + R_b) f_ab^n - Pi_ab I ] . gbar
//   du_a/dt   = - sum_b m_b (sigma_a/rho_a^2) : (v_ab (x) gbar)
//               - 1/2 sum_b m_b [ (R_a + R_b) f_ab^n - Pi_ab I ] : (v_ab (x) gbar)
//   drho_a/dt =   sum_b m_b v_ab . gbar
// plus, for materials with artificial conductivity (a fluid in a scene that
// also holds a solid), hydro_pair's conductivity term in du_a/dt.
//
// The pair force is antisymmetric in (a,b) (momentum to round-off), and
// du/dt is exactly the work of the pair force, so kinetic + internal energy
// is conserved by the spatial discretisation. The shear part of du_a/dt,
// -(1/rho_a^2) sum_b m_b S_a : (v_ab (x) gbar) = (1/rho_a) S_a : L_a with
// L_a = sum_b (m_b/rho_a)(v_b - v_a) (x) gbar, is the SPH form of the shear
// heating (1/rho) S : eps_dot (jaumann_rate.hpp: shear_heating). With S = 0
// and no artificial stress this is hydro_pair's continuity-density form.
//
// Kernel-gradient correction (simulation.kernel_correction; issue #17
// item 4): every stress term uses the corrected gradient of its own
// particle, G_ab = K_a gbar with K_a = C_a^T (kernel_gradient_correction.hpp),
//   dv_a/dt   = sum_b m_b [ sigma_a/rho_a^2 K_a + sigma_b/rho_b^2 K_b ] gbar + (viscosity, R)
//   du_a/dt   = - sum_b m_b (sigma_a/rho_a^2) : (v_ab (x) K_a gbar) - (viscosity, R)/2
//   drho_a/dt =   sum_b m_b v_ab . K_a gbar            = -rho_a tr(L_a)
// with L_a = sum_b (m_b/rho_a) v_ba (x) K_a gbar the velocity gradient that
// evolves S (solid_gradient_particle), so du_a/dt = sigma_a : L_a / rho_a
// and drho/dt = -rho tr(L) use the very strain rate of Hooke's law. The
// momentum equation is the one whose work is that du/dt (sum over a of
// m_a v_a . dv_a/dt + m_a du_a/dt = 0 pair by pair), so energy and linear
// momentum stay conserved. Angular momentum too (Bonet & Lok 1999,
// Comput. Methods Appl. Mech. Engrg. 180:97): L_a is exact for a linear
// velocity field, so a rigid rotation (L = W skew) does no work against a
// symmetric sigma, and forces that do no work in every rigid rotation
// exert no net torque. (Only where C_a fell back to the identity is any of
// this approximate.) Viscosity and artificial stress keep the uncorrected,
// antisymmetric gbar.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"
#include "rubble/physics/artificial_conductivity.hpp"
#include "rubble/physics/artificial_stress.hpp"
#include "rubble/physics/artificial_viscosity.hpp"
#include "rubble/physics/kernels.hpp"

namespace rubble {

// What one particle brings to a solid pair interaction.
template <int D>
struct SolidParticle {
  Vec<D> x, v;
  Real m, rho, p, h, cs;
  Mat<D> S;           // deviatoric stress
  Mat<D> R;           // artificial stress tensor (artificial_stress_tensor; 0 = off)
  ViscosityParams av;  // of the particle's material
  Real dp;            // initial particle spacing of its material (artificial stress)
  Real as_exponent;   // n of the artificial stress (0 = off)
  Real u = 0;         // specific internal energy (artificial conductivity)
  Real alpha_u = 0;   // conductivity coefficient of its material (0 = off)
  // kernel-gradient correction K = C^T of the particle (nullptr = off):
  // its stress terms act along K gbar
  const Mat<D>* K = nullptr;
};

template <int D>
struct SolidPairRates {
  Vec<D> dvdt;
  Real dudt;
  Real drhodt;
  Real mu;  // |mu_ab| for the Courant condition
};

// The two divisions a particle brings to each of its solid pairs: 1/H of its
// kernel and 1/rho^2 of its stress term. The CPU driver computes them once
// per particle and evaluation and hands them to every pair
// (RhsContext::solid_inv); without them solid_pair computes them per pair,
// the same values bit for bit.
struct SolidInverses {
  Real inv_h, inv_rho2;
};

RUBBLE_HD_INLINE SolidInverses solid_inverses(Real h, Real rho) {
  return SolidInverses{Real(1) / h, Real(1) / (rho * rho)};
}

// sigma / rho^2 of a particle, from 1/rho^2.
template <int D>
RUBBLE_HD_INLINE Mat<D> stress_times_inv_rho2(Real p, const Mat<D>& S, Real inv_rho2) {
  Mat<D> s = S;
  for (int i = 0; i < D; ++i) s.m[i][i] -= p;
  return inv_rho2 * s;
}

// sigma / rho^2 of a particle.
template <int D>
RUBBLE_HD_INLINE Mat<D> stress_over_rho2(Real p, const Mat<D>& S, Real rho) {
  return stress_times_inv_rho2<D>(p, S, Real(1) / (rho * rho));
}

// What the two sides of a solid pair share, computed once: the CPU driver
// computes a pair of two particles of its own range once and gives both
// their rates (solid_pair_rates_a and _b), the same floating-point
// operations as the pair computed from each side (seen from b, dx, gbar
// and v_ab change sign, which is exact, and every sum of two terms
// commutes), so only the order of each particle's sum differs from the
// gather loop (tested bit for bit in test_solid_physics.cpp).
template <int D>
struct SolidPairTerms {
  bool active = false;  // inside a support, r > 0
  bool corrected = false;
  Vec<D> g, dv;        // gbar (symmetrised kernel gradient at dx), v_a - v_b
  Vec<D> ga, gb;       // the gradient each side's stress acts along (K gbar, or gbar)
  Vec<D> force;        // the momentum bracket: dv_a/dt = m_b force, dv_b/dt = -m_a force
  Mat<D> sa, sb, shared;
  Real mu = 0;         // the viscosity's mu_ab (<= 0 approaching)
  Real half_shared_work = 0;  // (shared : (v_ab (x) gbar)) / 2, corrected form
  Real cond = 0;       // conductivity du_a/dt without the mass m_b (0 when off)
};

// ia and ib: the particles' solid_inverses; dx = x_a - x_b (minimum image).
template <int D>
RUBBLE_HD_INLINE SolidPairTerms<D> solid_pair_terms(KernelType kernel, const SolidParticle<D>& a,
                                                    const SolidInverses& ia, const SolidParticle<D>& b,
                                                    const SolidInverses& ib, const Vec<D>& dx) {
  SolidPairTerms<D> t;
  const Real r2 = norm2(dx);
  const Real r = std::sqrt(r2);
  if (r <= Real(0)) return t;
  if (r >= a.h && r >= b.h) return t;
  t.active = true;

  t.g = Real(0.5) * (kernel_grad<D>(kernel_at_inv<D>(kernel, ia.inv_h), dx, r) +
                     kernel_grad<D>(kernel_at_inv<D>(kernel, ib.inv_h), dx, r));
  t.dv = a.v - b.v;

  const ViscosityParams av{Real(0.5) * (a.av.alpha + b.av.alpha), Real(0.5) * (a.av.beta + b.av.beta)};
  const Real hbar = Real(0.5) * (a.h + b.h);
  t.mu = viscosity_mu(dot(t.dv, dx), r2, monaghan_h<D>(kernel, hbar));
  const Real rhobar = Real(0.5) * (a.rho + b.rho);
  const Real pi_ab = (t.mu < Real(0)) ? viscosity_pi(av, t.mu, Real(0.5) * (a.cs + b.cs), rhobar) : Real(0);

  t.sa = stress_times_inv_rho2(a.p, a.S, ia.inv_rho2);
  t.sb = stress_times_inv_rho2(b.p, b.S, ib.inv_rho2);
  // pair terms that are shared equally (viscosity, artificial stress)
  t.shared = Mat<D>::zero();
  for (int i = 0; i < D; ++i) t.shared.m[i][i] = -pi_ab;
  const Real n = Real(0.5) * (a.as_exponent + b.as_exponent);
  // two particles without artificial stress (R = 0, e.g. the clumping form
  // on an ordered lattice) skip the factor's two kernel evaluations
  if (n > Real(0) && !(is_zero(a.R) && is_zero(b.R))) {
    const Real dp = Real(0.5) * (a.dp + b.dp);
    const Real fn = artificial_stress_factor(kernel_w<D>(kernel, r, hbar), kernel_w<D>(kernel, dp, hbar), n);
    t.shared += fn * (a.R + b.R);
  }

  t.corrected = a.K || b.K;
  if (t.corrected) {  // kernel-gradient correction: each stress along its own K gbar
    t.ga = a.K ? (*a.K) * t.g : t.g;
    t.gb = b.K ? (*b.K) * t.g : t.g;
    t.force = t.sa * t.ga + t.sb * t.gb + t.shared * t.g;
    t.half_shared_work = Real(0.5) * double_dot(t.shared, Mat<D>::outer(t.dv, t.g));
  } else {
    t.ga = t.gb = t.g;
    t.force = (t.sa + t.sb + t.shared) * t.g;
  }

  // Artificial conductivity (Price 2008), as in hydro_pair: the fluid of a
  // scene that also holds a solid keeps it (issue #17 item 6); pair-mean
  // coefficient, so it acts at half strength across a fluid-solid contact.
  const Real alpha_u = Real(0.5) * (a.alpha_u + b.alpha_u);
  if (alpha_u > Real(0)) {
    const Real F_ab = dot(t.g, dx) / r;  // g = xhat F_ab
    const Real vsig_u = conductivity_signal_speed(a.p, b.p, rhobar);
    t.cond = conductivity_dudt(alpha_u, vsig_u, a.u, b.u, rhobar, F_ab);
  }
  return t;
}

// The rates of a from the pair (b's mass m_b).
template <int D>
RUBBLE_HD_INLINE SolidPairRates<D> solid_pair_rates_a(const SolidPairTerms<D>& t, Real m_b) {
  SolidPairRates<D> out{Vec<D>::zero(), Real(0), Real(0), Real(0)};
  if (!t.active) return out;
  out.dvdt = m_b * t.force;
  if (t.corrected) {
    out.dudt = -m_b * (double_dot(t.sa, Mat<D>::outer(t.dv, t.ga)) + t.half_shared_work);
  } else {
    // -(sigma_a/rho_a^2 + shared/2) : (v_ab (x) g)
    const Mat<D> work = t.sa + Real(0.5) * t.shared;
    out.dudt = -m_b * double_dot(work, Mat<D>::outer(t.dv, t.g));
  }
  out.drhodt = m_b * dot(t.dv, t.ga);
  out.mu = -t.mu;
  if (t.cond != Real(0)) out.dudt += m_b * t.cond;
  return out;
}

// The rates of b from the same pair (a's mass m_a): the pair seen from b.
template <int D>
RUBBLE_HD_INLINE SolidPairRates<D> solid_pair_rates_b(const SolidPairTerms<D>& t, Real m_a) {
  SolidPairRates<D> out{Vec<D>::zero(), Real(0), Real(0), Real(0)};
  if (!t.active) return out;
  out.dvdt = m_a * (-t.force);
  if (t.corrected) {
    out.dudt = -m_a * (double_dot(t.sb, Mat<D>::outer(t.dv, t.gb)) + t.half_shared_work);
  } else {
    const Mat<D> work = t.sb + Real(0.5) * t.shared;
    out.dudt = -m_a * double_dot(work, Mat<D>::outer(t.dv, t.g));
  }
  out.drhodt = m_a * dot(t.dv, t.gb);
  out.mu = -t.mu;
  if (t.cond != Real(0)) out.dudt += m_a * (-t.cond);
  return out;
}

// The complete solid interaction of b on a; dx = x_a - x_b (minimum image),
// ia and ib the particles' solid_inverses.
template <int D>
RUBBLE_HD_INLINE SolidPairRates<D> solid_pair(KernelType kernel, const SolidParticle<D>& a, const SolidInverses& ia,
                                              const SolidParticle<D>& b, const SolidInverses& ib,
                                              const Vec<D>& dx) {
  return solid_pair_rates_a<D>(solid_pair_terms<D>(kernel, a, ia, b, ib, dx), b.m);
}

// The same, computing both particles' inverses here (tests; one pair).
template <int D>
RUBBLE_HD_INLINE SolidPairRates<D> solid_pair(KernelType kernel, const SolidParticle<D>& a,
                                              const SolidParticle<D>& b, const Vec<D>& dx) {
  return solid_pair<D>(kernel, a, solid_inverses(a.h, a.rho), b, solid_inverses(b.h, b.rho), dx);
}

// Longitudinal (P-wave) speed of an elastic solid, the signal speed of the
// Courant condition: c_l^2 = c^2 + 4 mu / (3 rho), c the bulk sound speed.
RUBBLE_HD_INLINE Real elastic_signal_speed(Real cs, Real shear_modulus, Real rho) {
  return std::sqrt(cs * cs + Real(4) * shear_modulus / (Real(3) * rho));
}

// One neighbour's contribution to the velocity gradient of a:
// L_a += (m_b/rho) (v_b - v_a) (x) grad_a W_ab (PHYSICS.md §1), rho = rho_b
// (the volume V_b = m_b/rho_b) without correction. With the kernel-gradient
// correction rho = rho_a, the weight of the energy and continuity equations
// above, and the sum is multiplied from the right by C_a (computed with the
// same weight, so L_a is exact for linear fields and -rho_a tr(L_a) is the
// corrected continuity rate).
template <int D>
RUBBLE_HD_INLINE Mat<D> velocity_gradient_pair_term(Real m_b, Real rho, const Vec<D>& v_ba, const Vec<D>& grad_a_w) {
  return (m_b / rho) * Mat<D>::outer(v_ba, grad_a_w);
}

}  // namespace rubble
